// Synthetic run records whose statistics are known, for the analysis and report tests.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "gear_dynamics/batch/run_record.hpp"

namespace gear_dynamics::test {

inline RunRecord record(RunKind kind, double mu, std::uint32_t index, double d, double delta, double delta_dot) {
  RunRecord r;
  r.kind = kind;
  r.mu = mu;
  r.index = index;
  r.name = std::string(to_string(kind)) + std::to_string(index);
  r.center_distance = d;
  r.steady_state_time = 0.3 + 0.001 * index;
  r.steady_state_time_fine = 0.35 + 0.001 * index;
  r.reached_steady_state = index % 3 != 0;
  r.final_delta = delta;
  r.final_delta_dot = delta_dot;
  r.final_phi = 20.0;
  r.snapshot_times = {0.30, 0.33, 0.35, 0.36, 0.40};
  for (double t : r.snapshot_times) {
    r.snapshot_delta.push_back(delta * t / 0.4);
    r.snapshot_delta_dot.push_back(delta_dot - (0.4 - t));
  }
  return r;
}

// Two mu values; at each, S1, 8 phase runs and 12 realizations with known values.
inline std::vector<RunRecord> synthetic() {
  std::vector<RunRecord> runs;
  for (double mu : {0.04, 0.0}) {  // out of order on purpose
    const double shift = mu * 10;
    runs.push_back(record(RunKind::S1, mu, 0, 0.0005 + shift * 1e-3, 5.1e-5, -0.002));
    for (std::uint32_t j = 0; j < 8; ++j)
      runs.push_back(record(RunKind::Phase, mu, j, 0.0002 + 0.0001 * j, 5.0e-5 + 1e-7 * j, 0.001 * j));
    for (std::uint32_t r = 0; r < 12; ++r)
      runs.push_back(record(RunKind::Stochastic, mu, r, 0.0001 * (r + 1) + shift * 1e-4,
                            3.5e-5 + 2e-6 * r, -0.030 + 0.005 * r));
  }
  return runs;
}


}  // namespace gear_dynamics::test
