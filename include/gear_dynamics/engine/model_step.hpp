// The model seam of the engine (doc/architecture.md): a gear model is a state vector, its right-hand
// side on each smooth branch of the backlash function, and the mesh deflection as a linear function
// of the state whose crossings of +-b (shifted by the transmission error e) are located. This file
// steps any such model by RK4 through one MeshSchedule plan, locating every crossing as
// located_segment.hpp does for the torsional model: a branch step, its cubic Hermite dense output of
// the deflection, Newton on the step's own length, a restart on the branch beyond. So the method
// keeps RK4's fourth order through impacts whatever the model.
//
// A Model provides:
//   static constexpr int kStates;                 // size of the state
//   using State = Eigen::Matrix<double, kStates, 1>;
//   double deflection(const State&) const;        // the mesh deflection, linear in the state [m]
//   double deflection_rate(const State&) const;   // its time derivative (the same linear map of dy/dt)
//   State derivative(int branch, const State&, const MeshPoint&) const;  // dy/dt on `branch`,
//                                                 // smoothly continued past its boundaries
// The torsional model keeps its own SIMD kernel (rk4_kernel.hpp); this path is scalar.
#pragma once

#include <Eigen/Core>
#include <cmath>

#include "gear_dynamics/engine/located_segment.hpp"
#include "gear_dynamics/model/mesh_schedule.hpp"

namespace gear_dynamics::model_step {

// The mesh and the load at one RK4 stage time.
struct MeshPoint {
  double stiffness;       // K [N/m]
  double q;               // Q = q3 + mu f [1/kg]: the mesh force's effect on the torsional coordinate
  double friction_force;  // mu sigma: friction force across the line of action per unit mesh force [-]
  double load;            // Phi [m/s^2]
  double error;           // static transmission error e [m]
  double error_rate;      // e_dot [m/s]
};

// One piece of a grid step on which the mesh is smooth: the MeshPoints at its start, midpoint and
// end; the values in between are straight lines (as the torsional segment's).
struct Segment {
  double H;  // length [s]
  double b;  // backlash [m]
  MeshPoint start, mid, end;
};

// The branch of deflection d against the boundaries +-b shifted by e (located_segment.hpp).
inline int branch_of(double d, double e, double b) { return kernel::branch_of(d - e, b); }

namespace detail {

inline double line(double u, double a, double b) { return u == 0.0 ? a : u == 1.0 ? b : std::fma(u, b - a, a); }

inline MeshPoint point_at(const Segment& s, double u) {
  return {line(u, s.start.stiffness, s.end.stiffness), line(u, s.start.q, s.end.q),
          line(u, s.start.friction_force, s.end.friction_force), line(u, s.start.load, s.end.load),
          line(u, s.start.error, s.end.error), s.start.error_rate};
}

// One classical RK4 step of length H on branch s, the mesh at its start p0, midpoint pm, end p1.
template <class M>
inline void branch_rk4(const M& model, int s, double H, const MeshPoint& p0, const MeshPoint& pm,
                       const MeshPoint& p1, typename M::State& y) {
  using State = typename M::State;
  const double half = 0.5 * H;
  const State k1 = model.derivative(s, y, p0);
  const State k2 = model.derivative(s, y + half * k1, pm);
  const State k3 = model.derivative(s, y + half * k2, pm);
  const State k4 = model.derivative(s, y + H * k3, p1);
  y += (H / 6.0) * (k1 + 2.0 * k2 + 2.0 * k3 + k4);
}

}  // namespace detail

// Integrates one segment from y with every crossing of the deflection through +-b + e located
// (at most kernel::kMaxCrossingsPerSegment; past it the rest stays on its branch). Returns the
// crossings located.
template <class M>
inline int located_segment(const M& model, const Segment& in, typename M::State& y) {
  using namespace kernel::located;
  using State = typename M::State;
  int s = branch_of(model.deflection(y), in.start.error, in.b);
  double u0 = 0.0;
  for (int crossings = 0;; ++crossings) {
    const double rest = 1.0 - u0, Hr = rest * in.H;
    const auto step = [&](double w, State& yy) {
      const double u1 = w == 1.0 ? 1.0 : u0 + w * rest;
      const bool whole = u0 == 0.0 && u1 == 1.0;
      const MeshPoint pm = whole ? in.mid : detail::point_at(in, 0.5 * (u0 + u1));
      detail::branch_rk4(model, s, w == 1.0 ? Hr : w * Hr, detail::point_at(in, u0), pm, detail::point_at(in, u1), yy);
    };
    State y1 = y;
    step(1.0, y1);
    if (crossings == kernel::kMaxCrossingsPerSegment) {
      y = y1;
      return crossings;
    }
    const double d = model.deflection(y), d1 = model.deflection(y1);
    const double m0 = Hr * model.deflection_rate(y), m1 = Hr * model.deflection_rate(y1);
    const double c2 = 3.0 * (d1 - d) - 2.0 * m0 - m1, c3 = 2.0 * (d - d1) + m0 + m1;
    const double e0 = detail::line(u0, in.start.error, in.end.error), de = rest * (in.end.error - in.start.error);
    // Far from both flanks (the band of the end values widened by the most a cubic Hermite can
    // overshoot them, 4/27 (|m0| + |m1|) taken as 1/4, and by e's change) no root can exist: the
    // step is the branch step, as the root search below would find.
    {
      const double reach = 0.25 * (std::fabs(m0) + std::fabs(m1)) + std::fabs(de);
      const double lo = std::fmin(d, d1) - e0 - reach, hi = std::fmax(d, d1) - e0 + reach;
      if ((lo > in.b || hi < -in.b || (lo > -in.b && hi < in.b)) && s == branch_of(d1, e0 + de, in.b)) {
        y = y1;
        return crossings;
      }
    }
    Boundary bnd[2];
    const int nb = boundaries(s, in.b, bnd);
    double w = -1.0;
    int hit = -1;
    for (int k = 0; k < nb; ++k) {
      const double sd = bnd[k].side;
      // A state restarted on a boundary may sit 1e-15 b beyond it: counted as on it (the torsional
      // segment puts it there exactly).
      const double gap = std::fmax(0.0, sd * (d - (bnd[k].level + e0)));
      const double wk = first_negative_root(gap, sd * (m0 - de), sd * c2, sd * c3);
      if (wk > 0.0 && (w < 0.0 || wk < w)) w = wk, hit = k;
    }
    if (hit < 0) {
      y = y1;
      return crossings;
    }
    // Newton on the step length w: deflection(w) - level(w) = 0, slope Hr deflection_rate - de.
    const Boundary& B = bnd[hit];
    State yw = y;
    double level = B.level + e0, dw = d;
    for (int it = 0; it < 8; ++it) {
      yw = y;
      step(w, yw);
      level = B.level + std::fma(w, de, e0);
      dw = model.deflection(yw);
      const double f = dw - level, slope = Hr * model.deflection_rate(yw) - de;
      if (std::fabs(f) <= 1e-15 * in.b || slope == 0.0) break;
      const double next = std::fmin(1.0, std::fmax(0.0, w - f / slope));
      if (next == w) break;
      w = next;
    }
    if (w >= 1.0 && B.side * (dw - level) >= 0.0) {  // the step itself stays on the branch
      y = yw;
      return crossings;
    }
    y = yw;  // on the boundary within the Newton tolerance (1e-15 b): no projection, the state is the model's
    s = B.beyond;
    u0 = w >= 1.0 ? 1.0 : u0 + w * rest;
    if (u0 >= 1.0) return crossings + 1;
  }
}

}  // namespace gear_dynamics::model_step
