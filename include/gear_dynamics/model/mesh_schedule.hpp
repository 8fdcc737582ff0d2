// Kinematic mesh timing (doc/model.md D3): the mesh phase, the stiffness K(phi) and the friction
// factor f(phi) as known functions of time, and how each integration step is split at the
// stiffness switches (doc/model.md §5). Shared by every realization of a block.
#pragma once

#include <array>
#include <cstdint>

#include "gear_dynamics/model/gear_pair.hpp"

namespace gear_dynamics {

// A piece [begin, end] (fractions of h) of one integration step with constant stiffness.
struct StepSegment {
  double begin = 0.0, end = 1.0;
  double stiffness = 0.0;  // K on the open segment [N/m]
  // Friction factor f at the RK4 stage times: segment start, midpoint, end [1/kg]. An unsplit
  // step evaluates it at the stage times; a split sub-step freezes it at its midpoint.
  double friction_start = 0.0, friction_mid = 0.0, friction_end = 0.0;
};

struct StepPlan {
  int segments = 1;
  std::array<StepSegment, 3> segment;  // a step holds at most two switches (checked at load)
};

class MeshSchedule {
 public:
  MeshSchedule(const GearPair& gear, double time_step);

  // How to integrate grid step n, i.e. [n h, (n+1) h].
  StepPlan plan(std::int64_t n) const;

  double phase(double t) const;      // phi(t) in [0, phi_n) [rad]
  double stiffness(double t) const;  // K(phi(t)) [N/m]

 private:
  double angle(double t) const { return phase0_ + speed_ * t; }  // unwrapped phi0 + Omega t
  double stiffness_at_local(double phi) const { return phi < single_ ? k1_ : k2_; }

  GearPair gear_;
  double h_, phase0_, speed_, period_, single_, k1_, k2_;
};

}  // namespace gear_dynamics
