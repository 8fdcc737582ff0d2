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
#include <type_traits>
#if defined(__AVX512F__) || defined(__FMA__)
#include <immintrin.h>
#endif

#include "gear_dynamics/model/mesh_schedule.hpp"

// The kernel is inlined into each stepping loop (GCC otherwise calls the packet version once per
// packet, with d and v through memory: 4 % slower).
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

// Eq. 15 with doc/model.md D1/D2: backlash in stiffness and damping, Hunt-Crossley |g|:
// load - q (K g + alpha |g| v), v entering by the last two roundings (it is the stages' chain).
// S is double or, for lanes of different gear pairs (GearLanes), P.
template <class P, class S>
GD_KERNEL_INLINE P acceleration(const P& d, const P& v, const P& load, const S& stiffness, const P& q, const S& b,
                                const S& alpha) {
  const P g = d - clamp(d, b);
  const P force = fused_mul_add(P(alpha * magnitude(g)), v, P(stiffness * g));
  return fused_neg_mul_add(q, force, load);
}

// Load (Eq. 19) at the end of the step: exact in distribution on the grid; z is the step's normal.
template <class P>
GD_KERNEL_INLINE P load_next(const P& load0, const P& drift, const P& sigma, const P& z, double h, double sqrt_h) {
  return fused_mul_add(P(sigma * sqrt_h), z, fused_mul_add(drift, h, load0));
}

// One classical RK4 step of length H with K and b constant, Q at the three stage times (qa, qm,
// qb) and the load linear from la to lb.
template <class P, class S>
GD_KERNEL_INLINE void rk4_segment(double H, const S& K, const S& b, const S& alpha, const P& qa, const P& qm,
                                  const P& qb, const P& la, const P& lb, P& d, P& v) {
  const double half = 0.5 * H;
  const P lm = 0.5 * (la + lb);
  const P a1 = acceleration<P, S>(d, v, la, K, qa, b, alpha);
  const P v2 = fused_mul_add(half, a1, v);
  const P a2 = acceleration<P, S>(fused_mul_add(half, v, d), v2, lm, K, qm, b, alpha);
  const P v3 = fused_mul_add(half, a2, v);
  const P a3 = acceleration<P, S>(fused_mul_add(half, v2, d), v3, lm, K, qm, b, alpha);
  const P v4 = fused_mul_add(H, a3, v);
  const P a4 = acceleration<P, S>(fused_mul_add(H, v3, d), v4, lb, K, qb, b, alpha);
  // x + (H/6)(y1 + 2 y2 + 2 y3 + y4), summed left to right; 2 y is exact, so only the last
  // product's fusion changes a rounding.
  const P dv = fused_mul_add(2.0, v3, P(fused_mul_add(2.0, v2, v))) + v4;
  const P da = fused_mul_add(2.0, a3, P(fused_mul_add(2.0, a2, a1))) + a4;
  d = fused_mul_add(H / 6.0, dv, d);
  v = fused_mul_add(H / 6.0, da, v);
}

// One grid step of (d, v) by RK4 over the plan's segments (split at the stiffness switches), the
// load a straight line from load0 to load1 within the step.
template <class P>
GD_KERNEL_INLINE void rk4_step(const StepPlan& plan, double h, double b, double alpha, double q3, const P& mu,
                               const P& load0, const P& load1, P& d, P& v) {
  for (int s = 0; s < plan.segments; ++s) {
    const StepSegment& seg = plan.segment[s];
    const P la = seg.begin == 0.0 ? load0 : fused_mul_add(seg.begin, P(load1 - load0), load0);
    const P lb = seg.end == 1.0 ? load1 : fused_mul_add(seg.end, P(load1 - load0), load0);
    rk4_segment<P, double>((seg.end - seg.begin) * h, seg.stiffness, b, alpha, fused_mul_add(mu, seg.friction_start, q3),
                           fused_mul_add(mu, seg.friction_mid, q3), fused_mul_add(mu, seg.friction_end, q3), la, lb,
                           d, v);
  }
}

}  // namespace gear_dynamics::kernel
