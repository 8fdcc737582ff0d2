// Bad configuration of the model, generated from the schema: for every key of config/gear_pair.yaml,
// load.yaml and run.yaml the cases of bad_input.hpp (missing, wrong type, NaN, +-inf, a sign or
// zero where meaningless, just out of range, a typo), each refused with one message that names the
// key, the value and the schema's range; then the sets that are inconsistent between keys.
#include <gtest/gtest.h>

#include <algorithm>

#include "bad_input.hpp"
#include "gear_dynamics/config.hpp"

namespace gd = gear_dynamics;
namespace bi = bad_input;

namespace {

const YAML::Node& defaults() {
  static const YAML::Node root = [] {
    const std::string dir = GEAR_DYNAMICS_CONFIG_DIR;
    return gd::read_yaml_files({dir + "/gear_pair.yaml", dir + "/load.yaml", dir + "/run.yaml"});
  }();
  return root;
}

std::string error_of(const YAML::Node& root) {
  return bi::error_of<gd::ConfigError>([](const YAML::Node& r) { gd::parse_config(r); }, root);
}

std::vector<bi::Case> schema_cases() {
  std::vector<bi::Case> all;
  for (const gd::KeySpec& k : gd::config_schema()) {
    const bi::Range range{k.lo, k.hi, k.open_lo, k.open_hi};
    const auto cases = bi::key_cases(k.section, k.key, defaults()[k.section][k.key], range,
                                     k.kind == gd::KeyKind::Integer);
    all.insert(all.end(), cases.begin(), cases.end());
  }
  return all;
}

}  // namespace

TEST(FaultsSchema, ShippedFilesHoldExactlyTheSchemaKeys) {
  std::vector<std::string> shipped, schema;
  for (const char* section : {"gear_pair", "load", "run"})
    for (const auto& kv : defaults()[section]) shipped.push_back(std::string(section) + "." + kv.first.as<std::string>());
  for (const gd::KeySpec& k : gd::config_schema()) schema.push_back(k.section + "." + k.key);
  std::sort(shipped.begin(), shipped.end());
  std::sort(schema.begin(), schema.end());
  EXPECT_EQ(shipped, schema);
  EXPECT_EQ(error_of(defaults()), "");
}

class FaultsModelConfig : public testing::TestWithParam<bi::Case> {};

TEST_P(FaultsModelConfig, RefusedNamingKeyValueAndRange) {
  const bi::Case& c = GetParam();
  YAML::Node root = YAML::Clone(defaults());
  c.apply(root);
  EXPECT_EQ(bi::judge(c, error_of(root)), "");
}

INSTANTIATE_TEST_SUITE_P(Generated, FaultsModelConfig, testing::ValuesIn(schema_cases()),
                         [](const testing::TestParamInfo<bi::Case>& info) { return info.param.name(); });

// Sets of values each in range that do not fit together; the message names the key and value.
struct Inconsistent {
  std::string name, overlay;
  std::vector<std::string> expected;  // substrings of the one error line
};

void PrintTo(const Inconsistent& c, std::ostream* os) { *os << c.overlay; }

class FaultsModelConsistency : public testing::TestWithParam<Inconsistent> {};

TEST_P(FaultsModelConsistency, RefusedNamingKeyAndValue) {
  YAML::Node root = YAML::Clone(defaults());
  gd::merge_yaml(root, YAML::Load(GetParam().overlay));
  const std::string e = error_of(root);
  const auto lines = bi::error_lines(e);
  ASSERT_EQ(lines.size(), 1u) << e;
  for (const std::string& s : GetParam().expected) EXPECT_NE(lines[0].find(s), std::string::npos) << lines[0] << "\nmissing: " << s;
}

INSTANTIATE_TEST_SUITE_P(
    Generated, FaultsModelConsistency,
    testing::Values(
        Inconsistent{"inconsistent__contact_ratio_below_1", "{gear_pair: {addendum_coefficient: 0.3}}",
                     {"contact ratio 0.5", "addendum_coefficient = 0.3", "outside (1, 2)"}},
        Inconsistent{"inconsistent__contact_ratio_above_2", "{gear_pair: {addendum_coefficient: 2.0, pinion_teeth: 60, gear_teeth: 240}}",
                     {"contact ratio", "addendum_coefficient = 2", "outside (1, 2)"}},
        Inconsistent{"inconsistent__time_step_too_large_for_stiffest_contact", "{run: {time_step: 5.0e-5, duration: 0.4}}",
                     {"run.time_step = 5e-05 s is too large for the stiffest contact", "omega_max h < 2.828"}},
        Inconsistent{"inconsistent__time_step_spans_stiffness_interval", "{gear_pair: {pinion_speed: 10000}, run: {time_step: 2.0e-5}}",
                     {"run.time_step = 2e-05 s spans a whole stiffness interval", "allowed time_step <"}},
        Inconsistent{"inconsistent__duration_not_whole_steps", "{run: {duration: 0.4000005}}",
                     {"run.duration = 0.4000005 s is not a whole number of time steps"}},
        Inconsistent{"inconsistent__window_longer_than_duration", "{run: {window: 0.5}}",
                     {"run.window = 0.5 s is out of range", "(0, duration = 0.4] s"}},
        Inconsistent{"inconsistent__snapshot_off_grid", "{run: {snapshot_times: [0.3, 0.3000005]}}",
                     {"run.snapshot_times[1] = 0.3000005 s is not a grid time", "[0, duration = 0.4]"}},
        Inconsistent{"inconsistent__snapshot_after_duration", "{run: {snapshot_times: [0.3, 0.5]}}",
                     {"run.snapshot_times[1] = 0.5 s is not a grid time", "[0, duration = 0.4]"}},
        Inconsistent{"inconsistent__snapshots_not_increasing", "{run: {snapshot_times: [0.35, 0.3]}}",
                     {"run.snapshot_times[1] = 0.3 s is not after the previous one"}},
        Inconsistent{"inconsistent__mesh_phase_beyond_period", "{gear_pair: {mesh_phase: 0.4}}",
                     {"gear_pair.mesh_phase = 0.4 is out of range", "[0, 0.314159"}},
        Inconsistent{"inconsistent__fine_tolerance_above_tolerance", "{run: {steady_state_tolerance_fine: 0.2}}",
                     {"run.steady_state_tolerance_fine = 0.2 is above run.steady_state_tolerance = 0.1"}}),
    [](const testing::TestParamInfo<Inconsistent>& info) { return info.param.name; });
