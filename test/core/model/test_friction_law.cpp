// The friction laws (model/friction_law.hpp, doc/model.md §2 "Friction laws") against their published
// formulas written out here in the units of each publication, at one hand-computed contact; their mean
// over a mesh cycle at the paper's light load and at ~1 kN; the default unchanged; bad values refused.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <string>

#include "gear_dynamics/config/config.hpp"
#include "gear_dynamics/model/friction_law.hpp"
#include "gear_dynamics/model/mesh_table.hpp"

namespace gd = gear_dynamics;

namespace {

YAML::Node defaults() {
  const std::string dir = GEAR_DYNAMICS_CONFIG_DIR;
  return gd::read_yaml_files({dir + "/gear_pair.yaml", dir + "/load.yaml", dir + "/run.yaml"});
}

gd::GearPair pair_with(gd::FrictionModel model, double load) {
  gd::GearInputs in = gd::parse_config(defaults()).gear;
  in.friction_model = model;
  in.friction_load = load;
  return gd::derive(in);
}

// The hand point: the default pair (r1 = 20 mm, r2 = 80 mm, 20 deg, L = 10 mm, 1000 rpm), 3 mm past
// the pitch point, 1000 N, eta = 0.023 Pa s, Ra = 0.4 um. The kinematics from the involute: rho1 = x,
// rho2 = (r1 + r2) sin(alpha) - x, u_i = Omega_i rho_i.
struct HandPoint {
  double x, u1, u2, R, w;  // [m], [m/s], [m/s], [m], W' [N/m]
};
HandPoint hand_point() {
  const double a = 20.0 * M_PI / 180.0, omega1 = 104.71975511965977, omega2 = omega1 / 4.0;
  const double x = 0.020 * std::sin(a) + 3e-3, rho2 = 0.100 * std::sin(a) - x;
  return {x, omega1 * x, omega2 * rho2, x * rho2 / (x + rho2), 1000.0 / 0.010};
}

double mean_over_mesh_cycle(const gd::GearPair& g) {
  // Force-weighted mu of the pairs in contact, sum_j lambda_j mu_j, sampled uniformly over a cycle.
  const auto table = gd::shared_mesh_table(g);
  const int n = 2000;
  double sum = 0.0;
  for (int k = 0; k < n; ++k)
    sum += gd::kLawReferenceMu * gd::friction_share(g, table.get(), (k + 0.5) / n * g.mesh_period_angle);
  return sum / n;
}

}  // namespace

// Benedict & Kelley 1961: mu = 0.0127 C_R log10(3.17e8 W' / (nu0 V_s V_e^2)), W' [lb/in], nu0 [cP],
// V [in/s], C_R = 50 / (50 - S), S [micro-inch]; V_e = u1 + u2. Hand value 0.09403 (by the same
// formula on a calculator); the code's kinematics and unit conversions must give it to rounding.
TEST(FrictionLaw, BenedictKelleyAtAHandPoint) {
  const HandPoint p = hand_point();
  const double in = 0.0254, lbf = 4.4482216152605;
  const double s = 0.4e-6 / (1e-6 * in), cr = 50.0 / (50.0 - s);
  const double vs = std::fabs(p.u1 - p.u2) / in, ve = (p.u1 + p.u2) / in;
  const double mu = 0.0127 * cr * std::log10(3.17e8 * (p.w * in / lbf) / (23.0 * vs * ve * ve));
  EXPECT_NEAR(mu, 0.09403, 5e-5);
  const gd::GearPair g = pair_with(gd::FrictionModel::kBenedictKelley, 1000.0);
  EXPECT_NEAR(gd::law_friction_coefficient(g, p.x, 1000.0), mu, 1e-12 * mu);
  // At the pitch point the slide-to-roll ratio is held at kMinSlideToRoll: finite, and the largest.
  const double at_pitch = gd::law_friction_coefficient(g, g.x_p, 1000.0);
  EXPECT_TRUE(std::isfinite(at_pitch));
  EXPECT_GT(at_pitch, mu);
}

// Xu, Kahraman, Anderson & Maddock 2007: mu = e^f P_h^b2 |SR|^b3 V_e^b6 nu0^b7 R^b8,
// f = b1 + b4 |SR| P_h log10(nu0) + b5 e^(-|SR| P_h log10(nu0)) + b9 e^S; P_h [GPa], nu0 [cP],
// S [um], V_e = (u1 + u2) / 2 [m/s], R [m]. Hand value 0.04141.
TEST(FrictionLaw, XuAtAHandPoint) {
  const HandPoint p = hand_point();
  const double e_prime = 2.068e11 / (1.0 - 0.09);
  const double ph = std::sqrt(p.w * e_prime / (2.0 * M_PI * p.R)) * 1e-9;
  const double ve = 0.5 * (p.u1 + p.u2), sr = std::fabs(p.u1 - p.u2) / ve, a = sr * ph * std::log10(23.0);
  const double f = -8.916465 - 0.354068 * a + 2.812084 * std::exp(-a) + 0.620305 * std::exp(0.4);
  const double mu = std::exp(f) * std::pow(ph, 1.03303) * std::pow(sr, 1.036077) * std::pow(ve, -0.100601) *
                    std::pow(23.0, 0.752755) * std::pow(p.R, -0.390958);
  EXPECT_NEAR(mu, 0.04141, 5e-5);
  const gd::GearPair g = pair_with(gd::FrictionModel::kXu, 1000.0);
  EXPECT_NEAR(gd::law_friction_coefficient(g, p.x, 1000.0), mu, 1e-12 * mu);
  EXPECT_EQ(gd::law_friction_coefficient(g, g.x_p, 1000.0), 0.0) << "no sliding, no friction";
}

