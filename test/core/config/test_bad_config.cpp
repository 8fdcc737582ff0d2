// Bad configuration, generated key by key for every section from its declaration (section.hpp):
// gear_pair, load, run, monte_carlo, simulator, analysis and gear_aggregator's own keys. Each case
// of bad_input.hpp (missing, wrong type, NaN, +-inf, a sign or zero where meaningless, just out of
// range, a typo) must be refused with one message that names the key, the value and the range.
// Then the sets that are inconsistent between keys.
#include <gtest/gtest.h>

#include <algorithm>

#include "support/bad_input.hpp"
#include "gear_dynamics/config/aggregator_settings.hpp"
#include "gear_dynamics/config/analysis_settings.hpp"
#include "gear_dynamics/config/batch_settings.hpp"
#include "gear_dynamics/config/config.hpp"
#include "gear_dynamics/config/parameters.hpp"
#include "gear_dynamics/config/simulator_settings.hpp"

namespace gd = gear_dynamics;
namespace bi = bad_input;

namespace {

YAML::Node load(const std::vector<std::string>& files) {
  std::vector<std::string> paths;
  for (const std::string& f : files) paths.push_back(std::string(GEAR_DYNAMICS_CONFIG_DIR) + "/" + f);
  return gd::read_yaml_files(paths);
}

const std::vector<std::string> kModelFiles = {"gear_pair.yaml", "load.yaml", "run.yaml"};

// A validator, the files it reads (in the layout of the launch files, plus `overlay`), the
// sections it owns and where they lie in the root ("" = the root itself).
struct Validator {
  std::string name;
  std::vector<std::string> files;
  std::string overlay;
  std::vector<std::pair<std::string, std::string>> sections;  // (declared section, location)
  std::function<void(const YAML::Node&)> parse;

  YAML::Node defaults() const {
    YAML::Node root = load(files);
    if (!overlay.empty()) gd::merge_yaml(root, YAML::Load(overlay));
    return root;
  }
  std::string error_of(const YAML::Node& root) const { return bi::error_of<gd::ConfigError>(parse, root); }
};

const std::vector<Validator>& validators() {
  static const std::vector<Validator> all = [] {
    std::vector<Validator> v;
    const auto with_model = [](std::string file) {
      std::vector<std::string> f = kModelFiles;
      f.push_back(std::move(file));
      return f;
    };
    v.push_back({"model", kModelFiles, "", {{"gear_pair", "gear_pair"}, {"load", "load"}, {"run", "run"}},
                 [](const YAML::Node& r) { gd::parse_config(r); }});
    v.push_back({"monte_carlo", with_model("monte_carlo.yaml"), "", {{"monte_carlo", "monte_carlo"}},
                 [](const YAML::Node& r) { gd::parse_batch_settings(r["monte_carlo"], gd::parse_config(r)); }});
    v.push_back({"simulator", with_model("simulator.yaml"), "", {{"simulator", "simulator"}}, [](const YAML::Node& r) {
                   gd::parse_simulator_settings(r, gd::parse_config(r).run.time_step);
                 }});
    v.push_back({"analysis", {"aggregator.yaml"}, "", {{"analysis", "analysis"}},
                 [](const YAML::Node& r) { gd::parse_analysis_settings(r); }});
    // The aggregator's private namespace: its own keys at the top, with the section analysis.
    v.push_back({"aggregator", {"aggregator.yaml"}, "{folders: [/tmp/batch]}", {{"aggregator", ""}},
                 [](const YAML::Node& r) { gd::parse_aggregator_settings(r); }});
    return v;
  }();
  return all;
}

const Validator& validator(const std::string& name) {
  for (const Validator& v : validators())
    if (v.name == name) return v;
  throw std::logic_error("no validator " + name);
}

const gd::SectionSpec& declared(const std::string& name) {
  static const std::vector<gd::SectionSpec> all = gd::parameter_sections();
  for (const gd::SectionSpec& s : all)
    if (s.name == name) return s;
  throw std::logic_error("no section " + name);
}

struct Param {
  std::string validator;
  bi::Case c;
};

void PrintTo(const Param& p, std::ostream* os) { bi::PrintTo(p.c, os); }

std::vector<Param> generated_cases() {
  std::vector<Param> all;
  for (const Validator& v : validators()) {
    const YAML::Node root = v.defaults();
    for (const auto& [name, location] : v.sections) {
      const YAML::Node map = location.empty() ? root : root[location];
      for (const gd::KeySpec& k : declared(name).keys) {
        const YAML::Node good = map[k.name] ? map[k.name] : k.default_value;
        for (const bi::Case& c : bi::key_cases(declared(name), location, k, good)) all.push_back({v.name, c});
      }
    }
  }
  return all;
}

}  // namespace

