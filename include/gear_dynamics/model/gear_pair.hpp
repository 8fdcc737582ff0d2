// Spur gear pair: the inputs of doc/model.md §3 and every quantity derived from them.
// SI units throughout (m, kg, s, N, rad). No ROS.
#pragma once

#include <algorithm>
#include <cmath>
#include <vector>

namespace gear_dynamics {

// How the mesh stiffness K(theta1) is obtained (doc/model.md §3): the paper's two ISO 6336 levels,
// or the tooth geometry by the potential-energy method (model/tooth_stiffness.hpp).
enum class MeshStiffnessModel { kSquareWave, kPotentialEnergy };
// The sign of the friction force: the paper's, constant (D5), or reversed at the pitch point, where
// the sliding velocity changes sign (doc/model.md §2).
enum class FrictionDirection { kConstant, kReversing };
// The law of the friction coefficient (model/friction_law.hpp, doc/model.md §2 "Friction laws"): the
// lane's constant mu, or a law per tooth pair from its speeds, curvature and load.
enum class FrictionModel { kConstant, kBenedictKelley, kXu, kIsoTr13989 };
enum class FaultyGear { kNone, kPinion, kWheel };
// Which model of the pair the engine steps (doc/model.md §11): the one-degree-of-freedom torsional
// model, or the pair with the translations of both gears on their bearings.
enum class GearModel { kTorsional, kBearings };

// A root crack in one tooth (Chaari, Fakhfakh & Haddar 2009): a straight crack that starts at the
// root of the tooth's contact side and runs at `angle` to the tooth's centre line, `depth` long.
struct RootCrack {
  FaultyGear gear = FaultyGear::kNone;
  int tooth = 0;                       // index of the tooth: tooth 0 is in pair 0 (doc/model.md §3)
  double depth = 0.0;                  // q [m]
  double angle = 0.7853981633974483;   // upsilon [rad] (45 deg)
};

// A spall (pit) on one tooth's flank: a rectangle of the face where the teeth do not touch.
struct Spall {
  FaultyGear gear = FaultyGear::kNone;
  int tooth = 0;
  double length = 0.0;    // extent along the line of action [m]
  double width = 0.0;     // extent across the face [m], at most the face width
  double position = 0.0;  // radius of its centre on the faulty tooth [m]
};

// Static transmission error: the deviation of each tooth's profile from the true involute along
// the line of action [m] (positive: material added), constant over the tooth. Teeth beyond the
// lists' ends are true.
struct ProfileErrors {
  std::vector<double> pinion, wheel;
};

// What a user sets (paper Table 1 plus doc/model.md's assumed values).
struct GearInputs {
  double density = 7800.0;             // rho [kg/m^3]
  double youngs_modulus = 2.068e11;    // E [Pa]
  double poisson_ratio = 0.3;          // nu [-] (doc/model.md D6; not used by ISO 6336 method B)
  double pinion_pitch_radius = 0.020;  // r1 [m]
  double gear_pitch_radius = 0.080;    // r2 [m]
  double pressure_angle = 0.3490658503988659;  // alpha0 [rad] (20 deg)
  int pinion_teeth = 20;               // Z1
  int gear_teeth = 80;                 // Z2
  double face_width = 0.010;           // L [m]
  double backlash = 5.0e-5;            // b [m], half clearance (doc/model.md D7)
  double addendum_coefficient = 1.0;   // h_a / m
  double dedendum_coefficient = 1.25;  // h_f / m
  double pinion_speed = 104.71975511965977;  // Omega [rad/s] (1000 rpm)
  double damping_ratio = 0.09;         // zeta_ref [-] at the reference load
  double reference_load = 1000.0;      // F_ref [N]
  double mesh_phase = 0.0;             // phi0 [rad], initial mesh phase in [0, phi_n)
  double profile_shift1 = 0.0;         // x1 [-], pinion profile shift coefficient
  double profile_shift2 = 0.0;         // x2 [-], wheel profile shift coefficient
  double bore_radius1 = 0.008;         // pinion bore (shaft) radius [m], for the fillet foundation
  double bore_radius2 = 0.030;         // wheel bore radius [m]
  MeshStiffnessModel mesh_stiffness = MeshStiffnessModel::kSquareWave;
  FrictionDirection friction_direction = FrictionDirection::kConstant;
  FrictionModel friction_model = FrictionModel::kConstant;
  double friction_load = 1000.0;        // W [N]: the static mesh force a friction law is evaluated at
  double oil_viscosity = 0.023;         // eta [Pa s]: ISO VG 100 mineral oil at 70 C
  double surface_roughness = 0.4e-6;    // Ra [m]: composite roughness of ground flanks
  RootCrack crack;
  Spall spall;
  ProfileErrors profile_errors;
  GearModel model = GearModel::kTorsional;
  double bearing_stiffness = 1.0e8;     // k_b [N/m], each body and direction (bearings model)
  double bearing_damping_ratio = 0.05;  // zeta_b [-]: c = 2 zeta_b sqrt(k_b m)
  double pinion_mass = 0.0;             // m_p [kg]; 0: a solid disc of the pitch radius, rho pi r1^2 L
  double wheel_mass = 0.0;              // m_g [kg]; 0: rho pi r2^2 L
};

// Derived quantities, named as in doc/model.md §3.
struct GearPair {
  GearInputs in;
  double module;                 // m [m]
  double base_radius1, base_radius2;        // Rb1, Rb2 [m]
  double tip_radius1, tip_radius2;          // ra1, ra2 [m]
  double root_radius1, root_radius2;        // rf1, rf2 [m]
  double base_pitch;             // pb [m]
  double line_of_centres_length; // lp = C1C2 [m]
  double operating_pressure_angle;  // alpha_w [rad]: alpha0, unless x1 + x2 != 0
  double contact_ratio;          // epsilon_alpha [-]
  double x_a, x_b, x_p, x_d, x_e;  // contact points from C1 along the line of action [m]
  double inertia1, inertia2;     // J1, J2 [kg m^2]
  double half_tooth_angle1;      // theta_b1 [rad]
  double q1, q2, q3;             // paper Eqs. 12-14 [1/kg]
  double equivalent_mass;        // m_e = 1/q3 [kg]
  double c0, c1;                 // friction factor f = c0 + c1 X1 [1/kg], [1/(kg m)]
  double mesh_period_angle;      // phi_n [rad]
  double single_pair_angle;      // phi_m [rad]
  double iso_single_stiffness;   // c' [N/(mm um)]
  double iso_mesh_stiffness;     // c_gamma_alpha [N/(mm um)]
  double k1, k_mean, k2;         // mesh stiffness levels [N/m]
  double damping_coefficient;    // alpha [N s/m^2]

