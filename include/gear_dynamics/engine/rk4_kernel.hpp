// The integration step of doc/model.md §5, written once for any lane width: P is `double` (one
// realization, Realization: the live node's one-lane path) or an Eigen array of doubles (Ensemble:
// SIMD packets of realizations). Every lane goes through the same operations in the same order
// whatever P is. Products that feed a sum are fused explicitly (fused_mul_add: one rounding, exact
// on every build, FMA hardware or not); the build forbids any other contraction (-ffp-contract=off)
// and fast math, so a realization's numbers are bit for bit the same in either path and on every
// machine (test_core's Realization tests check the paths, RK4Kernel.* the fusion).
#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <tuple>
#include <type_traits>
#include <utility>
#if defined(__AVX512F__) || defined(__FMA__)
#include <immintrin.h>
#endif

#include "gear_dynamics/engine/located_segment.hpp"
#include "gear_dynamics/model/mesh_schedule.hpp"

// The kernel is inlined into each stepping loop (GCC otherwise calls the packet version once per
// packet, with d and v through memory).
#define GD_KERNEL_INLINE inline __attribute__((always_inline))
#define GD_KERNEL_INLINE_LAMBDA __attribute__((always_inline))

namespace gear_dynamics::kernel {

template <int N>
using Lanes = Eigen::Array<double, N, 1>;

// a * b + c and c - a * b rounded once (IEEE fusedMultiplyAdd). A scalar operand of the packet
// versions stands for every lane.
GD_KERNEL_INLINE double fused_mul_add(double a, double b, double c) { return std::fma(a, b, c); }
GD_KERNEL_INLINE double fused_neg_mul_add(double a, double b, double c) { return std::fma(-a, b, c); }

namespace detail {

template <class T>
struct width : std::integral_constant<int, 0> {};  // a scalar
template <int N>
struct width<Lanes<N>> : std::integral_constant<int, N> {};
template <class A, class B, class C>
constexpr int packet_width = std::max({width<A>::value, width<B>::value, width<C>::value});

GD_KERNEL_INLINE double lane(double x, int) { return x; }
template <int N>
GD_KERNEL_INLINE double lane(const Lanes<N>& x, int i) { return x[i]; }
#if defined(__AVX512F__)
GD_KERNEL_INLINE __m512d vector8(double x, int) { return _mm512_set1_pd(x); }
template <int N>
GD_KERNEL_INLINE __m512d vector8(const Lanes<N>& x, int i) { return _mm512_loadu_pd(x.data() + i); }
#elif defined(__FMA__)
GD_KERNEL_INLINE __m256d vector4(double x, int) { return _mm256_set1_pd(x); }
template <int N>
GD_KERNEL_INLINE __m256d vector4(const Lanes<N>& x, int i) { return _mm256_loadu_pd(x.data() + i); }
#endif

// Lane by lane: +-a * b + c with one rounding, in FMA instructions where the build has them,
// otherwise std::fma (exact in software too): the same numbers on every build.
template <bool kNegate, class A, class B, class C, int N = packet_width<A, B, C>>
GD_KERNEL_INLINE Lanes<N> fused(const A& a, const B& b, const C& c) {
  Lanes<N> r;
  int i = 0;
#if defined(__AVX512F__)
  for (; i + 8 <= N; i += 8) {
    const __m512d x = vector8(a, i), y = vector8(b, i), z = vector8(c, i);
    if constexpr (kNegate)
      _mm512_storeu_pd(r.data() + i, _mm512_fnmadd_pd(x, y, z));
    else
      _mm512_storeu_pd(r.data() + i, _mm512_fmadd_pd(x, y, z));
  }
#elif defined(__FMA__)
  for (; i + 4 <= N; i += 4) {
    const __m256d x = vector4(a, i), y = vector4(b, i), z = vector4(c, i);
    if constexpr (kNegate)
      _mm256_storeu_pd(r.data() + i, _mm256_fnmadd_pd(x, y, z));
    else
      _mm256_storeu_pd(r.data() + i, _mm256_fmadd_pd(x, y, z));
  }
#endif
  for (; i < N; ++i) r[i] = std::fma(kNegate ? -lane(a, i) : lane(a, i), lane(b, i), lane(c, i));
  return r;
}

}  // namespace detail

// The packet versions: each operand a packet or a scalar, at least one a packet.
template <class A, class B, class C, std::enable_if_t<(detail::packet_width<A, B, C> > 0), int> = 0>
GD_KERNEL_INLINE auto fused_mul_add(const A& a, const B& b, const C& c) {
  return detail::fused<false>(a, b, c);
}
template <class A, class B, class C, std::enable_if_t<(detail::packet_width<A, B, C> > 0), int> = 0>
GD_KERNEL_INLINE auto fused_neg_mul_add(const A& a, const B& b, const C& c) {
  return detail::fused<true>(a, b, c);
}

// min(max(d, -b), b) and |x| at either width. Eigen's packet max/min pass their operands to the
// instructions in std::max/std::min's order, so ties (signed zeros) and NaNs resolve alike.
inline double clamp(double d, double b) { return std::min(std::max(d, -b), b); }
template <int N, class B>
inline Lanes<N> clamp(const Lanes<N>& d, const B& b) {
  return d.max(-b).min(b);
}
inline double magnitude(double x) { return std::fabs(x); }
template <int N>
inline Lanes<N> magnitude(const Lanes<N>& x) {
  return x.abs();
}

// Eq. 15 with doc/model.md D1/D2: backlash in stiffness and damping, Hunt-Crossley |g|, the static
// transmission error e (rate e_dot) as a displacement excitation:
// load - q (K g(delta - e) + alpha |g| (v - e_dot)), v entering by the last two roundings (it is
// the stages' chain). S is double or, for lanes of different gear pairs (GearLanes), P. Without
// an excitation (kExcited false: e = 0) the two subtractions stay out of the stages' chain.
template <class P, class S, bool kExcited>
GD_KERNEL_INLINE P acceleration(const P& d, const P& v, const P& load, const S& stiffness, const P& q, const S& b,
                                const S& alpha, const S& e, const S& e_dot) {
  if constexpr (kExcited) {
    const P x = d - e;
    const P g = x - clamp(x, b);
    const P force = fused_mul_add(P(alpha * magnitude(g)), P(v - e_dot), P(stiffness * g));
    return fused_neg_mul_add(q, force, load);
  } else {
    const P g = d - clamp(d, b);
    const P force = fused_mul_add(P(alpha * magnitude(g)), v, P(stiffness * g));
    return fused_neg_mul_add(q, force, load);
  }
}

// Load (Eq. 19) at the end of the step: exact in distribution on the grid; z is the step's normal.
template <class P>
GD_KERNEL_INLINE P load_next(const P& load0, const P& drift, const P& sigma, const P& z, double h, double sqrt_h) {
  return fused_mul_add(P(sigma * sqrt_h), z, fused_mul_add(drift, h, load0));
}

inline double minimum(double a, double b) { return std::min(a, b); }
template <int N>
inline Lanes<N> minimum(const Lanes<N>& a, const Lanes<N>& b) {
  return a.min(b);
}
inline double maximum(double a, double b) { return std::max(a, b); }
template <int N>
inline Lanes<N> maximum(const Lanes<N>& a, const Lanes<N>& b) {
  return a.max(b);
}

// <= 0 where a lane's step may have met |delta - e| = b: the band from the lowest to the highest of
// its stage deflections and end, widened by the most a cubic Hermite with the end slopes can
// overshoot its end values (4/27 (|m0| + |m1|), taken as 1/4), and shifted by e (widened by its
// change over the step), contains b or -b. Elsewhere every stage saw one smooth branch and the dense
// output stays on it, so the step is the located step, bit for bit.
template <class P, class S, bool kExcited = true>
GD_KERNEL_INLINE P boundary_proximity(double H, const S& b, const S& ea, const S& eb, const P& d0, const P& x2,
                                      const P& x3, const P& x4, const P& d1, const P& v0, const P& v1) {
  const P reach = (0.25 * H) * P(magnitude(v0) + magnitude(v1));
  P lo = P(minimum(minimum(minimum(d0, x2), minimum(x3, x4)), d1) - reach);
  P hi = P(maximum(maximum(maximum(d0, x2), maximum(x3, x4)), d1) + reach);
  if constexpr (kExcited) {
    const S spread = magnitude(S(eb - ea));
    lo = P(lo - S(ea + spread));
    hi = P(hi - S(ea - spread));
  }
  return minimum(P((lo - b) * (hi - b)), P((lo + b) * (hi + b)));
}

// One RK4 step of length H with b constant; K, Q at the three stage times (start, midpoint, end);
// the load and the transmission error straight lines from la to lb and ea to eb; the backlash
// crossings located (located_segment.hpp). Every lane first takes the plain step; lanes that may
// have met a boundary are redone by the located segment, one by one (a few in a thousand
// lane-steps).
template <class P, class S, bool kExcited = true>
GD_KERNEL_INLINE void rk4_segment(double H, const S& Ka, const S& Km, const S& Kb, const S& b, const S& alpha,
                                  const P& qa, const P& qm, const P& qb, const P& la, const P& lb, const S& ea,
                                  const S& eb, P& d, P& v) {
  const P d0 = d, v0 = v;
  const double half = 0.5 * H;
  const P lm = 0.5 * (la + lb);
  const S em = S(0.5 * S(ea + eb)), e_dot = S(S(eb - ea) / H);
  const P a1 = acceleration<P, S, kExcited>(d, v, la, Ka, qa, b, alpha, ea, e_dot);
  const P v2 = fused_mul_add(half, a1, v);
  const P x2 = fused_mul_add(half, v, d);
  const P a2 = acceleration<P, S, kExcited>(x2, v2, lm, Km, qm, b, alpha, em, e_dot);
  const P v3 = fused_mul_add(half, a2, v);
  const P x3 = fused_mul_add(half, v2, d);
  const P a3 = acceleration<P, S, kExcited>(x3, v3, lm, Km, qm, b, alpha, em, e_dot);
  const P v4 = fused_mul_add(H, a3, v);
  const P x4 = fused_mul_add(H, v3, d);
  const P a4 = acceleration<P, S, kExcited>(x4, v4, lb, Kb, qb, b, alpha, eb, e_dot);
  // x + (H/6)(y1 + 2 y2 + 2 y3 + y4), summed left to right; 2 y is exact, so only the last
  // product's fusion changes a rounding.
  const P dv = fused_mul_add(2.0, v3, P(fused_mul_add(2.0, v2, v))) + v4;
  const P da = fused_mul_add(2.0, a3, P(fused_mul_add(2.0, a2, a1))) + a4;
  d = fused_mul_add(H / 6.0, dv, d);
  v = fused_mul_add(H / 6.0, da, v);

  const P near = boundary_proximity<P, S, kExcited>(H, b, ea, eb, d0, x2, x3, x4, d, v0, v);
  const auto locate = [&](int i) {
    using detail::lane;
    const SegmentInputs in{H,         lane(Ka, i), lane(Km, i), lane(Kb, i), lane(b, i),  lane(alpha, i), lane(qa, i),
                           lane(qm, i), lane(qb, i), lane(la, i), lane(lb, i), lane(ea, i), lane(eb, i)};
    double di = lane(d0, i), vi = lane(v0, i);
    NoTangent none;
    located_segment(in, di, vi, none);
    return std::pair<double, double>(di, vi);
  };
  if constexpr (std::is_same_v<P, double>) {
    if (near <= 0.0) std::tie(d, v) = locate(0);
  } else {
    if (near.minCoeff() <= 0.0) {
      for (int i = 0; i < P::RowsAtCompileTime; ++i)
        if (near[i] <= 0.0) std::tie(d[i], v[i]) = locate(i);
    }
  }
}

// The segment's inputs as the kernel takes them: the loads at its ends (straight line from load0
// to load1 over the step) and Q = q3 + mu f at its stage times.
template <class P>
struct SegmentLoads {
  P la, lb, qa, qm, qb;
};
template <class P>
GD_KERNEL_INLINE SegmentLoads<P> segment_loads(const StepSegment& seg, double q3, const P& mu, const P& load0,
                                               const P& load1) {
  return {seg.begin == 0.0 ? load0 : P(fused_mul_add(seg.begin, P(load1 - load0), load0)),
          seg.end == 1.0 ? load1 : P(fused_mul_add(seg.end, P(load1 - load0), load0)),
          P(fused_mul_add(mu, seg.friction_start, q3)), P(fused_mul_add(mu, seg.friction_mid, q3)),
          P(fused_mul_add(mu, seg.friction_end, q3))};
}

// One grid step of (d, v) by RK4 over the plan's segments (split at the stiffness switches), the
// load a straight line from load0 to load1 within the step, with the plan's transmission error if
// it has one (kExcited).
template <class P, bool kExcited>
GD_KERNEL_INLINE void rk4_step_of(const StepPlan& plan, double h, double b, double alpha, double q3, const P& mu,
                                  const P& load0, const P& load1, P& d, P& v) {
  for (int s = 0; s < plan.segments; ++s) {
    const StepSegment& seg = plan.segment[s];
    const SegmentLoads<P> l = segment_loads<P>(seg, q3, mu, load0, load1);
    rk4_segment<P, double, kExcited>((seg.end - seg.begin) * h, seg.stiffness_start, seg.stiffness_mid,
                                     seg.stiffness_end, b, alpha, l.qa, l.qm, l.qb, l.la, l.lb,
                                     kExcited ? seg.error_start : 0.0, kExcited ? seg.error_end : 0.0, d, v);
  }
}

// The excited step out of line: inlined beside the plain one it would double the stepping loops'
// code and slow the paper's model, which never has an excitation.
template <class P>
__attribute__((noinline)) void rk4_step_excited(const StepPlan& plan, double h, double b, double alpha, double q3,
                                                const P& mu, const P& load0, const P& load1, P& d, P& v) {
  rk4_step_of<P, true>(plan, h, b, alpha, q3, mu, load0, load1, d, v);
}

template <class P>
GD_KERNEL_INLINE void rk4_step(const StepPlan& plan, double h, double b, double alpha, double q3, const P& mu,
                               const P& load0, const P& load1, P& d, P& v) {
  if (plan.excited)
    rk4_step_excited<P>(plan, h, b, alpha, q3, mu, load0, load1, d, v);
  else
    rk4_step_of<P, false>(plan, h, b, alpha, q3, mu, load0, load1, d, v);
}

// rk4_step for one lane with its tangent vectors (the Lyapunov spectrum): the variational equation
// is carried through the same sub-steps, and (d, v) come out bit for bit as rk4_step's. A step that
// stays on its branch is the branch step (its stages decide the located path exactly as
// rk4_segment's do: both sets of stages agree until one leaves the branch, and then both bands
// contain a boundary).
inline void rk4_step_tangent(const StepPlan& plan, double h, double b, double alpha, double q3, double mu,
                             double load0, double load1, double& d, double& v, Tangent& tangent) {
  for (int s = 0; s < plan.segments; ++s) {
    const StepSegment& seg = plan.segment[s];
    const double H = (seg.end - seg.begin) * h;
    const SegmentLoads<double> l = segment_loads<double>(seg, q3, mu, load0, load1);
    const SegmentInputs in{H,    seg.stiffness_start, seg.stiffness_mid, seg.stiffness_end, b, alpha, l.qa, l.qm,
                           l.qb, l.la,                l.lb,              seg.error_start,   seg.error_end};
    const located::BranchInputs bi{in.Ka, in.Km, in.Kb, in.qa, in.qm, in.qb, in.la, in.lb,
                                   in.ea, in.eb, (in.eb - in.ea) / H};
    double d1 = d, v1 = v, x[3];
    Tangent t1 = tangent;
    located::branch_rk4(branch_of(d - in.ea, b), H, bi, b, alpha, d1, v1, t1, x);
    if (boundary_proximity<double, double>(H, b, in.ea, in.eb, d, x[0], x[1], x[2], d1, v, v1) <= 0.0) {
      located_segment(in, d, v, tangent);
    } else {
      d = d1, v = v1, tangent = t1;
    }
  }
}

}  // namespace gear_dynamics::kernel