// ISO/TR 13989-2: mu_mC = 0.060 (w_Bt K_Bgamma / (v_SigmaC rho_redC))^0.2 eta^-0.05 Ra^0.25 X_L at the
// pitch point, w_Bt [N/mm], v [m/s], rho [mm], eta [mPa s], Ra [um], K_Bgamma = X_L = 1. Hand value
// 0.06788; the same at every contact of the cycle.
TEST(FrictionLaw, IsoTr13989AtAHandPoint) {
  const double a = 20.0 * M_PI / 180.0, omega1 = 104.71975511965977;
  const double rho1 = 0.020 * std::sin(a), rho2 = 0.080 * std::sin(a);
  const double v_sum = omega1 * rho1 + omega1 / 4.0 * rho2, rho_red = rho1 * rho2 / (rho1 + rho2) * 1e3;
  const double mu = 0.060 * std::pow(100.0 / (v_sum * rho_red), 0.2) * std::pow(23.0, -0.05) * std::pow(0.4, 0.25);
  EXPECT_NEAR(mu, 0.06788, 5e-5);
  const gd::GearPair g = pair_with(gd::FrictionModel::kIsoTr13989, 1000.0);
  EXPECT_NEAR(gd::law_friction_coefficient(g, hand_point().x, 400.0), mu, 1e-12 * mu);
  EXPECT_NEAR(mean_over_mesh_cycle(g), mu, 1e-9 * mu) << "the shares of the pairs sum to 1";
}

// The mean over a mesh cycle at the paper's light load (Phi = 20 m/s^2, the default S1, a static
// mesh force m_e Phi) and near 1 kN (Phi = 2e4 m/s^2). At 1 kN every law lies in the range lubricated
// steel spur gears are measured in, 0.02-0.08 widened to 0.015-0.12 for Benedict-Kelley's roughness
// factor (C_R = 1.46 at Ra = 0.4 um); at the light load each law gives less (all grow with load),
// and the laws hold outside their range there (the warning says so).
TEST(FrictionLaw, MeanOverAMeshCycleAtTwoLoads) {
  const double m_e = gd::derive(gd::parse_config(defaults()).gear).equivalent_mass;
  const double light = m_e * 20.0, heavy = m_e * 2e4;
  std::printf("static mesh force: light %.4g N, heavy %.4g N\n", light, heavy);
  for (gd::FrictionModel m : {gd::FrictionModel::kBenedictKelley, gd::FrictionModel::kXu,
                              gd::FrictionModel::kIsoTr13989}) {
    const double mu_light = mean_over_mesh_cycle(pair_with(m, light));
    const double mu_heavy = mean_over_mesh_cycle(pair_with(m, heavy));
    const std::string name = gd::friction_laws()[static_cast<std::size_t>(m)].name;
    std::printf("%-16s mean mu: %.4f at %.3g N, %.4f at %.4g N\n", name.c_str(), mu_light, light, mu_heavy, heavy);
    EXPECT_GE(mu_light, 0.0) << name;
    EXPECT_LT(mu_light, mu_heavy) << name;
    EXPECT_GT(mu_heavy, 0.015) << name;
    EXPECT_LT(mu_heavy, 0.12) << name;
    EXPECT_FALSE(gd::friction_law_warnings(pair_with(m, light)).empty()) << name;
    EXPECT_TRUE(gd::friction_law_warnings(pair_with(m, heavy)).empty()) << name;
  }
}

// Without friction_model the pair is the paper's: constant law, the closed-form mesh, and the new
// keys are not written back (so a dumped configuration is what it was).
TEST(FrictionLaw, DefaultIsTheConstantCoefficient) {
  const gd::ModelConfig c = gd::parse_config(defaults());
  EXPECT_EQ(c.gear.friction_model, gd::FrictionModel::kConstant);
  EXPECT_TRUE(gd::is_paper_mesh(c.gear));
  const YAML::Node dumped = gd::to_yaml(c);
  EXPECT_FALSE(dumped["gear_pair"]["friction_model"].IsDefined());
  EXPECT_FALSE(dumped["gear_pair"]["oil_viscosity"].IsDefined());
}

TEST(FrictionLaw, BadValuesAreRefusedNamingKeyValueAndRange) {
  const auto error_of = [](const std::string& key, const std::string& value) {
    YAML::Node root = defaults();
    root["gear_pair"][key] = YAML::Load(value);
    try {
      gd::parse_config(root);
      return std::string();
    } catch (const gd::ConfigError& e) {
      return std::string(e.what());
    }
  };
  const std::string roughness = error_of("surface_roughness", "2e-6");
  EXPECT_NE(roughness.find("gear_pair.surface_roughness"), std::string::npos) << roughness;
  EXPECT_NE(roughness.find("2e-06"), std::string::npos) << roughness;
  EXPECT_NE(roughness.find("1.2e-06"), std::string::npos) << roughness;
  const std::string viscosity = error_of("oil_viscosity", "0");
  EXPECT_NE(viscosity.find("gear_pair.oil_viscosity"), std::string::npos) << viscosity;
  const std::string model = error_of("friction_model", "stribeck");
  EXPECT_NE(model.find("gear_pair.friction_model"), std::string::npos) << model;
  EXPECT_NE(model.find("benedict_kelley"), std::string::npos) << model;
  EXPECT_NE(error_of("friction_load", "-5").find("gear_pair.friction_load"), std::string::npos);
}