  // Natural frequency sqrt(Q K) of the contact for the largest Q at friction mu [rad/s].
  double max_contact_frequency(double mu) const;
  // Friction factor f(phi) at local mesh phase phi in [0, phi_n].
  double friction_factor(double phi) const { return c0 + c1 * (x_b + base_radius1 * phi); }
  // Mesh frequency f_m = Omega / phi_n: tooth pairs per second [Hz].
  double mesh_frequency() const { return in.pinion_speed / mesh_period_angle; }
};

// The mesh period phi_n / Omega [s].
inline double mesh_period(const GearPair& gear) { return gear.mesh_period_angle / gear.in.pinion_speed; }

// The first time t >= 0 at which the mesh phase (phi0 + Omega t mod phi_n) is 0, i.e. a mesh period
// starts: 0 if phi0 = 0, else (phi_n - phi0) / Omega [s]. The Poincare sections sample there, then
// every mesh period phi_n / Omega (doc/nonlinear-dynamics.md §3).
double first_mesh_period_start(const GearPair& gear);

// Mesh force F_c = K g(delta - e) + alpha |g| (delta_dot - e_dot) [N] (doc/model.md §2, without the
// friction factor), g(x) = x - clamp(x, -b, b) the tooth deflection beyond the backlash, e and e_dot
// the static transmission error and its rate (MeshSchedule): the force the kernel integrates, and
// the quantity whose spectrum gear_analyze and the live node's spectrum topic show.
inline double mesh_force(const GearPair& gear, double stiffness, double delta, double delta_dot, double error = 0.0,
                         double error_rate = 0.0) {
  const double b = gear.in.backlash;
  const double x = delta - error;
  const double g = x - std::min(std::max(x, -b), b);  // as kernel::clamp
  return stiffness * g + (gear.damping_coefficient * std::abs(g)) * (delta_dot - error_rate);
}

// Computes every derived quantity by doc/model.md's formulas. Does not validate (see config.hpp).
GearPair derive(const GearInputs& in);

}  // namespace gear_dynamics
