// The largest Lyapunov exponent by the two-trajectory method (doc/nonlinear-dynamics.md §4), through
// one code path for the linear damped oscillator, Lorenz and the gear model.
#include <gtest/gtest.h>

#include <cmath>

#include "gear_dynamics/config/config.hpp"
#include "gear_dynamics/dynamics/bifurcation.hpp"
#include "gear_dynamics/dynamics/poincare.hpp"

namespace gd = gear_dynamics;

// Free damped oscillator: every separation decays like e^(-zeta omega t), so lambda_1 = -zeta omega.
// Over zeta omega T = 40 the bounded modulation of the separation's norm within a period
// (|ln| < 0.5 here) moves the estimate by at most 0.5/40 = 1.3 %; the test allows 2 %.
TEST(Lyapunov, LinearDampedOscillator) {
  const double omega = 2.0, zeta = 0.1;
  std::vector<gd::LinearOscillatorParams> p(2, {omega, zeta, 0.0, 1.0});
  gd::LinearOscillatorLanes sys(p, 0.005, {1.0, 1.0}, {0.0, 0.0});
  gd::LyapunovOptions o;
  o.duration = 200.0;
  o.renormalise_every = 20;
  o.separation = 1e-6;
  const auto r = gd::largest_lyapunov(sys, o);
  ASSERT_EQ(r.size(), 1u);
  EXPECT_NEAR(r[0].exponent, -zeta * omega, 0.02 * zeta * omega);
  EXPECT_FALSE(r[0].running.empty());
}

// Lorenz at sigma = 10, rho = 28, beta = 8/3: lambda_1 = 0.9056 (Sprott 2003, Chaos and Time-Series
// Analysis, Table A.1). Four pairs from different starts, 1000 time units each after 50 of transient;
// finite-time estimates over T = 1000 scatter by about 0.01 each, their mean by 0.005; 3 % = 0.027.
TEST(Lyapunov, LorenzClassic) {
  gd::LorenzLanes sys({}, 0.005,
                      {{1, 1, 1}, {1, 1, 1}, {-5, 3, 20}, {-5, 3, 20}, {0.1, -2, 30}, {0.1, -2, 30}, {8, 8, 27}, {8, 8, 27}});
  gd::LyapunovOptions o;
  o.transient = 50;
  o.duration = 1000;
  o.renormalise_every = 20;
  o.separation = 1e-8;
  const auto r = gd::largest_lyapunov(sys, o);
  ASSERT_EQ(r.size(), 4u);
  double mean = 0;
  for (const auto& x : r) mean += x.exponent / 4;
  EXPECT_NEAR(mean, 0.9056, 0.03 * 0.9056);
  for (const auto& x : r) EXPECT_NEAR(x.exponent, 0.9056, 0.08);
}

namespace {

gd::ModelConfig paper_config() {
  const std::string dir = GEAR_DYNAMICS_CONFIG_DIR;
  return gd::parse_config(gd::read_yaml_files({dir + "/gear_pair.yaml", dir + "/load.yaml", dir + "/run.yaml"}));
}

double gear_exponent(const gd::ModelConfig& c, double separation, double h) {
  gd::GearLaneSpec s{c.gear, c.friction_coefficient, c.load.initial_mean, c.initial};
  gd::GearLanes sys({s, s}, h);
  gd::LyapunovOptions o;
  o.transient = 0.3;
  o.duration = 0.5;
  o.renormalise_every = static_cast<std::int64_t>(std::llround(1e-4 / h));
  o.separation = separation;
  const double b = c.gear.backlash;
  o.scale = {b, std::sqrt(2.0 * c.load.initial_mean * b)};
  return gd::largest_lyapunov(sys, o)[0].exponent;
}

}  // namespace

// The gear model in permanent contact (Phi0 = 2000 m/s^2, 100x the paper's: the teeth never
// separate, see test_dynamics_bifurcation) is a damped, parametrically excited linear oscillator:
// its largest exponent is negative, and the estimate does not depend on d0 (linear regime) or, to
// 5 %, on the step.
TEST(Lyapunov, GearInPermanentContactIsStable) {
  gd::ModelConfig c = paper_config();
  c.load.initial_mean = 2000.0;
  const double l1 = gear_exponent(c, 1e-7, 1e-6);
  const double l2 = gear_exponent(c, 1e-9, 1e-6);
  const double l3 = gear_exponent(c, 1e-7, 5e-7);
  EXPECT_LT(l1, 0.0);
  EXPECT_NEAR(l2, l1, 1e-3 * std::abs(l1));
  EXPECT_NEAR(l3, l1, 0.05 * std::abs(l1));
}
