#include "gear_dynamics/model/mesh_schedule.hpp"

#include <cmath>

namespace gear_dynamics {

MeshSchedule::MeshSchedule(const GearPair& gear, double time_step)
    : gear_(gear),
      h_(time_step),
      phase0_(gear.in.mesh_phase),
      speed_(gear.in.pinion_speed),
      period_(gear.mesh_period_angle),
      single_(gear.single_pair_angle),
      k1_(gear.k1),
      k2_(gear.k2) {}

double MeshSchedule::phase(double t) const {
  const double a = angle(t);
  return a - std::floor(a / period_) * period_;
}

double MeshSchedule::stiffness(double t) const { return stiffness_at_local(phase(t)); }

StepPlan MeshSchedule::plan(std::int64_t n) const {
  StepPlan p;
  const double a0 = angle(static_cast<double>(n) * h_);
  const double a1 = angle(static_cast<double>(n + 1) * h_);

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
    s.stiffness = stiffness_at_local(local(mid, cycle));
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
    s.stiffness = stiffness_at_local(local(mid, cycle));
    s.friction_start = s.friction_mid = s.friction_end = gear_.friction_factor(local(mid, cycle));
  }
  p.segment[0].begin = 0.0;
  p.segment[p.segments - 1].end = 1.0;
  return p;
}

}  // namespace gear_dynamics
