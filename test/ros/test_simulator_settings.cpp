// The simulator's settings: the shipped file loads, each kind of bad input is refused naming the
// key, and the dynamic_reconfigure limits (config/Simulator.cfg) equal the validators'.
#include <gtest/gtest.h>

#include "gear_dynamics/SimulatorConfig.h"
#include "gear_dynamics/config/config.hpp"
#include "gear_dynamics/config/simulator_settings.hpp"

namespace gd = gear_dynamics;

namespace {

constexpr double kStep = 1e-6;

YAML::Node shipped() { return gd::read_yaml_files({std::string(GEAR_DYNAMICS_CONFIG_DIR) + "/simulator.yaml"}); }

// The message parse_simulator_settings refuses `root` with; empty when it accepts it.
std::string parse_error(const YAML::Node& root, double time_step = kStep) {
  try {
    gd::parse_simulator_settings(root, time_step);
    return "";
  } catch (const gd::ConfigError& e) {
    return e.what();
  }
}

std::string error_with(const std::string& key, const std::string& yaml_value, double time_step = kStep) {
  YAML::Node root = shipped();
  if (yaml_value.empty()) {
    root["simulator"].remove(key);
  } else {
    root["simulator"][key] = YAML::Load(yaml_value);
  }
  return parse_error(root, time_step);
}

#define EXPECT_HAS(haystack, needle) \
  EXPECT_NE((haystack).find(needle), std::string::npos) << "message: " << (haystack) << "\nmissing: " << (needle)

}  // namespace

TEST(SimulatorSettings, ShippedFileLoads) {
  const gd::SimulatorSettings s = gd::parse_simulator_settings(shipped(), kStep);
  EXPECT_FALSE(s.deterministic);
  EXPECT_EQ(s.realization, 0u);
  EXPECT_EQ(s.publish_rate, 1000.0);
  EXPECT_TRUE(s.publish_clock);
  EXPECT_EQ(s.real_time_factor, 1.0);
  EXPECT_EQ(s.t_end, 0.0);  // runs until stopped (the paper: t_end 0.4)
  EXPECT_EQ(s.load_input, "sde");
  EXPECT_FALSE(s.loop);
  EXPECT_FALSE(s.paused);
  // to_yaml round-trips.
  YAML::Node root;
  root["simulator"] = gd::to_yaml(s);
  const gd::SimulatorSettings again = gd::parse_simulator_settings(root, kStep);
  EXPECT_EQ(again.publish_rate, s.publish_rate);
  EXPECT_EQ(again.t_end, s.t_end);
  EXPECT_EQ(again.publish_scalars, s.publish_scalars);
}

TEST(SimulatorSettings, BadValuesNameKeyValueAndRange) {
  EXPECT_HAS(error_with("publish_rate", ""), "simulator.publish_rate is missing");
  EXPECT_HAS(error_with("publish_rate", "0"), "simulator.publish_rate = 0 is out of range; allowed [1, 1000000]");
  EXPECT_HAS(error_with("publish_rate", "2e6"), "simulator.publish_rate = 2000000 is out of range");
  // At most one message per grid step.
  EXPECT_HAS(error_with("publish_rate", "60000", 2e-5), "allowed [1, 50000]");
  EXPECT_HAS(error_with("publish_rate", "fast"), "simulator.publish_rate = fast has the wrong type");
  EXPECT_HAS(error_with("publish_rate", ".nan"), "simulator.publish_rate = nan is not finite; allowed [1, 1000000]");
  EXPECT_HAS(error_with("real_time_factor", "-1"), "simulator.real_time_factor = -1 is out of range; allowed [0, 1000]");
  EXPECT_HAS(error_with("realization", "1.5"), "simulator.realization = 1.5 is not an integer");
  EXPECT_HAS(error_with("realization", "-1"), "simulator.realization = -1 is out of range");
  EXPECT_HAS(error_with("t_end", "0.0000015"), "simulator.t_end = 1.5e-06 s is not a whole number of time steps");
  EXPECT_HAS(error_with("loop", "1"), "simulator.loop = 1 has the wrong type: expected true or false");
  EXPECT_EQ(error_with("paused", "true"), "");
  EXPECT_HAS(error_with("publish_clock", "[true]"), "simulator.publish_clock = [true] has the wrong type");
  EXPECT_EQ(error_with("deterministic", "yes"), "");  // YAML's other spellings of true
}

TEST(SimulatorSettings, ContradictionsAndTypos) {
  YAML::Node root = shipped();
  root["simulator"]["t_end"] = 0.0;
  root["simulator"]["loop"] = true;
  EXPECT_HAS(parse_error(root), "simulator.loop = true needs simulator.t_end > 0");
  EXPECT_HAS(error_with("exit_at_end", "true"), "simulator.exit_at_end = true needs simulator.t_end > 0");
  root = shipped();
  root["simulator"]["t_end"] = 0.4;
  root["simulator"]["loop"] = true;
  root["simulator"]["exit_at_end"] = true;
  EXPECT_HAS(parse_error(root), "simulator.exit_at_end = true contradicts simulator.loop = true");
  root["simulator"]["loop"] = false;
  EXPECT_EQ(parse_error(root), "");
  EXPECT_TRUE(gd::parse_simulator_settings(root, kStep).exit_at_end);
  EXPECT_HAS(error_with("publish_rat", "100"), "simulator.publish_rat is not a known key (a typo?); valid keys:");
  EXPECT_HAS(error_with("publish_rat", "100"), "publish_rate");
  // Several problems are all reported.
  root = shipped();
  root["simulator"]["t_end"] = -1.0;
  root["simulator"]["real_time_factor"] = "x";
  const std::string both = parse_error(root);
  EXPECT_HAS(both, "simulator.t_end = -1");
  EXPECT_HAS(both, "simulator.real_time_factor = x");
  EXPECT_THROW(gd::parse_simulator_settings(YAML::Load("{gear_pair: {}}"), kStep), gd::ConfigError);
}

