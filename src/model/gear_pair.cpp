#include "gear_dynamics/model/gear_pair.hpp"

#include <algorithm>
#include <cmath>

namespace gear_dynamics {

namespace {
constexpr double kPi = 3.14159265358979323846;
constexpr double kIsoReferenceModulus = 2.06e11;  // E of ISO 6336-1's reference steel [Pa]
constexpr double kIsoGearBlankFactor = 1.0;       // C_R: solid disc
constexpr double kIsoCorrectionFactor = 0.8;      // C_M: theoretical to measured
constexpr double kNPerMmUmToNPerM2 = 1e9;         // 1 N/(mm um) = 1e9 N/m^2
}  // namespace

GearPair derive(const GearInputs& in) {
  GearPair g;
  g.in = in;
  const double r1 = in.pinion_pitch_radius, r2 = in.gear_pitch_radius;
  const double a0 = in.pressure_angle;
  const double z1 = in.pinion_teeth, z2 = in.gear_teeth;

  g.module = 2.0 * r1 / z1;
  g.base_radius1 = r1 * std::cos(a0);
  g.base_radius2 = r2 * std::cos(a0);
  g.tip_radius1 = r1 + in.addendum_coefficient * g.module;
  g.tip_radius2 = r2 + in.addendum_coefficient * g.module;
  g.root_radius1 = r1 - in.dedendum_coefficient * g.module;
  g.root_radius2 = r2 - in.dedendum_coefficient * g.module;
  g.base_pitch = kPi * g.module * std::cos(a0);
  g.line_of_centres_length = (r1 + r2) * std::sin(a0);
  g.operating_pressure_angle = a0;
  const double x1 = in.profile_shift1, x2 = in.profile_shift2;
  if (x1 != 0.0 || x2 != 0.0) {  // the unshifted teeth keep the arithmetic above, bit for bit
    g.tip_radius1 = r1 + (in.addendum_coefficient + x1) * g.module;
    g.tip_radius2 = r2 + (in.addendum_coefficient + x2) * g.module;
    g.root_radius1 = r1 - (in.dedendum_coefficient - x1) * g.module;
    g.root_radius2 = r2 - (in.dedendum_coefficient - x2) * g.module;
    // The pair meshes without backlash change at the centre distance where
    // inv(alpha_w) = inv(alpha0) + 2 tan(alpha0) (x1 + x2) / (Z1 + Z2); Newton on inv.
    const double target = std::tan(a0) - a0 + 2.0 * std::tan(a0) * (x1 + x2) / (z1 + z2);
    double aw = a0;
    for (int it = 0; it < 50; ++it) {
      const double t = std::tan(aw), step = (t - aw - target) / (t * t);
      aw -= step;
      if (std::fabs(step) < 1e-16) break;
    }
    g.operating_pressure_angle = aw;
    g.line_of_centres_length = (g.base_radius1 + g.base_radius2) * std::tan(aw);
  }

  const double tip_arm1 = std::sqrt(g.tip_radius1 * g.tip_radius1 - g.base_radius1 * g.base_radius1);
  const double tip_arm2 = std::sqrt(g.tip_radius2 * g.tip_radius2 - g.base_radius2 * g.base_radius2);
  g.contact_ratio = (tip_arm1 + tip_arm2 - g.line_of_centres_length) / g.base_pitch;
  g.x_e = tip_arm1;
  g.x_a = g.line_of_centres_length - tip_arm2;
  g.x_b = g.x_e - g.base_pitch;
  g.x_d = g.x_a + g.base_pitch;
  g.x_p = g.base_radius1 * std::tan(g.operating_pressure_angle);

  g.inertia1 = 0.5 * in.density * kPi * std::pow(r1, 4) * in.face_width;
  g.inertia2 = 0.5 * in.density * kPi * std::pow(r2, 4) * in.face_width;
  g.half_tooth_angle1 = kPi / (2.0 * z1) + std::tan(a0) - a0;

  const double rb1 = g.base_radius1, rb2 = g.base_radius2, j1 = g.inertia1, j2 = g.inertia2;
  g.q2 = rb1 * rb1 / j1 - rb1 * rb2 / j2;
  g.q3 = rb1 * rb1 / j1 + rb2 * rb2 / j2;
  g.q1 = a0 * g.q3 + g.half_tooth_angle1 * g.q2;
  g.equivalent_mass = 1.0 / g.q3;
  g.c0 = g.line_of_centres_length * rb2 / j2;
  g.c1 = rb1 / j1 - rb2 / j2;

  g.mesh_period_angle = 2.0 * kPi / z1;
  g.single_pair_angle = (2.0 - g.contact_ratio) * g.mesh_period_angle;

  // ISO 6336-1:2006 method B, spur (beta = 0).
  double q_prime = 0.04723 + 0.15551 / z1 + 0.25791 / z2;
  if (x1 != 0.0 || x2 != 0.0)  // ISO 6336-1 Table 7's profile-shift terms
    q_prime += -0.00635 * x1 - 0.11654 * x1 / z1 - 0.00193 * x2 - 0.24188 * x2 / z2 + 0.00529 * x1 * x1 +
               0.00182 * x2 * x2;
  const double c_th = 1.0 / q_prime;
  const double basic_rack_factor = (1.0 + 0.5 * (1.2 - in.dedendum_coefficient)) *
                                   (1.0 - 0.02 * (20.0 - a0 * 180.0 / kPi));  // C_B
  g.iso_single_stiffness = c_th * kIsoCorrectionFactor * kIsoGearBlankFactor * basic_rack_factor *
                           (in.youngs_modulus / kIsoReferenceModulus);
  g.iso_mesh_stiffness = g.iso_single_stiffness * (0.75 * g.contact_ratio + 0.25);
  g.k1 = g.iso_single_stiffness * kNPerMmUmToNPerM2 * in.face_width;
  g.k_mean = g.iso_mesh_stiffness * kNPerMmUmToNPerM2 * in.face_width;
  g.k2 = (g.k_mean - (2.0 - g.contact_ratio) * g.k1) / (g.contact_ratio - 1.0);

  g.damping_coefficient = 2.0 * in.damping_ratio * std::sqrt(g.k_mean * g.equivalent_mass) *
                          g.k_mean / in.reference_load;
  return g;
}

double GearPair::max_contact_frequency(double mu) const {
  const double f_max = std::max(friction_factor(0.0), friction_factor(mesh_period_angle));
  const double q_max = q3 + std::max(mu, 0.0) * f_max;
  return std::sqrt(q_max * std::max(k1, k2));
}

double first_mesh_period_start(const GearPair& gear) {
  return gear.in.mesh_phase == 0.0 ? 0.0 : (gear.mesh_period_angle - gear.in.mesh_phase) / gear.in.pinion_speed;
}

}  // namespace gear_dynamics
