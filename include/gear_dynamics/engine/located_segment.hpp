// The located RK4 segment (doc/model.md §5): one piece of a step with constant stiffness, integrated
// so that every RK4 sub-step sees one smooth branch of the contact law. The backlash boundaries
// |delta| = b are located on the sub-step's own solution and the step is restarted there on the
// other branch, so the scheme keeps RK4's fourth order through impacts, rebounds and grazing
// contacts. Scalar only: the packet kernel (rk4_kernel.hpp) calls it for the lanes that may reach a
// boundary, the one-lane paths for their one lane, so a realization's bits do not depend on its path.
#pragma once

#include <cmath>
#include <type_traits>
#include <utility>

namespace gear_dynamics::kernel {

#define GD_LOCATED_INLINE inline __attribute__((always_inline))

// The branch of a deflection: -1 back-flank contact (d < -b), 0 apart (|d| <= b), +1 working flank.
GD_LOCATED_INLINE int branch_of(double d, double b) { return (d > b) - (d < -b); }

// Most crossings a segment locates; past it the rest of the segment stays on the branch it is on.
constexpr int kMaxCrossingsPerSegment = 16;

// What a segment is integrated with: the stiffness K and Q = q3 + mu f at the segment's start,
// midpoint and end, backlash, Hunt-Crossley coefficient, and the load and the static transmission
// error e at its start and end (straight lines). The boundaries are |delta - e| = b.
struct SegmentInputs {
  double H, Ka, Km, Kb, b, alpha, qa, qm, qb, la, lb, ea, eb;
};

// Variational state carried beside (delta, delta_dot): two tangent vectors (columns of the
// fundamental matrix, in (delta, delta_dot) units) and the integral of the Jacobian's trace, which
// equals ln det of the flow's Jacobian (Liouville). NoTangent carries nothing.
struct NoTangent {};
struct Tangent {
  double xi[2] = {1.0, 0.0};   // delta components of the two vectors
  double eta[2] = {0.0, 1.0};  // delta_dot components
  double trace_integral = 0.0; // integral of d(delta_ddot)/d(delta_dot) over time [-]
};

namespace located {

// The acceleration on branch s, smoothly continued past its boundary, with the Jacobian entries
// jd = da/d(delta), jv = da/d(delta_dot). The same roundings as kernel::acceleration on the branch.
// e and e_dot: the static transmission error and its rate.
GD_LOCATED_INLINE double acceleration(int s, double d, double v, double load, double K, double q, double b,
                                      double alpha, double e, double e_dot, double& jd, double& jv) {
  if (s == 0) {
    jd = jv = 0.0;
    return load;  // what acceleration() gives for g = 0 as well: load - q (+0)
  }
  const double g = (d - e) - (s > 0 ? b : -b);
  const double ag = alpha * (s > 0 ? g : -g);  // alpha |g| on this branch
  const double force = std::fma(ag, v - e_dot, K * g);
  jd = -q * (K + (s > 0 ? alpha : -alpha) * (v - e_dot));
  jv = -q * ag;
  return std::fma(-q, force, load);
}

// One classical RK4 step of length H on branch s: rk4_segment's operations in its order, so that on
// a step that stays on its branch the result is rk4_segment's, bit for bit. The tangent follows
// the same stages (the variational equation of the same branch).
// K, q, the load and e at the step's start (0), midpoint (m) and end (1); e_dot is constant.
struct BranchInputs {
  double K0, Km, K1, q0, qm, q1, l0, l1, e0, e1, e_dot;
};

template <class T>
GD_LOCATED_INLINE void branch_rk4(int s, double H, const BranchInputs& in, double b, double alpha, double& d,
                                  double& v, T& tangent, double* stages = nullptr) {
  const double half = 0.5 * H;
  const double lm = 0.5 * (in.l0 + in.l1), em = 0.5 * (in.e0 + in.e1), ed = in.e_dot;
  double jd[4], jv[4];
  const double a1 = acceleration(s, d, v, in.l0, in.K0, in.q0, b, alpha, in.e0, ed, jd[0], jv[0]);
  const double v2 = std::fma(half, a1, v);
  const double a2 = acceleration(s, std::fma(half, v, d), v2, lm, in.Km, in.qm, b, alpha, em, ed, jd[1], jv[1]);
  const double v3 = std::fma(half, a2, v);
  const double a3 = acceleration(s, std::fma(half, v2, d), v3, lm, in.Km, in.qm, b, alpha, em, ed, jd[2], jv[2]);
  const double v4 = std::fma(H, a3, v);
  const double a4 = acceleration(s, std::fma(H, v3, d), v4, in.l1, in.K1, in.q1, b, alpha, in.e1, ed, jd[3], jv[3]);
  if (stages) {  // the stage deflections, for the packet kernel's proximity test
    stages[0] = std::fma(half, v, d);
    stages[1] = std::fma(half, v2, d);
    stages[2] = std::fma(H, v3, d);
  }
  const double dv = std::fma(2.0, v3, std::fma(2.0, v2, v)) + v4;
  const double da = std::fma(2.0, a3, std::fma(2.0, a2, a1)) + a4;
  d = std::fma(H / 6.0, dv, d);
  v = std::fma(H / 6.0, da, v);
  if constexpr (std::is_same_v<T, Tangent>) {
    for (int k = 0; k < 2; ++k) {
      const double x = tangent.xi[k], y = tangent.eta[k];
      const double kx1 = y, ky1 = jd[0] * x + jv[0] * y;
      const double x2 = x + half * kx1, y2 = y + half * ky1;
      const double kx2 = y2, ky2 = jd[1] * x2 + jv[1] * y2;
      const double x3 = x + half * kx2, y3 = y + half * ky2;
      const double kx3 = y3, ky3 = jd[2] * x3 + jv[2] * y3;
      const double x4 = x + H * kx3, y4 = y + H * ky3;
      const double kx4 = y4, ky4 = jd[3] * x4 + jv[3] * y4;
      tangent.xi[k] = x + H / 6.0 * (kx1 + 2.0 * kx2 + 2.0 * kx3 + kx4);
      tangent.eta[k] = y + H / 6.0 * (ky1 + 2.0 * ky2 + 2.0 * ky3 + ky4);
    }
    tangent.trace_integral += H / 6.0 * (jv[0] + 2.0 * jv[1] + 2.0 * jv[2] + jv[3]);
  }
}

// A boundary the state may leave its branch through: level L, with sign such that
// side * (delta - L) >= 0 on the branch, and the branch beyond it.
struct Boundary {
  double level, side;
  int beyond;
};

GD_LOCATED_INLINE int boundaries(int s, double b, Boundary out[2]) {
  if (s > 0) {
    out[0] = {b, 1.0, 0};
    return 1;
  }
  if (s < 0) {
    out[0] = {-b, -1.0, 0};
    return 1;
  }
  out[0] = {b, -1.0, 1};
  out[1] = {-b, 1.0, -1};
  return 2;
}

// The first u in (0, 1] where e(u) = e0 + e1 u + e2 u^2 + e3 u^3 becomes negative, e(0) taken as
// >= 0 (the state is on its branch); -1 if e stays >= 0. The cubic is split at its extrema into
// monotone pieces, and the first piece that ends below 0 holds the root (bisection to 1e-15).
inline double first_negative_root(double e0, double e1, double e2, double e3) {
  const auto e = [&](double u) { return ((e3 * u + e2) * u + e1) * u + e0; };
  double knots[4] = {0.0, 0.0, 0.0, 1.0};
  int n = 1;
  // Extrema: roots of e1 + 2 e2 u + 3 e3 u^2 inside (0, 1), in increasing order.
  const double A = 3.0 * e3, B = 2.0 * e2, C = e1;
  if (A == 0.0) {
    if (B != 0.0) {
      const double u = -C / B;
      if (u > 0.0 && u < 1.0) knots[n++] = u;
    }
  } else {
    const double disc = B * B - 4.0 * A * C;
    if (disc > 0.0) {
      const double q = -0.5 * (B + std::copysign(std::sqrt(disc), B));
      double u1 = q / A, u2 = q != 0.0 ? C / q : u1;
      if (u1 > u2) std::swap(u1, u2);
      if (u1 > 0.0 && u1 < 1.0) knots[n++] = u1;
      if (u2 > 0.0 && u2 < 1.0 && u2 != u1) knots[n++] = u2;
    }
  }
  knots[n++] = 1.0;
  for (int i = 1; i < n; ++i) {
    if (!(e(knots[i]) < 0.0)) continue;
    double lo = knots[i - 1], hi = knots[i];  // e(lo) >= 0 (or lo = 0), e(hi) < 0, monotone between
    for (int it = 0; it < 60 && hi - lo > 1e-15; ++it) {
      const double mid = 0.5 * (lo + hi);
      (e(mid) < 0.0 ? hi : lo) = mid;
    }
    return hi;
  }
  return -1.0;
}

}  // namespace located

namespace located {

// The crossing search of every model's located segment (this file's torsional one, model_step.hpp's
// generic one): one implementation, so that both models locate their impacts the same way.
// `step(s, u0, w, y)` takes y by one RK4 step on branch s over the fraction w of the rest of the
// segment from u0 (w = 1: to its end); `deflection` and `rate` read the mesh deflection and its time
// derivative off a state; ea, eb are e at the segment's start and end. `project(y, level)` puts a
// state on a boundary it was located on (the torsional state, whose deflection is a coordinate), or
// is nullptr: the state stays the model's, and a restart up to 1e-15 b beyond the boundary counts
// as on it. Returns the crossings located.
template <class State, class Step, class Deflection, class Rate, class Project>
GD_LOCATED_INLINE int locate_crossings(double H, double b, double ea, double eb, State& y, const Step& step,
                                       const Deflection& deflection, const Rate& rate, const Project& project) {
  constexpr bool kProjects = !std::is_null_pointer_v<Project>;
  const auto line = [](double u, double a, double c) { return u == 0.0 ? a : u == 1.0 ? c : std::fma(u, c - a, a); };
  int s = branch_of(deflection(y) - ea, b);
  double u0 = 0.0;  // fraction of the segment done
  for (int crossings = 0;; ++crossings) {
    const double rest = 1.0 - u0, Hr = rest * H;
    State y1 = y;
    step(s, u0, 1.0, y1);
    if (crossings == kMaxCrossingsPerSegment) {
      y = y1;
      return crossings;
    }
    // The first boundary the dense output reaches: p(w) = d + m0 w + c2 w^2 + c3 w^3 against the
    // boundary level + e(w), e a straight line (slope de over the rest of the segment).
    const double d = deflection(y), d1 = deflection(y1);
    const double m0 = Hr * rate(y), m1 = Hr * rate(y1);
    const double c2 = 3.0 * (d1 - d) - 2.0 * m0 - m1, c3 = 2.0 * (d - d1) + m0 + m1;
    const double e0 = line(u0, ea, eb), de = rest * (eb - ea);
    Boundary bnd[2];
    const int nb = boundaries(s, b, bnd);
    double w = -1.0;
    int hit = -1;
    for (int k = 0; k < nb; ++k) {
      const double sd = bnd[k].side;
      const double gap = sd * (d - (bnd[k].level + e0));
      const double wk = first_negative_root(kProjects ? gap : std::fmax(0.0, gap), sd * (m0 - de), sd * c2, sd * c3);
      if (wk > 0.0 && (w < 0.0 || wk < w)) w = wk, hit = k;
    }
    if (hit < 0) {
      y = y1;
      return crossings;
    }
    // Newton on the step length: side * (delta(w) - L - e(w)) = 0, whose slope in w is
    // Hr delta_dot(w) - de.
    const Boundary& B = bnd[hit];
    State yw = y;
    double dw = d, level = B.level + e0;
    for (int it = 0; it < 8; ++it) {
      yw = y;
      step(s, u0, w, yw);
      level = B.level + std::fma(w, de, e0);
      dw = deflection(yw);
      const double f = dw - level, slope = Hr * rate(yw) - de;
      if (std::fabs(f) <= 1e-15 * b || slope == 0.0) break;
      const double next = std::fmin(1.0, std::fmax(0.0, w - f / slope));
      if (next == w) break;
      w = next;
    }
    if (w >= 1.0 && B.side * (dw - level) >= 0.0) {  // the step itself stays on the branch
      y = yw;
      return crossings;
    }
    y = yw;  // on the boundary within the Newton tolerance (1e-15 b)
    if constexpr (kProjects) project(y, level);
    s = B.beyond;
    u0 = w >= 1.0 ? 1.0 : u0 + w * rest;
    if (u0 >= 1.0) return crossings + 1;
  }
}

}  // namespace located

// Integrates the segment from (d, v) with every crossing of |delta| = b located: a branch RK4 step to
// the segment's end; if its cubic Hermite dense output (the step's end values and slopes) leaves
// the branch, the crossing is refined by Newton on the RK4 step's own length (to 1e-15 of b), the
// state is put on the boundary, and the rest of the segment restarts on the branch beyond.
template <class T = NoTangent>
inline void located_segment(const SegmentInputs& in, double& d, double& v, T& tangent) {
  using namespace located;
  struct State {
    double d, v;
    T tangent;
  };
  // K, Q, the load and e at the fraction u of the segment: straight lines between its end values.
  const auto line = [](double u, double a, double b) { return u == 0.0 ? a : u == 1.0 ? b : std::fma(u, b - a, a); };
  const double e_dot = (in.eb - in.ea) / in.H;
  // The branch step over [u0, u0 + w rest]; the whole segment uses its own midpoint K and Q.
  const auto step = [&](int s, double u0, double w, State& y) {
    const double rest = 1.0 - u0, Hr = rest * in.H;
    const double u1 = w == 1.0 ? 1.0 : u0 + w * rest;
    const bool whole = u0 == 0.0 && u1 == 1.0;
    const double um = 0.5 * (u0 + u1);
    const BranchInputs bi{line(u0, in.Ka, in.Kb), whole ? in.Km : line(um, in.Ka, in.Kb), line(u1, in.Ka, in.Kb),
                          line(u0, in.qa, in.qb), whole ? in.qm : line(um, in.qa, in.qb), line(u1, in.qa, in.qb),
                          line(u0, in.la, in.lb), line(u1, in.la, in.lb),
                          line(u0, in.ea, in.eb), line(u1, in.ea, in.eb), e_dot};
    branch_rk4(s, w == 1.0 ? Hr : w * Hr, bi, in.b, in.alpha, y.d, y.v, y.tangent);
  };
  State y{d, v, tangent};
  // On the boundary the new branch starts with g = 0 exactly.
  locate_crossings(
      in.H, in.b, in.ea, in.eb, y, step, [](const State& x) { return x.d; }, [](const State& x) { return x.v; },
      [](State& x, double level) { x.d = level; });
  d = y.d, v = y.v, tangent = y.tangent;
}

}  // namespace gear_dynamics::kernel
