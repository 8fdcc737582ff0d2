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

}  // namespace gear_dynamics
