#include "gear_dynamics/model/friction_law.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>

namespace gear_dynamics {

namespace {

constexpr double kPi = 3.14159265358979323846;

// Benedict & Kelley (1961) in the units of its fit: W' [lb/in], nu0 [cP], V [in/s], S [micro-inch];
// C_R = 50 / (50 - S) the roughness factor; V_e the sum of the rolling speeds.
double benedict_kelley(const GearPair& g, const ContactKinematics& c) {
  constexpr double kInch = 0.0254, kPoundForce = 4.4482216152605;
  const double w = c.load_per_width * kInch / kPoundForce;
  const double nu0 = g.in.oil_viscosity * 1e3;
  const double ve = c.sum_speed / kInch;
  const double vs = std::max(c.sliding, 0.5 * kMinSlideToRoll * c.sum_speed) / kInch;
  const double s = g.in.surface_roughness / (1e-6 * kInch);
  const double cr = 50.0 / (50.0 - s);
  return std::max(0.0, 0.0127 * cr * std::log10(3.17e8 * w / (nu0 * vs * ve * ve)));
}

// Xu, Kahraman, Anderson & Maddock (2007), the regression of their EHL runs: P_h [GPa], nu0 [cP],
// S [um], V_e = (u1 + u2) / 2 [m/s], R [m], SR = |u1 - u2| / V_e.
double xu(const GearPair& g, const ContactKinematics& c) {
  constexpr double b1 = -8.916465, b2 = 1.03303, b3 = 1.036077, b4 = -0.354068, b5 = 2.812084,
                   b6 = -0.100601, b7 = 0.752755, b8 = -0.390958, b9 = 0.620305;
  const double ph = c.hertz_pressure * 1e-9, nu0 = g.in.oil_viscosity * 1e3, s = g.in.surface_roughness * 1e6;
  const double ve = 0.5 * c.sum_speed, sr = c.sliding / ve;
  const double a = sr * ph * std::log10(nu0);
  const double f = b1 + b4 * a + b5 * std::exp(-a) + b9 * std::exp(s);
  return std::exp(f) * std::pow(ph, b2) * std::pow(sr, b3) * std::pow(ve, b6) * std::pow(nu0, b7) *
         std::pow(c.reduced_radius, b8);
}

// ISO/TR 13989-2 (integral temperature method), the mean coefficient of the mesh at the pitch point C:
// mu_mC = 0.060 (w_Bt K_Bgamma / (v_SigmaC rho_redC))^0.2 eta^-0.05 Ra^0.25 X_L with w_Bt [N/mm] the
// whole mesh force per face width, v_SigmaC [m/s], rho_redC [mm], eta [mPa s], Ra [um]; spur gears
// (K_Bgamma = 1) and a mineral oil (X_L = 1). One value for every contact of the cycle.
double iso_tr_13989(const GearPair& g, const ContactKinematics& c) {
  (void)c;
  const ContactKinematics p = contact_kinematics(g, g.x_p, g.in.friction_load);
  const double w = p.load_per_width * 1e-3, rho = p.reduced_radius * 1e3;
  return 0.060 * std::pow(w / (p.sum_speed * rho), 0.2) * std::pow(g.in.oil_viscosity * 1e3, -0.05) *
         std::pow(g.in.surface_roughness * 1e6, 0.25);
}

}  // namespace

ContactKinematics contact_kinematics(const GearPair& g, double x, double load) {
  ContactKinematics c;
  const double omega1 = g.in.pinion_speed, omega2 = omega1 * g.base_radius1 / g.base_radius2;
  c.x = x;
  c.radius1 = x;
  c.radius2 = g.line_of_centres_length - x;
  c.rolling1 = omega1 * c.radius1;
  c.rolling2 = omega2 * c.radius2;
  c.sliding = std::fabs(c.rolling1 - c.rolling2);
  c.sum_speed = c.rolling1 + c.rolling2;
  c.reduced_radius = c.radius1 * c.radius2 / (c.radius1 + c.radius2);
  c.load = load;
  c.load_per_width = load / g.in.face_width;
  const double e_prime = g.in.youngs_modulus / (1.0 - g.in.poisson_ratio * g.in.poisson_ratio);
  c.hertz_pressure = std::sqrt(c.load_per_width * e_prime / (2.0 * kPi * c.reduced_radius));
  return c;
}

const std::vector<FrictionLaw>& friction_laws() {
  static const std::vector<FrictionLaw> laws = {
      {"constant", "the lane's mu (gear_pair.friction_coefficient), the paper's", nullptr},
      {"benedict_kelley", "Benedict & Kelley 1961, per pair from sliding and rolling speed and load", benedict_kelley},
      {"xu", "Xu, Kahraman, Anderson & Maddock 2007 EHL regression, per pair", xu},
      {"iso_tr_13989", "ISO/TR 13989-2 mean mu_mC at the pitch point, the same for every pair", iso_tr_13989},
  };
  return laws;
}

std::vector<std::string> friction_model_names() {
  std::vector<std::string> n;
  for (const FrictionLaw& l : friction_laws()) n.push_back(l.name);
  return n;
}

double law_friction_coefficient(const GearPair& g, double x, double load) {
  const FrictionLaw& law = friction_laws().at(static_cast<std::size_t>(g.in.friction_model));
  return law.coefficient(g, contact_kinematics(g, x, load));
}

double pair_friction_weight(const GearPair& g, double x, double x_mid, double share) {
  const double sign =
      g.in.friction_direction == FrictionDirection::kReversing && x_mid < g.x_p ? -1.0 : 1.0;
  return sign * share * law_friction_coefficient(g, x, share * g.in.friction_load) / kLawReferenceMu;
}

std::vector<std::string> friction_law_warnings(const GearPair& g) {
  std::vector<std::string> out;
  if (g.in.friction_model == FrictionModel::kConstant) return out;
  const std::string name = friction_laws().at(static_cast<std::size_t>(g.in.friction_model)).name;
  // The laws are fits to loaded EHL contacts; below ~0.5 GPa of Hertz pressure no test backs them.
  const double ph = contact_kinematics(g, g.x_p, g.in.friction_load).hertz_pressure;
  if (ph < 0.5e9) {
    std::ostringstream w;
    w << "gear_pair.friction_load = " << g.in.friction_load << " N gives a Hertz pressure of " << ph * 1e-9
      << " GPa at the pitch point, below 0.5 GPa, the lower end of the loaded contacts friction_model " << name
      << " was fitted to (doc/model.md, Friction laws)";
    out.push_back(w.str());
  }
  return out;
}

}  // namespace gear_dynamics