TEST(FaultsSchema, EverySectionHasAValidator) {
  std::vector<std::string> covered, declared_names;
  for (const Validator& v : validators())
    for (const auto& s : v.sections) covered.push_back(s.first);
  for (const gd::SectionSpec& s : gd::parameter_sections()) declared_names.push_back(s.name);
  std::sort(covered.begin(), covered.end());
  std::sort(declared_names.begin(), declared_names.end());
  EXPECT_EQ(covered, declared_names);
}

TEST(FaultsSchema, ShippedFilesAreAccepted) {
  for (const Validator& v : validators()) EXPECT_EQ(v.error_of(v.defaults()), "") << v.name;
}

class FaultsConfig : public testing::TestWithParam<Param> {};

TEST_P(FaultsConfig, RefusedNamingKeyValueAndRange) {
  const Validator& v = validator(GetParam().validator);
  const bi::Case& c = GetParam().c;
  YAML::Node root = v.defaults();
  c.apply(root);
  EXPECT_EQ(bi::judge(c, v.error_of(root)), "");
}

INSTANTIATE_TEST_SUITE_P(Generated, FaultsConfig, testing::ValuesIn(generated_cases()),
                         [](const testing::TestParamInfo<Param>& info) { return info.param.c.name(); });

// Sets of values, each in range, that do not fit together; the one message names key and value.
struct Inconsistent {
  std::string name, validator, overlay;
  std::vector<std::string> expected;  // substrings of the one error line
};

void PrintTo(const Inconsistent& c, std::ostream* os) { *os << c.overlay; }

class FaultsConsistency : public testing::TestWithParam<Inconsistent> {};

TEST_P(FaultsConsistency, RefusedNamingKeyAndValue) {
  const Validator& v = validator(GetParam().validator);
  YAML::Node root = v.defaults();
  gd::merge_yaml(root, YAML::Load(GetParam().overlay));
  const std::string e = v.error_of(root);
  const auto lines = bi::error_lines(e);
  ASSERT_EQ(lines.size(), 1u) << e;
  for (const std::string& s : GetParam().expected)
    EXPECT_NE(lines[0].find(s), std::string::npos) << lines[0] << "\nmissing: " << s;
}

