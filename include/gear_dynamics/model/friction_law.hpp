// Friction-coefficient laws (doc/model.md §2 "Friction laws"): the table of the laws a spur pair's
// tooth friction may follow, each a function of one contact's kinematics, curvature and load.
// Adding a law is one row of friction_laws() (doc/architecture.md, "A friction law").
#pragma once

#include <string>
#include <vector>

#include "gear_dynamics/model/gear_pair.hpp"

namespace gear_dynamics {

// The contact of one tooth pair at x along the line of action, carrying `load` [N] (SI units).
struct ContactKinematics {
  double x = 0.0;                  // distance from the pinion's base tangent point [m]
  double rolling1 = 0.0;           // u1 = Omega1 rho1, the pinion surface's speed along the profile [m/s]
  double rolling2 = 0.0;           // u2 = Omega2 rho2 [m/s]
  double sliding = 0.0;            // |u1 - u2| [m/s]
  double sum_speed = 0.0;          // u1 + u2 [m/s]
  double radius1 = 0.0, radius2 = 0.0;  // rho1 = x, rho2 = lp - x: involute radii of curvature [m]
  double reduced_radius = 0.0;     // R = rho1 rho2 / (rho1 + rho2) [m]
  double load = 0.0;               // W [N]
  double load_per_width = 0.0;     // W' = W / L [N/m]
  double hertz_pressure = 0.0;     // p_h = sqrt(W' E' / (2 pi R)), E' = E / (1 - nu^2) [Pa]
};

ContactKinematics contact_kinematics(const GearPair& gear, double x, double load);

struct FrictionLaw {
  const char* name;         // the value of gear_pair.friction_model
  const char* description;  // one line for the parameter docs
  // mu of one contact (>= 0); nullptr for `constant`, the lane's mu itself.
  double (*coefficient)(const GearPair& gear, const ContactKinematics& contact);
};

// Every law, in the order of FrictionModel.
const std::vector<FrictionLaw>& friction_laws();
std::vector<std::string> friction_model_names();

// The slide-to-roll ratio 2 |u1 - u2| / (u1 + u2) below which Benedict-Kelley is evaluated at this
// ratio: the law's log diverges at the pitch point, where no sliding film shear is left to model.
constexpr double kMinSlideToRoll = 0.05;
// A law's mu enters Q = q3 + mu_lane f scaled by mu_lane / kLawReferenceMu, so that the lane's
// default mu (the paper's 0.04) gives the law as published and a batch's mu axis scales it.
constexpr double kLawReferenceMu = 0.04;

// mu of the pair at x carrying `load`, by gear.in.friction_model (not `constant`).
double law_friction_coefficient(const GearPair& gear, double x, double load);

// The pair's weight in f and sigma under a law: its share of the force, times its mu at its share of
// friction_load over kLawReferenceMu, signed by its sliding velocity if friction_direction reverses
// (x_mid: a point of the same side of the pitch point).
double pair_friction_weight(const GearPair& gear, double x, double x_mid, double share);

// Where gear.in's friction law is used outside its published range (one line each, naming the key
// and the range); empty for `constant`.
std::vector<std::string> friction_law_warnings(const GearPair& gear);

}  // namespace gear_dynamics
