// The model parameters that bench/gear_numpy.py and bench/gear_octave.m integrate, as JSON: the
// derived quantities of doc/model.md §3 that the equations use, the load and the initial state.
#pragma once

#include <cstdio>
#include <string>
#include <utility>

#include "gear_dynamics/config/config.hpp"

namespace gear_bench {

inline std::string params_json(const gear_dynamics::ModelConfig& c) {
  const gear_dynamics::GearPair g = gear_dynamics::derive(c.gear);
  const std::pair<const char*, double> p[] = {
      {"time_step", c.run.time_step}, {"backlash", g.in.backlash},
      {"damping_coefficient", g.damping_coefficient}, {"q3", g.q3}, {"c0", g.c0}, {"c1", g.c1},
      {"x_b", g.x_b}, {"base_radius1", g.base_radius1}, {"k1", g.k1}, {"k2", g.k2},
      {"mesh_phase", g.in.mesh_phase}, {"pinion_speed", g.in.pinion_speed},
      {"mesh_period_angle", g.mesh_period_angle}, {"single_pair_angle", g.single_pair_angle},
      {"mu", c.friction_coefficient}, {"sigma", c.load.sigma}, {"drift", c.load.drift},
      {"load_mean", c.load.initial_mean}, {"load_sd", c.load.initial_sd},
      {"initial_deflection", c.initial.deflection}, {"initial_velocity", c.initial.velocity},
      {"seed", static_cast<double>(c.seed)}};
  std::string s = "{";
  char buf[96];
  for (const auto& [k, v] : p) {
    std::snprintf(buf, sizeof buf, "%s\n  \"%s\": %.17g", s.size() > 1 ? "," : "", k, v);
    s += buf;
  }
  return s + "\n}\n";
}

}  // namespace gear_bench
