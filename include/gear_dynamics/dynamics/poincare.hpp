// Poincare sections and the Lyapunov exponent on a LaneSystem (doc/nonlinear-dynamics.md §3, §4).
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
// with a derivative component (delta, with slopes delta_dot), linear for the others.
struct PoincareOptions {
  double period = 0;  // [s]
  double offset = 0;  // [s]
  double start = 0;   // first time kept [s] (the transient before it is discarded)
  double end = 0;     // the system is stepped to this time [s]
  std::vector<double> lane_period;  // if not empty: one period per lane [s] (overrides period)
};

struct PoincarePoint {
  int lane = 0;
  std::int64_t k = 0;     // index of the period
  double time = 0;        // t_k [s]
  bool on_grid = false;   // exact grid state, not interpolated
  std::vector<double> x;  // state at t_k
};

// Steps `system` from its current time to options.end. `after_step`, if set, is called after
// every step (for statistics of the whole trajectory).
std::vector<PoincarePoint> poincare_section(LaneSystem& system, const PoincareOptions& options,
                                            const std::function<void(const LaneSystem&)>& after_step = {});

// --- largest Lyapunov exponent: two trajectories with periodic renormalisation (Benettin 1980) ---
// Lanes 2i and 2i+1 of the system form pair i: lane 2i is the reference; after the transient
// lane 2i+1 is set to reference + d0 e (e = (1, ..., 1)/sqrt(dim) in scaled units, x_c / scale_c),
// and every `renormalise_every` steps the separation d (scaled Euclidean norm) is measured,
// ln(d/d0) accumulated, and lane 2i+1 pulled back to distance d0 along the current separation.
struct LyapunovOptions {
  double transient = 0;                   // [s] both lanes of a pair run it together
  double duration = 1;                    // [s] averaging time after the transient
  std::int64_t renormalise_every = 100;   // steps
  double separation = 1e-8;               // d0, scaled units
  std::vector<double> scale;              // per component; empty: all 1
  std::int64_t record_every = 10;         // renormalisations per point of the running estimate
};

struct LyapunovResult {
  double exponent = 0;               // sum ln(d/d0) / elapsed time [1/s]
  std::vector<double> time, running; // running estimate after each recorded renormalisation
  double max_log_growth = 0;         // largest ln(d/d0) over one renormalisation interval
  double min_log_growth = 0;         // smallest
  std::int64_t intervals = 0;
};
std::vector<LyapunovResult> largest_lyapunov(LaneSystem& system, const LyapunovOptions& options);

}  // namespace gear_dynamics
