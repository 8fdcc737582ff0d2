// Kinematic mesh timing (doc/model.md D3): the mesh phase, the stiffness K, the friction factor f
// and the static transmission error e as known functions of time, and how each integration step is
// split at their jumps (doc/model.md §5). Shared by every realization of a block.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <memory>

#include "gear_dynamics/model/gear_pair.hpp"
#include "gear_dynamics/model/mesh_table.hpp"

namespace gear_dynamics {

// A piece [begin, end] (fractions of h) of one integration step on which K, f and e are smooth.
struct StepSegment {
  double begin = 0.0, end = 1.0;
  // K at the RK4 stage times: segment start, midpoint, end [N/m] (one value on the paper's mesh).
  double stiffness_start = 0.0, stiffness_mid = 0.0, stiffness_end = 0.0;
  // Friction factor f at the stage times [1/kg]. On the paper's mesh an unsplit step evaluates it
  // at the stage times and a split sub-step freezes it at its midpoint.
  double friction_start = 0.0, friction_mid = 0.0, friction_end = 0.0;
  // Static transmission error at the segment's start and end [m], a straight line between.
  double error_start = 0.0, error_end = 0.0;
};

struct StepPlan {
  int segments = 1;
  bool excited = false;  // a static transmission error: some segment's error is not 0
  std::array<StepSegment, 3> segment;  // a step holds at most two switches (checked at load)
};

class MeshSchedule {
 public:
  MeshSchedule(const GearPair& gear, double time_step);

  // How to integrate grid step n, i.e. [n h, (n+1) h]. Inline (below): the one-lane path steps
  // one realization per plan, where a call per step would cost as much as its arithmetic.
  inline StepPlan plan(std::int64_t n) const;

  double phase(double t) const;      // phi(t) in [0, phi_n) [rad]
  // K(t) [N/m] and e(t) [m]; on a table, the values just after t (after a jump at t).
  double stiffness(double t) const;
  double transmission_error(double t) const;
  // de/dt at t [m/s], just after t: the e_dot with which the kernel damps delta_dot - e_dot.
  double transmission_error_rate(double t) const;
  // K at the unwrapped pinion angle a = phi0 + Omega t, i.e. theta1 from the model's theta1 = 0.
  double stiffness_at_angle(double a) const;
  // The table behind a mesh that is not the paper's (null on the paper's).
  const MeshTable* table() const { return table_.get(); }

 private:
  double angle(double t) const { return phase0_ + speed_ * t; }  // unwrapped phi0 + Omega t
  double stiffness_at_local(double phi) const { return phi < single_ ? k1_ : k2_; }
  StepPlan plan_from_table(double a0, double a1) const;
  double table_angle(double a) const;

  GearPair gear_;
  double h_, phase0_, speed_, period_, single_, k1_, k2_;
  std::shared_ptr<const MeshTable> table_;
};

inline StepPlan MeshSchedule::plan(std::int64_t n) const {
  const double a0 = angle(static_cast<double>(n) * h_);
  const double a1 = angle(static_cast<double>(n + 1) * h_);
  if (table_) return plan_from_table(a0, a1);
  StepPlan p;

  // Switch angles strictly inside the step. One that falls within a billionth of a step of a grid
  // point counts as on the grid point, so rounding never creates a sliver sub-step.
  std::array<double, 3> cuts{};
  int ncuts = 0;
  if (speed_ > 0.0) {
    const double tol = 1e-9 * (a1 - a0);
    const double first_cycle = std::floor(a0 / period_);
    for (double c = first_cycle; c * period_ < a1 && ncuts < 2; c += 1.0) {
      for (double s : {c * period_, c * period_ + single_}) {
        if (s > a0 + tol && s < a1 - tol && ncuts < 2) cuts[ncuts++] = s;
      }
    }
  }

  const auto local = [&](double a, double cycle) { return a - cycle * period_; };
  if (ncuts == 0) {
    const double mid = 0.5 * (a0 + a1);
    const double cycle = std::floor(mid / period_);
    StepSegment& s = p.segment[0];
    s.stiffness_start = s.stiffness_mid = s.stiffness_end = stiffness_at_local(local(mid, cycle));
    s.friction_start = gear_.friction_factor(local(a0, cycle));
    s.friction_mid = gear_.friction_factor(local(mid, cycle));
    s.friction_end = gear_.friction_factor(local(a1, cycle));
    return p;
  }

  std::array<double, 4> edges{a0, 0.0, 0.0, 0.0};
  for (int i = 0; i < ncuts; ++i) edges[i + 1] = cuts[i];
  edges[ncuts + 1] = a1;
  p.segments = ncuts + 1;
  for (int i = 0; i < p.segments; ++i) {
    const double mid = 0.5 * (edges[i] + edges[i + 1]);
    const double cycle = std::floor(mid / period_);
    StepSegment& s = p.segment[i];
    s.begin = (edges[i] - a0) / (a1 - a0);
    s.end = (edges[i + 1] - a0) / (a1 - a0);
    s.stiffness_start = s.stiffness_mid = s.stiffness_end = stiffness_at_local(local(mid, cycle));
    s.friction_start = s.friction_mid = s.friction_end = gear_.friction_factor(local(mid, cycle));
  }
  p.segment[0].begin = 0.0;
  p.segment[p.segments - 1].end = 1.0;
  return p;
}

}  // namespace gear_dynamics