TEST(SimulatorSettings, SpectrumOffByDefaultAndCheckedWhenOn) {
  const gd::SimulatorSettings s = gd::parse_simulator_settings(shipped(), kStep);
  EXPECT_EQ(s.spectrum_rate, 0.0);
  EXPECT_FALSE(gd::spectrum_sampling(s, kStep).enabled());
  // Ranges hold whether the topic is on or not.
  EXPECT_HAS(error_with("spectrum_rate", "-1"), "simulator.spectrum_rate = -1 is out of range; allowed [0, 100]");
  EXPECT_HAS(error_with("spectrum_overlap", "0.96"), "simulator.spectrum_overlap = 0.96 is out of range; allowed [0, 0.95]");
  EXPECT_HAS(error_with("spectrum_window", "0"), "simulator.spectrum_window = 0 is out of range; allowed (0, 1000]");
  EXPECT_HAS(error_with("spectrum_segment", ""), "simulator.spectrum_segment is missing");
  // Against the grid and the window only when it is on (a coarse grid need not fit an unused topic).
  EXPECT_EQ(error_with("spectrum_sample_rate", "200000", 1e-5), "");
  const auto with_spectrum = [](const std::string& key, const std::string& value, double time_step = kStep) {
    YAML::Node root = shipped();
    root["simulator"]["spectrum_rate"] = 1.0;
    root["simulator"][key] = YAML::Load(value);
    return parse_error(root, time_step);
  };
  EXPECT_EQ(with_spectrum("spectrum_overlap", "0.75"), "");
  EXPECT_HAS(with_spectrum("spectrum_sample_rate", "200000", 1e-5),
             "simulator.spectrum_sample_rate = 200000 is out of range; allowed [1, 100000] Hz (at most 1/time_step");
  EXPECT_HAS(with_spectrum("spectrum_window", "20"),
             "simulator.spectrum_window = 20 s holds 2000000 samples at the sample rate 100000 Hz; allowed at most 1000000");
  EXPECT_HAS(with_spectrum("spectrum_segment", "2"),
             "simulator.spectrum_segment = 2 s holds 200000 samples at the sample rate 100000 Hz; allowed [8, 100000] samples");
  EXPECT_HAS(with_spectrum("spectrum_segment", "0.00005"), "holds 5 samples");
}

TEST(SimulatorSettings, SpectrumSamplingOnTheGrid) {
  gd::SimulatorSettings s;
  s.spectrum_rate = 3.0;
  s.spectrum_sample_rate = 30000.0;  // every round(33.3) = 33 steps: 30303.03 Hz
  s.spectrum_window = 0.5;
  s.spectrum_segment = 0.09;
  const gd::SpectrumSampling p = gd::spectrum_sampling(s, kStep);
  EXPECT_TRUE(p.enabled());
  EXPECT_EQ(p.sample_steps, 33);
  EXPECT_DOUBLE_EQ(p.sample_rate, 1.0 / 33e-6);
  EXPECT_EQ(p.update_steps, 33 * 10101);  // round(30303.03 / 3) sample periods
  EXPECT_EQ(p.window_samples, 15152);
  EXPECT_EQ(p.segment_samples, 2727);
  // The defaults: every 10 steps, 30 mesh periods of 1000 rpm per segment (9000 samples).
  gd::SimulatorSettings d;
  d.spectrum_rate = 1.0;
  const gd::SpectrumSampling q = gd::spectrum_sampling(d, kStep);
  EXPECT_EQ(q.sample_steps, 10);
  EXPECT_EQ(q.update_steps, 1000000);
  EXPECT_EQ(q.window_samples, 100000);
  EXPECT_EQ(q.segment_samples, 9000);
}

TEST(SimulatorSettings, PublishPeriodRoundsToWholeSteps) {
  EXPECT_EQ(gd::publish_period_steps(1000.0, 1e-6), 1000);
  EXPECT_EQ(gd::publish_period_steps(10000.0, 1e-6), 100);
  EXPECT_EQ(gd::publish_period_steps(3000.0, 1e-6), 333);
  EXPECT_EQ(gd::publish_period_steps(1e6, 2e-5), 1);
}

TEST(SimulatorSettings, ReconfigureLimitsEqualTheValidators) {
  const gear_dynamics::SimulatorConfig lo = gear_dynamics::SimulatorConfig::__getMin__();
  const gear_dynamics::SimulatorConfig hi = gear_dynamics::SimulatorConfig::__getMax__();
  EXPECT_EQ(lo.mu, 0.0);
  EXPECT_EQ(hi.mu, gd::kMaxFrictionCoefficient);
  EXPECT_EQ(lo.sigma, 0.0);
  EXPECT_EQ(hi.sigma, gd::kMaxLoadSigma);
  EXPECT_EQ(lo.lambda, -gd::kMaxLoadDrift);
  EXPECT_EQ(hi.lambda, gd::kMaxLoadDrift);
  EXPECT_EQ(lo.real_time_factor, 0.0);
  EXPECT_EQ(hi.real_time_factor, gd::kMaxRealTimeFactor);
  EXPECT_EQ(lo.publish_rate, gd::kMinPublishRate);
  EXPECT_EQ(hi.publish_rate, gd::kMaxPublishRate);
}