INSTANTIATE_TEST_SUITE_P(
    Generated, FaultsConsistency,
    testing::Values(
        Inconsistent{"inconsistent__contact_ratio_below_1", "model", "{gear_pair: {addendum_coefficient: 0.3}}",
                     {"contact ratio 0.5", "addendum_coefficient = 0.3", "outside (1, 2)"}},
        Inconsistent{"inconsistent__contact_ratio_above_2", "model",
                     "{gear_pair: {addendum_coefficient: 2.0, pinion_teeth: 60, gear_teeth: 240}}",
                     {"contact ratio", "addendum_coefficient = 2", "outside (1, 2)"}},
        Inconsistent{"inconsistent__time_step_too_large_for_stiffest_contact", "model", "{run: {time_step: 5.0e-5}}",
                     {"run.time_step = 5e-05 s is too large for the stiffest contact", "omega_max h < 2.828"}},
        Inconsistent{"inconsistent__time_step_spans_stiffness_interval", "model",
                     "{gear_pair: {pinion_speed: 10000}, run: {time_step: 2.0e-5}}",
                     {"run.time_step = 2e-05 s spans a whole stiffness interval", "allowed time_step <"}},
        Inconsistent{"inconsistent__duration_not_whole_steps", "model", "{run: {duration: 0.4000005}}",
                     {"run.duration = 0.4000005 s is not a whole number of time steps"}},
        Inconsistent{"inconsistent__window_longer_than_duration", "model", "{run: {window: 0.5}}",
                     {"run.window = 0.5 s is out of range", "(0, duration = 0.4] s"}},
        Inconsistent{"inconsistent__snapshot_off_grid", "model", "{run: {snapshot_times: [0.3, 0.3000005]}}",
                     {"run.snapshot_times[1] = 0.3000005 s is not a grid time", "[0, duration = 0.4]"}},
        Inconsistent{"inconsistent__snapshot_after_duration", "model", "{run: {snapshot_times: [0.3, 0.5]}}",
                     {"run.snapshot_times[1] = 0.5 s is not a grid time", "[0, duration = 0.4]"}},
        Inconsistent{"inconsistent__snapshots_not_increasing", "model", "{run: {snapshot_times: [0.35, 0.3]}}",
                     {"run.snapshot_times[1] = 0.3 s is not after the previous one"}},
        Inconsistent{"inconsistent__mesh_phase_beyond_period", "model", "{gear_pair: {mesh_phase: 0.4}}",
                     {"gear_pair.mesh_phase = 0.4 is out of range", "[0, 0.314159"}},
        Inconsistent{"inconsistent__fine_tolerance_above_tolerance", "model", "{run: {steady_state_tolerance_fine: 0.2}}",
                     {"run.steady_state_tolerance_fine = 0.2 is above run.steady_state_tolerance = 0.1"}},
        Inconsistent{"inconsistent__empty_mu_list", "monte_carlo", "{monte_carlo: {mu: []}}",
                     {"monte_carlo.mu = []", "non-empty list", "[0, 0.2]"}},
        Inconsistent{"inconsistent__no_realizations", "monte_carlo", "{monte_carlo: {realizations: 0}}",
                     {"monte_carlo.realizations = 0", "[1, 1000000]"}},
        Inconsistent{"inconsistent__mu_repeated", "monte_carlo", "{monte_carlo: {mu: [0.04, 0.04]}}",
                     {"monte_carlo.mu = [0.04, 0.04] repeats 0.04"}},
        Inconsistent{"inconsistent__more_recorded_than_realizations", "monte_carlo",
                     "{monte_carlo: {realizations: 4, record_realizations: 5}}",
                     {"monte_carlo.record_realizations = 5", "[0, 4]"}},
        Inconsistent{"inconsistent__record_rate_off_grid", "monte_carlo", "{monte_carlo: {record_rate: 300000.0}}",
                     {"monte_carlo.record_rate = 300000 Hz does not fit the grid"}},
        Inconsistent{"inconsistent__shard_index_beyond_count", "monte_carlo", "{monte_carlo: {shard_index: 2, shard_count: 2}}",
                     {"monte_carlo.shard_index = 2", "[0, 1]"}},
        Inconsistent{"inconsistent__simulator_t_end_off_grid", "simulator", "{simulator: {t_end: 0.1000005}}",
                     {"simulator.t_end = 0.1000005 s is not a whole number of time steps"}},
        Inconsistent{"inconsistent__simulator_publish_rate_above_grid", "simulator",
                     "{run: {time_step: 1.0e-5}, simulator: {publish_rate: 2.0e5}}",
                     {"simulator.publish_rate = 200000 is out of range; allowed [1, 100000]", "at most 1/time_step"}},
        Inconsistent{"inconsistent__simulator_loop_forever", "simulator", "{simulator: {loop: true, t_end: 0}}",
                     {"simulator.loop = true needs simulator.t_end > 0"}},
        Inconsistent{"inconsistent__analysis_empty_interval", "analysis", "{analysis: {delta_interval: [5.5e-5, 4.0e-5]}}",
                     {"analysis.delta_interval = [5.5e-05, 4e-05] is empty"}},
        Inconsistent{"inconsistent__analysis_bins_width_zero", "analysis", "{analysis: {delta_bins: [3.0e-5, 6.0e-5, 0.0]}}",
                     {"analysis.delta_bins"}}),
    [](const testing::TestParamInfo<Inconsistent>& info) { return info.param.name; });
