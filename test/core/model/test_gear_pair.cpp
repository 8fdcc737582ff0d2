// Every derived quantity against the values printed in doc/model.md §3.
#include <gtest/gtest.h>

#include <cmath>

#include "gear_dynamics/model/gear_pair.hpp"

namespace gd = gear_dynamics;

namespace {

// doc/model.md prints most values to 8 significant digits (relative 1e-6 is the brief's tolerance);
// a few are printed with fewer digits, so the tolerance is also never below half a unit in the
// last printed place.
void expect_printed(double actual, double printed, double last_place, const char* name) {
  const double tol = std::max(1e-6 * std::abs(printed), 0.5 * last_place);
  EXPECT_NEAR(actual, printed, tol) << name;
}

}  // namespace

TEST(GearPair, DerivedQuantitiesMatchModelMd) {
  const gd::GearPair g = gd::derive(gd::GearInputs{});
  expect_printed(g.module, 0.002, 1e-9, "m");
  expect_printed(g.base_radius1, 0.018793852, 1e-9, "Rb1");
  expect_printed(g.base_radius2, 0.075175410, 1e-9, "Rb2");
  expect_printed(g.tip_radius1, 0.022, 1e-9, "ra1");
  expect_printed(g.tip_radius2, 0.082, 1e-9, "ra2");
  expect_printed(g.root_radius1, 0.0175, 1e-9, "rf1");
  expect_printed(g.root_radius2, 0.0775, 1e-9, "rf2");
  expect_printed(g.base_pitch, 5.9042629e-3, 1e-10, "pb");
  expect_printed(g.line_of_centres_length, 0.034202014, 1e-9, "lp");
  expect_printed(g.contact_ratio, 1.6912923, 1e-7, "eps_alpha");
  expect_printed(g.x_a, 1.4505597e-3, 1e-10, "X_A");
  expect_printed(g.x_b, 5.5321313e-3, 1e-10, "X_B");
  expect_printed(g.x_p, 6.8404029e-3, 1e-10, "X_P");
  expect_printed(g.x_d, 7.3548225e-3, 1e-10, "X_D");
  expect_printed(g.x_e, 11.436394e-3, 1e-9, "X_E");
  expect_printed(g.inertia1, 1.9603538e-5, 1e-12, "J1");
  expect_printed(g.inertia2, 5.0185058e-3, 1e-10, "J2");
  expect_printed(g.half_tooth_angle1, 0.0934442, 1e-7, "theta_b1");
  expect_printed(g.q1, 8.3397495, 1e-7, "q1");
  expect_printed(g.q2, 17.736084, 1e-6, "q2");
  expect_printed(g.q3, 19.143710, 1e-6, "q3");
  expect_printed(g.equivalent_mass, 0.052236479, 1e-9, "m_e");
  expect_printed(g.c0, 0.51233386, 1e-8, "c0");
  expect_printed(g.c1, 943.71732, 1e-5, "c1");
  expect_printed(g.mesh_period_angle, 0.31415927, 1e-8, "phi_n");
  expect_printed(g.single_pair_angle, 0.096983376, 1e-9, "phi_m");
  expect_printed(g.iso_single_stiffness, 13.447321, 1e-6, "c'");
  expect_printed(g.iso_mesh_stiffness, 20.419344, 1e-6, "c_gamma_alpha");
  expect_printed(g.k1, 1.3447321e8, 1e1, "k1");
  expect_printed(g.k_mean, 2.0419344e8, 1e1, "k_mean");
  expect_printed(g.k2, 2.3532813e8, 1e1, "k2");
  expect_printed(g.damping_coefficient, 1.2003894e8, 1e1, "alpha");
  expect_printed(g.in.pinion_speed, 104.71976, 1e-5, "Omega");
  // doc/model.md: the square wave with mean k_mean gives exactly k2 = 1.75 k1.
  EXPECT_NEAR(g.k2 / g.k1, 1.75, 1e-12);
  // §3 derived dynamics and §7 check 8: omega = sqrt(q3 K) at mu = 0.
  expect_printed(std::sqrt(g.q3 * g.k1), 50737.72, 1e-2, "omega1");
  expect_printed(std::sqrt(g.q3 * g.k2), 67119.69, 1e-2, "omega2");
  // Static deflections under Phi0 = 20 m/s^2.
  expect_printed(20.0 / (g.q3 * g.k1), 7.769e-9, 1e-12, "x_s(k1)");
  expect_printed(20.0 / (g.q3 * g.k2), 4.439e-9, 1e-12, "x_s(k2)");
  // The friction arm runs from X_B to X_E over one mesh period (doc/model.md D4).
  EXPECT_NEAR(g.friction_factor(g.mesh_period_angle), g.c0 + g.c1 * g.x_e, 1e-9);
}
