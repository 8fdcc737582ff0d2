// The integration step of doc/model.md §5, written once for any lane width: P is `double` (one
// realization, Realization: the live node's one-lane path) or an Eigen array of Ensemble::kPacket
// doubles (Ensemble: a SIMD packet of realizations). Every lane goes through the same operations in
// the same order whatever P is, and the build forbids contraction into FMAs (-ffp-contract=off)
// and fast math, so a realization's numbers are bit for bit the same in either (test_core's
// Realization tests check it).
#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <cmath>

#include "gear_dynamics/model/mesh_schedule.hpp"

// The kernel is inlined into each stepping loop (GCC otherwise calls the packet version once per
// packet, with d and v through memory: 4 % slower).
#define GD_KERNEL_INLINE inline __attribute__((always_inline))
#define GD_KERNEL_INLINE_LAMBDA __attribute__((always_inline))

namespace gear_dynamics::kernel {

// min(max(d, -b), b) and |x| at either width. Eigen's packet max/min pass their operands to the
// instructions in std::max/std::min's order, so ties (signed zeros) and NaNs resolve alike.
inline double clamp(double d, double b) { return std::min(std::max(d, -b), b); }
template <int N>
inline Eigen::Array<double, N, 1> clamp(const Eigen::Array<double, N, 1>& d, double b) {
  return d.max(-b).min(b);
}
inline double magnitude(double x) { return std::fabs(x); }
template <int N>
inline Eigen::Array<double, N, 1> magnitude(const Eigen::Array<double, N, 1>& x) {
  return x.abs();
}

// Eq. 15 with doc/model.md D1/D2: backlash in stiffness and damping, Hunt-Crossley |g|.
template <class P>
GD_KERNEL_INLINE P acceleration(const P& d, const P& v, const P& load, double stiffness, const P& q, double b,
                      double alpha) {
  const P g = d - clamp(d, b);
  return load - q * (stiffness * g + (alpha * magnitude(g)) * v);
}

// Load (Eq. 19) at the end of the step: exact in distribution on the grid; z is the step's normal.
template <class P>
GD_KERNEL_INLINE P load_next(const P& load0, const P& drift, const P& sigma, const P& z, double h, double sqrt_h) {
  return load0 + drift * h + (sigma * sqrt_h) * z;
}

// One grid step of (d, v) by RK4 over the plan's segments (split at the stiffness switches), the
// load a straight line from load0 to load1 within the step.
template <class P>
GD_KERNEL_INLINE void rk4_step(const StepPlan& plan, double h, double b, double alpha, double q3, const P& mu,
                     const P& load0, const P& load1, P& d, P& v) {
  for (int s = 0; s < plan.segments; ++s) {
    const StepSegment& seg = plan.segment[s];
    const double H = (seg.end - seg.begin) * h, half = 0.5 * H;
    const P la = seg.begin == 0.0 ? load0 : P(load0 + seg.begin * (load1 - load0));
    const P lb = seg.end == 1.0 ? load1 : P(load0 + seg.end * (load1 - load0));
    const P lm = 0.5 * (la + lb);
    const P qa = q3 + mu * seg.friction_start;
    const P qm = q3 + mu * seg.friction_mid;
    const P qb = q3 + mu * seg.friction_end;
    const double K = seg.stiffness;

    const P a1 = acceleration<P>(d, v, la, K, qa, b, alpha);
    const P v2 = v + half * a1;
    const P a2 = acceleration<P>(d + half * v, v2, lm, K, qm, b, alpha);
    const P v3 = v + half * a2;
    const P a3 = acceleration<P>(d + half * v2, v3, lm, K, qm, b, alpha);
    const P v4 = v + H * a3;
    const P a4 = acceleration<P>(d + H * v3, v4, lb, K, qb, b, alpha);
    d += (H / 6.0) * (v + 2.0 * v2 + 2.0 * v3 + v4);
    v += (H / 6.0) * (a1 + 2.0 * a2 + 2.0 * a3 + a4);
  }
}

}  // namespace gear_dynamics::kernel
