// Lyapunov exponents of the gear models (doc/nonlinear-dynamics.md §4): every exponent of the flow
// from the variational equation, carried through the production arithmetic's located sub-steps,
// and the two-trajectory estimate of the largest one as a cross-check.
#pragma once

#include <cstdint>
#include <vector>

#include "gear_dynamics/dynamics/system.hpp"

namespace gear_dynamics {

// --- every exponent from the tangent flow (Benettin et al. 1980, Shimada & Nagashima 1979) ---
// One tangent vector per state component (two for the torsional model's (delta, delta_dot), ten
// for the bearings model's state) starts as a unit vector of the scaled state (x_c / scale_c) at
// t = 0; they are Gram-Schmidt orthonormalised in that norm every `orthonormalise_every` steps and
// at every window edge; the logarithms of the diagonal of R, summed over an interval and divided
// by its length, are its exponents. The field is continuous across |delta_m| = b, so a crossing's
// saltation matrix is the identity. The sum of the exponents is the time average of the
// Jacobian's trace (Liouville): the check of every run.
struct SpectrumOptions {
  double duration = 1.2;                  // [s], from t = 0
  std::int64_t orthonormalise_every = 100;  // steps
  // Units of the norm, one per state component; empty: b for a displacement, sqrt(2 Phi b) for a rate.
  std::vector<double> scale;
  std::vector<double> windows;            // window edges [s] in increasing order (grid points)
  std::int64_t record_every = 10;         // orthonormalisations per point of the running estimate
};

struct SpectrumWindow {
  double start = 0, end = 0;     // [s]
  // The exponents over the window [1/s] in the QR order, the descending order of the long-time limit
  // (over a finite time nearly equal ones, e.g. two bearing modes, may come out of order).
  std::vector<double> exponent;
  double trace = 0;              // time average of the Jacobian's trace over the window [1/s]
};

// The sums at a window edge: ln r_kk and the trace's integral, accumulated from t = 0.
struct SpectrumEdge {
  double time = 0;
  std::vector<double> log_r;
  double trace_integral = 0;
};

struct LyapunovSpectrum {
  std::vector<double> exponent;  // over [0, duration] [1/s], one per state component
  double trace = 0;              // time average of tr J over [0, duration] [1/s] (= the exponents' sum)
  std::vector<SpectrumEdge> edges;
  std::vector<SpectrumWindow> windows;  // between consecutive edges
  std::vector<double> time, running;    // running estimate of lambda1 over [0, t]
  // The last grid time at which delta_m - e <= b (teeth apart or on the back flank) [s]; 0 if never
  // after t = 0. A run with duration - last_separation long is in permanent contact since then.
  double last_separation = 0;
};

// The exponents over [from.time, to.time] from the sums at two edges.
SpectrumWindow window_between(const SpectrumEdge& from, const SpectrumEdge& to);

// One lane's spectrum: a deterministic gear with its own gear inputs (gear_pair.model: torsional,
// two exponents, or bearings, ten), mu, constant load and initial state, stepped with the
// production arithmetic at `time_step` (the torsional kernel's located steps, or bearings_step's).
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
