// The loader: the shipped files load; each kind of bad input is refused naming key, value, range.
#include <gtest/gtest.h>

#include <cmath>

#include "gear_dynamics/config/config.hpp"

namespace gd = gear_dynamics;

namespace {

YAML::Node defaults() {
  const std::string dir = GEAR_DYNAMICS_CONFIG_DIR;
  return gd::read_yaml_files({dir + "/gear_pair.yaml", dir + "/load.yaml", dir + "/run.yaml"});
}

// The error message of parsing `root`, or "" if it parsed.
std::string error_of(const YAML::Node& root) {
  try {
    gd::parse_config(root);
    return "";
  } catch (const gd::ConfigError& e) {
    return e.what();
  }
}

std::string with(const std::string& section, const std::string& key, const std::string& yaml_value) {
  YAML::Node root = defaults();
  root[section][key] = YAML::Load(yaml_value);
  return error_of(root);
}

#define EXPECT_HAS(haystack, needle) \
  EXPECT_NE((haystack).find(needle), std::string::npos) << "message: " << (haystack) << "\nmissing: " << (needle)

}  // namespace

TEST(Config, ShippedFilesLoadWithPaperValues) {
  const gd::ModelConfig c = gd::parse_config(defaults());
  const gd::ModelConfig builtin;
  EXPECT_EQ(c.gear.backlash, builtin.gear.backlash);
  EXPECT_EQ(c.gear.pinion_teeth, 20);
  EXPECT_EQ(c.load.initial_mean, 20.0);
  EXPECT_EQ(c.load.sigma, 5.0);
  EXPECT_EQ(c.run.time_step, 2.5e-6);
  EXPECT_EQ(c.run.steps(), 160000);
  EXPECT_EQ(c.seed, 20180529u);
  EXPECT_EQ(c.run.snapshot_times.size(), 5u);
  // to_yaml round-trips.
  const gd::ModelConfig again = gd::parse_config(gd::to_yaml(c));
  EXPECT_EQ(again.gear.pressure_angle, c.gear.pressure_angle);
  EXPECT_EQ(again.run.snapshot_times, c.run.snapshot_times);
  EXPECT_EQ(again.seed, c.seed);
}

TEST(Config, MissingKey) {
  YAML::Node root = defaults();
  root["gear_pair"].remove("backlash");
  const std::string e = error_of(root);
  EXPECT_HAS(e, "gear_pair.backlash is missing");
  EXPECT_HAS(e, "[0, 0.001] m");
}

TEST(Config, MissingSection) {
  YAML::Node root = defaults();
  root.remove("load");
  EXPECT_HAS(error_of(root), "missing section 'load'");
}

TEST(Config, WrongType) {
  EXPECT_HAS(with("gear_pair", "face_width", "wide"), "gear_pair.face_width = wide has the wrong type");
  EXPECT_HAS(with("load", "sigma", "true"), "load.sigma = true has the wrong type");
  EXPECT_HAS(with("run", "snapshot_times", "0.3"), "run.snapshot_times = 0.3 has the wrong type");
  EXPECT_HAS(with("run", "snapshot_times", "[0.3, x]"), "run.snapshot_times[1] = x has the wrong type");
  EXPECT_HAS(with("gear_pair", "pinion_teeth", "20.5"), "gear_pair.pinion_teeth = 20.5 is not an integer");
}

TEST(Config, NonFinite) {
  EXPECT_HAS(with("load", "sigma", ".nan"), "load.sigma = nan is not finite");
  EXPECT_HAS(with("gear_pair", "density", ".inf"), "gear_pair.density = inf is not finite");
  EXPECT_HAS(with("run", "time_step", "-.inf"), "run.time_step = -inf is not finite");
}

TEST(Config, OutOfRange) {
  const std::string e = with("gear_pair", "backlash", "-1e-5");
  EXPECT_HAS(e, "gear_pair.backlash = -1e-05 is out of range");
  EXPECT_HAS(e, "allowed [0, 0.001] m");
  EXPECT_HAS(with("run", "time_step", "0"), "run.time_step = 0 is out of range; allowed (0, 0.0001] s");
  EXPECT_HAS(with("gear_pair", "friction_coefficient", "0.5"), "allowed [0, 0.2] -");
  EXPECT_HAS(with("load", "sigma", "-1"), "load.sigma = -1 is out of range");
  EXPECT_HAS(with("gear_pair", "poisson_ratio", "0.5"), "allowed [0, 0.5) -");
}

TEST(Config, UnknownKeyIsReported) {
  const std::string e = with("load", "sigmaa", "3");
  EXPECT_HAS(e, "load.sigmaa is not a known key");
  EXPECT_HAS(e, "valid keys: initial_mean, initial_sd, drift, sigma");
}

TEST(Config, EveryProblemIsListed) {
  YAML::Node root = defaults();
  root["load"]["sigma"] = -1;
  root["run"]["window"] = "x";
  const std::string e = error_of(root);
  EXPECT_HAS(e, "load.sigma");
  EXPECT_HAS(e, "run.window");
}

TEST(Config, InconsistentSets) {
  // A short addendum gives a contact ratio below 1.
  EXPECT_HAS(with("gear_pair", "addendum_coefficient", "0.3"), "is outside (1, 2)");
  // 1e-4 s: omega_max h = 7.1 > 2 sqrt(2).
  const std::string h = with("run", "time_step", "1e-4");
  EXPECT_HAS(h, "run.time_step = 0.0001 s is too large for the stiffest contact");
  EXPECT_HAS(h, "RK4 needs omega_max h < 2.828");
  EXPECT_HAS(with("run", "window", "0.5"), "run.window = 0.5 s is out of range; allowed (0, duration = 0.4] s");
  EXPECT_HAS(with("run", "duration", "0.4000005"), "is not a whole number of time steps");
  EXPECT_HAS(with("run", "snapshot_times", "[0.3, 0.3000005]"), "run.snapshot_times[1] = 0.3000005 s is not a grid time");
  EXPECT_HAS(with("run", "snapshot_times", "[0.35, 0.3]"), "the list must increase");
  EXPECT_HAS(with("gear_pair", "mesh_phase", "0.4"), "gear_pair.mesh_phase = 0.4 is out of range; allowed [0, 0.314159");
}

TEST(Config, OverlaysMergeKeyByKey) {
  YAML::Node root = defaults();
  gd::merge_yaml(root, YAML::Load("{load: {sigma: 2.5}, run: {seed: 7}}"));
  const gd::ModelConfig c = gd::parse_config(root);
  EXPECT_EQ(c.load.sigma, 2.5);
  EXPECT_EQ(c.load.initial_sd, 5.0);  // untouched sibling
  EXPECT_EQ(c.seed, 7u);
}

TEST(Config, UnreadableFiles) {
  EXPECT_THROW(gd::read_yaml_files({"/nonexistent/gear.yaml"}), gd::ConfigError);
}
