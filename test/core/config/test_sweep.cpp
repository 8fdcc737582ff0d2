// Sweep axes (doc/studies.md): lists, linear and log ranges in the schema's order, text axes with
// their key's choices, refusals naming the key, gear_run's --sweep argument, and the batch
// settings' reading of the sweep.
#include <gtest/gtest.h>

#include "gear_dynamics/config/batch_settings.hpp"
#include "gear_dynamics/config/sweep.hpp"
#include "sweeps.hpp"

namespace gd = gear_dynamics;
using gd::test::refusal;
using gd::test::sweep_of;

TEST(SweepGrid, ListsRangesAndSchemaOrder) {
  const auto axes = sweep_of(
      "{load.sigma: [0, 2.5, 5], gear_pair: {backlash: {from: 4.0e-5, to: 6.0e-5, count: 3}}, "
      "load.initial_mean: {from: 1, to: 100, count: 3, scale: log}}");
  ASSERT_EQ(axes.size(), 3u);
  EXPECT_EQ(axes[0].key, "gear_pair.backlash");  // schema order, not the map's
  EXPECT_EQ(axes[1].key, "load.initial_mean");
  EXPECT_EQ(axes[2].key, "load.sigma");
  EXPECT_EQ(axes[0].values.front(), 4.0e-5);
  EXPECT_EQ(axes[0].values.back(), 6.0e-5);  // both ends exact
  EXPECT_NEAR(axes[0].values[1], 5.0e-5, 1e-18);
  EXPECT_EQ(axes[1].values.front(), 1.0);
  EXPECT_NEAR(axes[1].values[1], 10.0, 1e-12);
  EXPECT_EQ(axes[1].values.back(), 100.0);
  EXPECT_EQ(axes[2].values, (std::vector<double>{0, 2.5, 5}));
  EXPECT_EQ(gd::range_values(3, 3, 1, false), std::vector<double>{3});
}

TEST(SweepGrid, BadSweepsNameTheKey) {
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"{load.sgima: [1, 2]}", "monte_carlo.sweep.load.sgima is not a key that can be swept"},
      {"{run.seed: [1, 2]}", "run.* is common to every point"},
      {"{load.sigma: []}", "is empty"},
      {"{load.sigma: [1, 1]}", "repeats 1"},
      {"{load.sigma: [1, x]}", "monte_carlo.sweep.load.sigma[1] = x is not a finite number"},
      {"{load.sigma: {from: 1, to: 5, count: 0}}", "monte_carlo.sweep.load.sigma.count = 0 is out of range"},
      {"{load.sigma: {from: 0, to: 5, count: 3, scale: log}}", "needs from > 0"},
      {"{load.sigma: {from: 0, to: 5, count: 3, step: 1}}", "load.sigma.step is not a key of a range"},
      {"{load.sigma: 3}", "has the wrong type"},
      {"[1, 2]", "must be a map"},
  };
  for (const auto& [yaml, expected] : cases) {
    std::vector<std::string> errors;
    sweep_of(yaml, &errors);
    ASSERT_FALSE(errors.empty()) << yaml;
    EXPECT_NE(errors.front().find(expected), std::string::npos) << yaml << " gave: " << errors.front();
  }
}

TEST(SweepGrid, BatchSettingsReadTheSweep) {
  const std::string dir = GEAR_DYNAMICS_CONFIG_DIR;
  const gd::ModelConfig model =
      gd::parse_config(gd::read_yaml_files({dir + "/gear_pair.yaml", dir + "/load.yaml", dir + "/run.yaml"}));
  YAML::Node section = YAML::LoadFile(std::string(GEAR_DYNAMICS_CONFIG_DIR) + "/monte_carlo.yaml")["monte_carlo"];
  EXPECT_TRUE(gd::parse_batch_settings(section, model).sweep.empty());  // the shipped mu sweep
  section["sweep"] = YAML::Load("{load.sigma: [0, 5], gear_pair.friction_coefficient: [0.01, 0.03]}");
  const gd::BatchSettings s = gd::parse_batch_settings(section, model);
  EXPECT_EQ(s.mu, (std::vector<double>{0.01, 0.03}));  // a friction axis in the sweep replaces mu
  ASSERT_EQ(s.sweep.size(), 1u);
  EXPECT_EQ(s.sweep[0].key, "load.sigma");
  section["sweep"] = YAML::Load("{gear_pair.friction_coefficient: [0.01, 0.01001]}");
  EXPECT_NE(refusal([&] { gd::parse_batch_settings(section, model); }).find("4th decimal"), std::string::npos);
  section["sweep"] = YAML::Load("{load.sigmaa: [1]}");
  EXPECT_NE(refusal([&] { gd::parse_batch_settings(section, model); }).find("monte_carlo.sweep.load.sigmaa"),
            std::string::npos);
}

TEST(SweepGrid, ArgumentOfGearRun) {
  const gd::SweepAxis a = gd::parse_sweep_argument("load.sigma=0,2.5,5");
  EXPECT_EQ(a.key, "load.sigma");
  EXPECT_EQ(a.values, (std::vector<double>{0, 2.5, 5}));
  const gd::SweepAxis b = gd::parse_sweep_argument("load.initial_mean=1:100:3:log");
  EXPECT_EQ(b.values.size(), 3u);
  EXPECT_EQ(b.values.back(), 100.0);
  EXPECT_NE(refusal([] { gd::parse_sweep_argument("load.sigma"); }).find("--sweep expects"), std::string::npos);
}

TEST(SweepGrid, TextAxesTakeTheKeysChoices) {
  // A text axis keeps its values as labels (their positions are its numbers), each read by the key's
  // own table entry, so an unknown value is refused with the key, the value and the allowed choices.
  const auto axes = sweep_of("{gear_pair.friction_model: [xu, constant], load.sigma: [1, 2]}");
  ASSERT_EQ(axes.size(), 2u);
  EXPECT_EQ(axes[0].key, "gear_pair.friction_model");
  EXPECT_EQ(axes[0].labels, (std::vector<std::string>{"xu", "constant"}));
  EXPECT_EQ(axes[0].values, (std::vector<double>{0, 1}));
  EXPECT_EQ(axes[0].value_text(0), "xu");
  EXPECT_FALSE(axes[1].text());
  std::vector<std::string> errors;
  sweep_of("{gear_pair.friction_model: [xu, coulomb]}", &errors);
  ASSERT_EQ(errors.size(), 1u);
  for (const char* part : {"monte_carlo.sweep.gear_pair.friction_model", "coulomb", "benedict_kelley", "iso_tr_13989"})
    EXPECT_NE(errors[0].find(part), std::string::npos) << errors[0];
  errors.clear();
  sweep_of("{gear_pair.friction_direction: [reversing, reversing]}", &errors);
  ASSERT_EQ(errors.size(), 1u);
  EXPECT_NE(errors[0].find("repeats reversing"), std::string::npos) << errors[0];
}
