// The gear pair as a URDF robot description (doc/gear_simulator.md §3.3), drawn at the configured
// gear: what robot_state_publisher turns gear_simulator's joint states into TF and rviz draws.
#pragma once

#include <string>

#include "gear_dynamics/model/gear_pair.hpp"

namespace gear_dynamics {

// The working pitch radius of each gear, Rb / cos(alpha_w): the circles that roll on each other at
// the working centre distance (the reference pitch radii r1, r2 unless the profile shifts change
// alpha_w) [m].
double working_pitch_radius1(const GearPair& gear);
double working_pitch_radius2(const GearPair& gear);

// The URDF: the link gear_pair (the housing, the pinion's axis at its origin, x towards the
// wheel's), the links pinion and wheel (cylinders of the working pitch radii and the face width,
// each with a mark on its rim a module thick, on the face towards +z) on the continuous joints
// pinion_joint (about +z, at the origin) and wheel_joint (about -z, the working centre distance
// along x).
std::string gear_pair_urdf(const GearPair& gear);

}  // namespace gear_dynamics
