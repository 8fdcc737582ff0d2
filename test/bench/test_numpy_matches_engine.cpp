// bench/gear_numpy.py is an independent implementation of the same model and scheme: on a
// deterministic run it must follow the engine path by path (1e-9 relative) before the
// chaotic separation (~0.1 s). numpy rounds every product, the engine fuses some into its sums
// (doc/model.md §5), so the two differ by rounding from the first steps on. Two starts over 10 ms: S1 from rest (free flight, the first
// impacts), and at rest in contact, where every stiffness switch falls inside the contact, so the
// switch splitting of doc/model.md §5 decides the result (without it the paths differ at order 1).
#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>  // reads JSON

#include <cmath>
#include <cstdlib>
#include <fstream>
#include <string>

#include "gear_dynamics/config/config.hpp"
#include "gear_dynamics/engine/ensemble.hpp"
#include "params_json.hpp"

namespace gd = gear_dynamics;

namespace {

gd::ModelConfig default_config() {
  const std::string dir = GEAR_DYNAMICS_CONFIG_DIR;
  return gd::parse_config(
      gd::read_yaml_files({dir + "/gear_pair.yaml", dir + "/load.yaml", dir + "/run.yaml"}));
}

// Runs numpy and the engine on S1 of `c` for 10 ms; compares every 0.5 ms, the deviation from
// the flank (delta - b) relative to delta_scale and delta_dot relative to velocity_scale.
void expect_same_path(const gd::ModelConfig& c, double delta_scale, double velocity_scale, double tolerance) {
  const std::string dir = ::testing::TempDir(), params = dir + "gd_params.json",
                    out = dir + "gd_numpy.json";
  std::ofstream(params) << gear_bench::params_json(c);
  ASSERT_EQ(std::system(("/usr/bin/python3 " GEAR_BENCH_DIR "/gear_numpy.py " + params + " " + out +
                         " --realizations 0 --check-duration 0.01 --check-every 0.0005")
                            .c_str()),
            0);
  const YAML::Node numpy = YAML::LoadFile(out);
  const std::int64_t every = std::llround(0.0005 / c.run.time_step);
  ASSERT_EQ(numpy["check_every"].as<std::int64_t>(), every);
  ASSERT_EQ(numpy["check_delta"].size(), 21u);

  gd::Ensemble e(gd::derive(c.gear), c.run.time_step, c.initial,
                 {gd::deterministic_lane(c, c.friction_coefficient)}, c.seed);
  const double b = c.gear.backlash;
  for (std::size_t k = 0; k < numpy["check_delta"].size(); ++k) {
    while (e.step_index() < static_cast<std::int64_t>(k) * every) e.step();
    EXPECT_NEAR(numpy["check_delta"][k].as<double>() - b, e.delta()[0] - b, tolerance * delta_scale)
        << "t = " << e.time();
    EXPECT_NEAR(numpy["check_velocity"][k].as<double>(), e.velocity()[0], tolerance * velocity_scale)
        << "t = " << e.time();
  }
}

}  // namespace

TEST(NumpyBenchmark, MatchesEngineFromRest) {
  const gd::ModelConfig c = default_config();
  // Scales of the rattle: the backlash b and the impact speed sqrt(2 Phi0 b) = 45 mm/s.
  // Rounding apart: the engine's fused and a plain double evaluation differ by 2e-13 at 10 ms.
  expect_same_path(c, c.gear.backlash, std::sqrt(2.0 * c.load.initial_mean * c.gear.backlash), 1e-9);
}

TEST(NumpyBenchmark, MatchesEngineInContactAcrossSwitches) {
  gd::ModelConfig c = default_config();
  const gd::GearPair g = gd::derive(c.gear);
  // At rest at the static deflection x_s on k1 (mu = 0 value): the switch to k2 at 0.93 ms starts
  // an oscillation of amplitude ~x_s about the new equilibrium, and later switches kick it.
  const double xs = c.load.initial_mean / (g.q3 * g.k1);
  c.initial.deflection = c.gear.backlash + xs;
  // This start amplifies rounding differences (e-folding ~0.6 ms from 4 ms on): at 10 ms a plain
  // double evaluation of the scheme (numpy's, an unfused RK4) is
  // 1.0e-8 (delta) and 6.9e-9 (delta_dot) of these scales from the same scheme in long double, the
  // engine's fused one 2.6e-8 and 1.8e-8, the two double ones 1.6e-8 and 1.1e-8 from each other.
  // So 1e-7 here: rounding only; a step not split at a switch errs at order 1.
  expect_same_path(c, xs, xs * std::sqrt(g.q3 * g.k2), 1e-7);
}
