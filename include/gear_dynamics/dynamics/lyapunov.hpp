// Lyapunov exponents of the gear model (doc/nonlinear-dynamics.md §4): both exponents of the
// (delta, delta_dot) flow from the variational equation, carried through the production kernel's
// located sub-steps, and the two-trajectory estimate of the largest one as a cross-check.
#pragma once

#include <cstdint>
#include <vector>

#include "gear_dynamics/dynamics/system.hpp"

namespace gear_dynamics {

// --- both exponents from the tangent flow (Benettin et al. 1980, Shimada & Nagashima 1979) ---
// Two tangent vectors start as the unit vectors of the scaled state (delta/scale[0],
// delta_dot/scale[1]) at t = 0 and are Gram-Schmidt orthonormalised in that norm every
// `orthonormalise_every` steps and at every window edge; the logarithms of the diagonal of R,
// summed over an interval and divided by its length, are its two exponents. The field is
// continuous across |delta| = b, so a crossing's saltation matrix is the identity.
struct SpectrumOptions {
  double duration = 1.2;                  // [s], from t = 0
  std::int64_t orthonormalise_every = 100;  // steps
  std::vector<double> scale;              // (delta, delta_dot) units of the norm; empty: (b, sqrt(2 Phi b))
  std::vector<double> windows;            // window edges [s] in increasing order (grid points)
  std::int64_t record_every = 10;         // orthonormalisations per point of the running estimate
};

struct SpectrumWindow {
  double start = 0, end = 0;     // [s]
  double exponent[2] = {0, 0};   // lambda1 >= lambda2 over the window [1/s]
  double trace = 0;              // time average of the Jacobian's trace over the window [1/s]
};

// The sums at a window edge: ln r11, ln r22 and the trace's integral, accumulated from t = 0.
struct SpectrumEdge {
  double time = 0, log_r[2] = {0, 0}, trace_integral = 0;
};

struct LyapunovSpectrum {
  double exponent[2] = {0, 0};  // over [0, duration] [1/s]
  double trace = 0;             // time average of tr J over [0, duration] [1/s] (= lambda1 + lambda2)
  std::vector<SpectrumEdge> edges;
  std::vector<SpectrumWindow> windows;  // between consecutive edges
  std::vector<double> time, running;    // running estimate of lambda1 over [0, t]
  // The last grid time at which delta - e <= b (teeth apart or on the back flank) [s]; 0 if never
  // after t = 0. A run with duration - last_separation long is in permanent contact since then.
  double last_separation = 0;
};

// The exponents over [from.time, to.time] from the sums at two edges.
SpectrumWindow window_between(const SpectrumEdge& from, const SpectrumEdge& to);

// One spectrum per lane: each lane a deterministic gear with its own gear inputs, mu, constant load
// and initial state, stepped with the production kernel at `time_step`.
LyapunovSpectrum lyapunov_spectrum(const GearLaneSpec& lane, double time_step, const SpectrumOptions& options);

// --- largest exponent: two trajectories with periodic renormalisation (Benettin 1980) ---
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
