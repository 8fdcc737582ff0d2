// gear_bearings_bench: the cost of a realization-step of the bearings model against the torsional
// model's, both paths of it: the SIMD ensemble (cost per lane) and the one-lane Realization; and
// the bearings model in the ensemble (its own SIMD kernel) against BearingsRealization, which steps
// one lane at a time through bearings_step, the ensemble's path before its kernel. S1 and
// stochastic realizations of the default configuration at a given load; prints CPU ns per step.
#include <ctime>
#include <cstdio>
#include <string>
#include <vector>

#include "gear_dynamics/config/config.hpp"
#include "gear_dynamics/engine/bearings.hpp"
#include "gear_dynamics/engine/ensemble.hpp"
#include "gear_dynamics/engine/realization.hpp"
#include "cli.hpp"

namespace gd = gear_dynamics;

int main(int argc, char** argv) try {
  gd::tools::ModelOptions model;
  int lanes = 32;
  double duration = 0.05;
  CLI::App app("Times a realization-step of the bearings model against the torsional model's.", "gear_bearings_bench");
  gd::tools::add_model_options(app, model);
  app.add_option("--lanes", lanes, "realizations (the ensemble's block)")->capture_default_str();
  app.add_option("--duration", duration, "simulated time [s]")->capture_default_str();
  gd::tools::parse_or_exit(app, argc, argv);
  const gd::ModelConfig c = gd::parse_config(gd::tools::model_yaml(model, {}));
  gd::GearInputs torsional = c.gear, bearings = c.gear;
  torsional.model = gd::GearModel::kTorsional;
  bearings.model = gd::GearModel::kBearings;
  const double h = c.run.time_step;
  const auto steps = static_cast<std::int64_t>(std::llround(duration / h));
  std::vector<gd::LaneSpec> specs;
  for (int i = 0; i < lanes; ++i) specs.push_back(gd::stochastic_lane(c, c.friction_coefficient, static_cast<std::uint64_t>(i)));
  // CPU time of this (single) thread: the machine's other load does not count.
  const auto ns_per_step = [&](auto&& run) {
    const std::clock_t t0 = std::clock();
    run();
    return 1e9 * static_cast<double>(std::clock() - t0) / CLOCKS_PER_SEC / (static_cast<double>(steps) * lanes);
  };
  const double ensemble = ns_per_step([&] {
    gd::Ensemble e(gd::derive(torsional), h, c.initial, specs, c.seed);
    for (std::int64_t n = 0; n < steps; ++n) e.step();
  });
  const double one_lane = ns_per_step([&] {
    for (const gd::LaneSpec& s : specs) {
      gd::Realization r(gd::derive(torsional), h, c.initial, s, c.seed);
      for (std::int64_t n = 0; n < steps; ++n) r.step();
    }
  });
  const double bear = ns_per_step([&] {
    for (const gd::LaneSpec& s : specs) {
      gd::BearingsRealization r(gd::derive(bearings), h, c.initial, s, c.seed);
      for (std::int64_t n = 0; n < steps; ++n) r.step();
    }
  });
  const double bear_ensemble = ns_per_step([&] {
    gd::Ensemble e(gd::derive(bearings), h, c.initial, specs, c.seed);
    for (std::int64_t n = 0; n < steps; ++n) e.step();
  });
  std::printf("Phi0 %g m/s^2, mu %g, %d realizations x %lld steps of %g s\n", c.load.initial_mean,
              c.friction_coefficient, lanes, static_cast<long long>(steps), h);
  std::printf("torsional, ensemble (SIMD lanes): %.2f ns CPU per realization-step\n", ensemble);
  std::printf("torsional, one lane (Realization): %.2f ns\n", one_lane);
  std::printf("bearings (BearingsRealization):    %.2f ns  (x%.2f the ensemble, x%.2f the one lane)\n", bear,
              bear / ensemble, bear / one_lane);
  std::printf("bearings, ensemble (SIMD lanes):    %.2f ns  (x%.2f the torsional ensemble, x%.2f BearingsRealization)\n",
              bear_ensemble, bear_ensemble / ensemble, bear_ensemble / bear);
  return 0;
} catch (const std::exception& e) {
  std::fprintf(stderr, "gear_bearings_bench: %s\n", e.what());
  return 1;
}
