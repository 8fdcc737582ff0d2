// Poincare sections against analytic cases (doc/nonlinear-dynamics.md §3) and the gear lanes
// against the production Ensemble.
#include <gtest/gtest.h>

#include <cmath>
#include <map>

#include "gear_dynamics/config/config.hpp"
#include "gear_dynamics/dynamics/bifurcation.hpp"
#include "gear_dynamics/dynamics/poincare.hpp"

#include "paper_config.hpp"

namespace gd = gear_dynamics;

// Free undamped oscillator sampled at its own period: one fixed point, the initial state. The period
// 1 s is 1000 steps (on the grid). RK4's phase error is (omega h)^5 / 120 = 8e-14 rad per step,
// 8e-11 per period: after 100 periods 8e-9 rad, i.e. below 2e-8 in x and v (|x| omega < 2); 5e-8.
TEST(Poincare, FreeOscillatorOwnPeriodIsOneFixedPoint) {
  gd::LinearOscillatorParams p{2 * M_PI, 0.0, 0.0, 1.0};
  gd::LinearOscillatorLanes sys({p}, 1e-3, {0.3}, {-0.2});
  const auto pts = gd::poincare_section(sys, {1.0, 0.0, 0.0, 100.0, {}});
  ASSERT_EQ(pts.size(), 101u);
  for (const auto& q : pts) {
    EXPECT_TRUE(q.on_grid);
    EXPECT_NEAR(q.x[0], 0.3, 5e-8);
    EXPECT_NEAR(q.x[1], -0.2, 5e-8);
  }
}

// The same with a period that is not a whole number of steps: Hermite interpolation (error of
// order h^4 x'''' = (omega h)^4 |x| / 384 ~ 1e-10 with h = 0.0007).
TEST(Poincare, InterpolatedSamplesOffTheGrid) {
  gd::LinearOscillatorParams p{2 * M_PI, 0.0, 0.0, 1.0};
  gd::LinearOscillatorLanes sys({p}, 7e-4, {0.3}, {-0.2});
  const auto pts = gd::poincare_section(sys, {1.0, 0.25, 0.0, 50.0, {}});
  ASSERT_EQ(pts.size(), 50u);
  double x = 0, v = 0;
  // Exact solution at t = 0.25 + k: x(t) = 0.3 cos(w t) - 0.2/w sin(w t).
  const double w = 2 * M_PI;
  x = 0.3 * std::cos(w * 0.25) - 0.2 / w * std::sin(w * 0.25);
  v = -0.3 * w * std::sin(w * 0.25) - 0.2 * std::cos(w * 0.25);
  for (const auto& q : pts) {
    EXPECT_FALSE(q.on_grid);
    EXPECT_NEAR(q.x[0], x, 1e-8);
    EXPECT_NEAR(q.x[1], v, 1e-4 * std::abs(v) + 1e-6);  // linear in velocity: h^2 x''' / 8 ~ 2e-5
  }
}

// Forced damped oscillator: after the transient every point is the analytic steady state
// x_p(t_k) at the forcing phase. Several forcing amplitudes as lanes (a scan over F).
TEST(Poincare, ForcedOscillatorAnalyticSteadyState) {
  std::vector<gd::LinearOscillatorParams> lanes;
  for (double F : {0.5, 1.0, 2.0}) lanes.push_back({1.0, 0.1, F, 1.3});
  const double period = 2 * M_PI / 1.3, h = period / 1000;
  gd::LinearOscillatorLanes sys(lanes, h, {0.0, 1.0, -1.0}, {0.0, 0.0, 0.5});
  // transient 250: e^(-zeta omega t) = e^-25 = 1.4e-11
  const auto pts = gd::poincare_section(sys, {period, 0.0, 250.0, 300.0, {}});
  ASSERT_FALSE(pts.empty());
  for (const auto& q : pts) {
    double x, v;
    gd::LinearOscillatorLanes::steady_state(lanes[q.lane], q.time, x, v);
    EXPECT_TRUE(q.on_grid);
    EXPECT_NEAR(q.x[0], x, 1e-8 * lanes[q.lane].force);
    EXPECT_NEAR(q.x[1], v, 1e-8 * lanes[q.lane].force);
  }
}

// GearLanes (a mesh schedule per lane, SIMD packets of lanes when no lane's step is split) steps
// exactly like the production Ensemble: bit for bit over 50 ms (about 30 impacts), for 8 lanes of
// one block at two speeds, two mesh phases and two friction coefficients, plus one lane alone.
TEST(GearLanes, BitIdenticalToEnsemble) {
  const gd::ModelConfig base = paper_config();
  std::vector<gd::ModelConfig> cs;
  std::vector<double> mus;
  for (double rpm : {1000.0, 1370.0})
    for (double phase : {0.0, 0.11})
      for (double mu : {0.0, 0.04}) {
        gd::ModelConfig c = gd::with_parameter(base, gd::ScanParameter::Speed, rpm);
        c.gear.mesh_phase = phase;
        cs.push_back(c);
        mus.push_back(mu);
      }
  std::vector<gd::GearLaneSpec> specs;
  for (std::size_t i = 0; i < cs.size(); ++i)
    specs.push_back(gd::GearLaneSpec{cs[i].gear, mus[i], cs[i].load.initial_mean, cs[i].initial});
  gd::GearLanes block(specs, base.run.time_step);
  gd::GearLanes alone({specs[5]}, base.run.time_step);
  for (int n = 0; n < 50000; ++n) {
    block.step();
    alone.step();
  }
  for (std::size_t i = 0; i < cs.size(); ++i) {
    const gd::ModelConfig& c = cs[i];
    gd::Ensemble e(gd::derive(c.gear), c.run.time_step, c.initial, {gd::deterministic_lane(c, mus[i])}, c.seed);
    for (int n = 0; n < 50000; ++n) e.step();
    EXPECT_EQ(e.delta()[0], block.state(static_cast<int>(i), 0)) << "lane " << i;
    EXPECT_EQ(e.velocity()[0], block.state(static_cast<int>(i), 1)) << "lane " << i;
    if (i == 5) {
      EXPECT_EQ(e.delta()[0], alone.state(0, 0));
      EXPECT_EQ(e.velocity()[0], alone.state(0, 1));
    }
  }
}

// At 1000 rpm the mesh period, 3 ms, is a whole number of steps: the gear's section is taken on the grid, and it
// equals the Ensemble's state at those steps.
TEST(Poincare, GearSectionOnTheGrid) {
  const gd::ModelConfig c = paper_config();
  const gd::GearPair g = gd::derive(c.gear);
  EXPECT_TRUE(gd::on_step_grid(gd::mesh_period(g), c.run.time_step));
  gd::Ensemble e(g, c.run.time_step, c.initial, {gd::deterministic_lane(c, 0.04)}, c.seed);
  gd::EnsembleLanes sys(e);
  const auto pts = gd::poincare_section(sys, {gd::mesh_period(g), 0.0, 0.0, 0.03, {}});
  ASSERT_EQ(pts.size(), 11u);
  gd::Ensemble ref(g, c.run.time_step, c.initial, {gd::deterministic_lane(c, 0.04)}, c.seed);
  for (std::size_t k = 0; k < pts.size(); ++k) {
    EXPECT_TRUE(pts[k].on_grid);
    while (ref.step_index() < static_cast<std::int64_t>(k) * std::llround(gd::mesh_period(g) / c.run.time_step)) ref.step();
    EXPECT_EQ(pts[k].x[0], ref.delta()[0]);
    EXPECT_EQ(pts[k].x[1], ref.velocity()[0]);
  }
}

