// Offline reference for simulator_reconfigure.test: runs one realization with the core alone,
// switching mu at a given grid step through Ensemble::set_mu, and prints the series the node
// publishes (CSV t,delta,delta_dot,phi,mu with 17 significant digits: doubles round-trip).
#include <cstdio>
#include <iostream>
#include <string>

#include "gear_dynamics/config/config.hpp"
#include "gear_dynamics/engine/ensemble.hpp"
#include "gear_dynamics/engine/simulation.hpp"

namespace gd = gear_dynamics;

int main(int argc, char** argv) try {
  if (argc != 8) {
    std::cerr << "usage: mu_switch_reference CONFIG.yaml REALIZATION|S1 EVERY END_STEP SWITCH_STEP MU OUT.csv\n";
    return 2;
  }
  const gd::ModelConfig cfg = gd::parse_config(gd::read_yaml_files({argv[1]}));
  const std::string run = argv[2];
  const std::int64_t every = std::stoll(argv[3]), end = std::stoll(argv[4]), at = std::stoll(argv[5]);
  const double mu = std::stod(argv[6]);
  const gd::LaneSpec lane = run == "S1"
                                ? gd::deterministic_lane(cfg, cfg.friction_coefficient)
                                : gd::stochastic_lane(cfg, cfg.friction_coefficient, std::stoull(run));
  gd::Ensemble e(gd::derive(cfg.gear), cfg.run.time_step, cfg.initial, {lane}, cfg.seed);
  FILE* out = std::fopen(argv[7], "w");
  if (!out) throw std::runtime_error(std::string("cannot write ") + argv[7]);
  for (;;) {
    const std::int64_t n = e.step_index();
    if (n % every == 0 || n == end)
      std::fprintf(out, "%.17g,%.17g,%.17g,%.17g,%.17g\n", gd::grid_time(n, e.time_step()), e.delta()[0], e.velocity()[0],
                   e.load()[0], e.lane(0).mu);
    if (n == end) break;
    if (n == at) e.set_mu(0, mu);  // as the node: after publishing step n, before integrating it
    e.step();
  }
  std::fclose(out);
  return 0;
} catch (const std::exception& ex) {
  std::cerr << "mu_switch_reference: " << ex.what() << "\n";
  return 1;
}
