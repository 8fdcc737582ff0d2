// Poincare sections on a LaneSystem (doc/nonlinear-dynamics.md §3).
#pragma once

#include <cstdint>
#include <functional>
#include <vector>

#include "gear_dynamics/dynamics/system.hpp"
#include "gear_dynamics/engine/observers.hpp"  // on_step_grid, the interpolation in a step

namespace gear_dynamics {

// Sample times t_k = offset + k period, k = 0, 1, ..., kept when start <= t_k <= end.
// If period and offset are whole numbers of steps (to 1e-9 of a step) the samples are grid states,
// exactly; otherwise each sample is interpolated within its step: cubic Hermite for a component
// with a derivative component (delta, with slopes delta_dot), that cubic's slope for the derivative
// component (delta_dot), linear for the others.
struct PoincareOptions {
  double period = 0;  // [s]
  double offset = 0;  // [s]
  double start = 0;   // first time kept [s] (the transient before it is discarded)
  double end = 0;     // the system is stepped to this time [s]
  std::vector<double> lane_period;  // if not empty: one period per lane [s] (overrides period)
};

// One crossing of the section: the lane's state at t_k (the ROS message of a batch's section is
// the PoincarePoint message; this is the core's, with the whole state vector).
struct SectionState {
  int lane = 0;
  std::int64_t k = 0;     // index of the period
  double time = 0;        // t_k [s]
  bool on_grid = false;   // exact grid state, not interpolated
  std::vector<double> x;  // state at t_k
};

// Steps `system` from its current time to options.end. `after_step`, if set, is called after
// every step (for statistics of the whole trajectory).
std::vector<SectionState> poincare_section(LaneSystem& system, const PoincareOptions& options,
                                            const std::function<void(const LaneSystem&)>& after_step = {});

}  // namespace gear_dynamics
