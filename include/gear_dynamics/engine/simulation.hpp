// Runs a block of realizations to the end time with the standard observers (doc/model.md §8) and an
// optional decimated recording: the one driver behind the CLI, the Monte Carlo batch and the tests.
#pragma once

#include <cstdint>
#include <functional>
#include <optional>
#include <vector>

#include "gear_dynamics/engine/bearings.hpp"
#include "gear_dynamics/engine/ensemble.hpp"
#include "gear_dynamics/engine/observers.hpp"

namespace gear_dynamics {

struct RunSettings {
  double time_step = 2.5e-6;   // h [s]
  double duration = 0.4;       // T [s]
  double window = 0.05;        // analysis window W, ending at T [s]
  std::vector<double> snapshot_times{0.30, 0.33, 0.35, 0.36, 0.40};  // grid times [s]
  double steady_state_tolerance = 0.1;       // t_ss threshold as a fraction of b
  double steady_state_tolerance_fine = 0.05; // the secondary variant

  std::int64_t steps() const;                   // N = T / h
  std::int64_t steps_for(double t) const;       // grid index of time t
};

struct SnapshotState {
  double time, delta, delta_dot, load;  // [s], [m], [m/s], [m/s^2]
};

// What a run leaves behind (SI).
struct RunResult {
  double center_distance = 0.0;         // d over [T - W, T] [m s^-1/2]
  double delta_range = 0.0;             // max - min of delta over the window [m]
  double delta_dot_range = 0.0;         // same for delta_dot [m/s]
  double steady_state_time = 0.0;       // t_ss at steady_state_tolerance [s]
  double steady_state_time_fine = 0.0;  // t_ss at steady_state_tolerance_fine [s]
  bool reached_steady_state = false;    // t_ss < T, decided on grid indices (not rounded times)
  double final_delta = 0.0, final_delta_dot = 0.0, final_load = 0.0;
  std::vector<SnapshotState> snapshots;
  std::vector<SectionPoint> section;  // the Poincare section, if asked for (SectionTimes)
  std::optional<BearingForces> bearings;  // gear_pair.model = bearings only
};

// A Poincare section taken while the run is stepped (PoincareSampler, doc/nonlinear-dynamics.md
// §3): (delta, delta_dot) of every lane at t_k = offset + k period, 0 <= t_k <= T, into
// RunResult::section, for a run that starts at t = 0. period 0: none.
struct SectionTimes {
  double period = 0;  // [s]
  double offset = 0;  // [s]
};

// Called at every grid step n with n % every == 0 (n = 0 and n = N included), after the step;
// center_distance is the instantaneous d(t) over the trailing window (SI).
struct Recorder {
  std::int64_t every = 0;  // 0: no recording
  std::function<void(const Ensemble&, const Eigen::ArrayXd& center_distance)> record;
};

// The time of grid point n, n h, rounded to whole nanoseconds, and as a double the one nearest to
// that decimal: what messages, bags and CSV files carry as t (printed shortest it reads 83.123, not
// n * h = 83.12299999999999). The integration itself uses n * h.
std::int64_t grid_time_ns(std::int64_t n, double time_step);
double grid_time(std::int64_t n, double time_step);

// Runs `ensemble` from its current state (normally t = 0) to settings.duration.
std::vector<RunResult> simulate(Ensemble& ensemble, const RunSettings& settings,
                                const Recorder& recorder = {}, const SectionTimes& section = {});

}  // namespace gear_dynamics
