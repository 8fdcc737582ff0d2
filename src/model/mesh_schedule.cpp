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
      k2_(gear.k2) {
  if (!is_paper_mesh(gear.in)) table_ = shared_mesh_table(gear);
}

double MeshSchedule::phase(double t) const {
  const double a = angle(t);
  return a - std::floor(a / period_) * period_;
}

double MeshSchedule::stiffness(double t) const { return stiffness_at_angle(angle(t)); }

double MeshSchedule::stiffness_at_angle(double a) const {
  return table_ ? table_->at(table_angle(a)).stiffness : stiffness_at_local(a - std::floor(a / period_) * period_);
}

double MeshSchedule::transmission_error(double t) const {
  return table_ ? table_->at(table_angle(angle(t))).error : 0.0;
}

double MeshSchedule::transmission_error_rate(double t) const {
  if (!table_) return 0.0;
  const double a = table_angle(angle(t));
  return table_->error_slope(table_->piece_of(a), a) * speed_;
}

// The table's local angle of a, a billionth of a step past it: at a jump that falls on a sample
// time (a mesh period is often a whole number of steps) the value after it, whatever the rounding
// of a.
double MeshSchedule::table_angle(double a) const {
  const double P = table_->period();
  const double local = a - std::floor(a / P) * P + 1e-9 * speed_ * h_;
  return local >= P ? local - P : local;
}

// The step [a0, a1] (unwrapped angles) cut at the table's jumps inside it; each segment takes K, f
// and e at its ends and midpoint from the piece it lies in (one-sided at a jump).
StepPlan MeshSchedule::plan_from_table(double a0, double a1) const {
  const MeshTable& T = *table_;
  const double P = T.period();
  const double wrap = std::floor(a0 / P) * P;
  const double l0 = a0 - wrap, l1 = a1 - wrap;  // l1 may pass P: the next schedule period
  const std::vector<double>& br = T.breaks();
  const int np = T.pieces();
  // A jump within a billionth of a step of a grid point counts as on it (no sliver sub-steps).
  const double tol = 1e-9 * (l1 - l0);
  std::array<double, 4> edges{l0, 0.0, 0.0, 0.0};
  int ncuts = 0;
  for (int k = T.piece_of(l0) + 1; ncuts < 2; ++k) {
    const double c = k <= np ? br[k] : P + br[k - np];
    if (c >= l1 - tol) break;
    if (c > l0 + tol) edges[++ncuts] = c;
  }
  edges[ncuts + 1] = l1;
  StepPlan p;
  p.segments = ncuts + 1;
  for (int i = 0; i < p.segments; ++i) {
    const double x0 = edges[i], x1 = edges[i + 1], mid = 0.5 * (x0 + x1);
    const double shift = mid >= P ? P : 0.0;
    const int piece = T.piece_of(mid - shift);
    const MeshTable::Values v0 = T.at(piece, x0 - shift), vm = T.at(piece, mid - shift), v1 = T.at(piece, x1 - shift);
    StepSegment& s = p.segment[i];
    s.begin = i == 0 ? 0.0 : (x0 - l0) / (l1 - l0);
    s.end = i + 1 == p.segments ? 1.0 : (x1 - l0) / (l1 - l0);
    s.stiffness_start = v0.stiffness, s.stiffness_mid = vm.stiffness, s.stiffness_end = v1.stiffness;
    s.friction_start = v0.friction, s.friction_mid = vm.friction, s.friction_end = v1.friction;
    s.error_start = v0.error, s.error_end = v1.error;
    p.excited = p.excited || s.error_start != 0.0 || s.error_end != 0.0;
  }
  return p;
}

}  // namespace gear_dynamics
