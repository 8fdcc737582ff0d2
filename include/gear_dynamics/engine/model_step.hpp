// The model seam of the engine (doc/architecture.md): a gear model is a state vector, its right-hand
// side on each smooth branch of the backlash function, and the mesh deflection as a linear function
// of the state whose crossings of +-b (shifted by the transmission error e) are located. This file
// steps any such model by RK4 through one MeshSchedule plan, every crossing located by the one
// crossing search of located_segment.hpp (kernel::located::locate_crossings), the torsional kernel's
// too: a branch step, its cubic Hermite dense output of the deflection, Newton on the step's own
// length, a restart on the branch beyond. So the method keeps RK4's fourth order through impacts
// whatever the model.
//
// A Model provides:
//   static constexpr int kStates;                 // size of the state
//   using State = Eigen::Matrix<double, kStates, 1>;
//   double deflection(const State&) const;        // the mesh deflection, linear in the state [m]
//   double deflection_rate(const State&) const;   // its time derivative (the same linear map of dy/dt)
//   State derivative(int branch, const State&, const MeshPoint&) const;  // dy/dt on `branch`,
//                                                 // smoothly continued past its boundaries
// This path is scalar; each model's SIMD kernel for the ensemble's lanes (rk4_kernel.hpp,
// src/engine/dispatched/bearings_step.cpp) calls it for the lanes that may reach a boundary.
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
// (at most kernel::kMaxCrossingsPerSegment; past it the rest stays on its branch): the crossing
// search of located_segment.hpp on this model's RK4 step. Returns the crossings located.
template <class M>
inline int located_segment(const M& model, const Segment& in, typename M::State& y) {
  using State = typename M::State;
  // The branch step over [u0, u0 + w (1 - u0)]; the whole segment uses its own midpoint.
  const auto step = [&](int s, double u0, double w, State& yy) {
    const double rest = 1.0 - u0;
    const double u1 = w == 1.0 ? 1.0 : u0 + w * rest;
    const bool whole = u0 == 0.0 && u1 == 1.0;
    const MeshPoint pm = whole ? in.mid : detail::point_at(in, 0.5 * (u0 + u1));
    detail::branch_rk4(model, s, w == 1.0 ? rest * in.H : w * (rest * in.H), detail::point_at(in, u0), pm,
                       detail::point_at(in, u1), yy);
  };
  return kernel::located::locate_crossings(
      in.H, in.b, in.start.error, in.end.error, y, step, [&](const State& x) { return model.deflection(x); },
      [&](const State& x) { return model.deflection_rate(x); }, nullptr);
}

}  // namespace gear_dynamics::model_step
