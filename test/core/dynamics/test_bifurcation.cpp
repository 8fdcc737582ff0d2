// Bifurcation scans (doc/nonlinear-dynamics.md §5).
#include <gtest/gtest.h>

#include <cmath>

#include "gear_dynamics/config/config.hpp"
#include "gear_dynamics/dynamics/bifurcation.hpp"
#include "gear_dynamics/model/mesh_table.hpp"

#include "paper_config.hpp"

namespace gd = gear_dynamics;

// A scan of a forced linear oscillator over its damping ratio (lanes = parameter values): each
// value's Poincare points are the single analytic steady-state point.
TEST(Bifurcation, ForcedLinearOscillatorScan) {
  std::vector<gd::LinearOscillatorParams> lanes;
  for (double zeta : {0.05, 0.1, 0.2, 0.4}) lanes.push_back({1.0, zeta, 1.0, 0.8});
  const double period = 2 * M_PI / 0.8, h = period / 2000;
  gd::LinearOscillatorLanes sys(lanes, h, std::vector<double>(4, 0.0), std::vector<double>(4, 0.0));
  // transient 600: e^(-0.05 * 600) = 1e-13
  const auto pts = gd::poincare_section(sys, {period, 0.0, 600.0, 700.0, {}});
  ASSERT_FALSE(pts.empty());
  for (const auto& q : pts) {
    double x, v;
    gd::LinearOscillatorLanes::steady_state(lanes[q.lane], 0.0, x, v);  // phase 0 of the forcing
    EXPECT_NEAR(q.x[0], x, 1e-8);
    EXPECT_NEAR(q.x[1], v, 1e-8);
  }
  // The points come lane after lane in each period: the sequence repeats every 4 (the lanes).
  EXPECT_EQ(gd::detect_period(pts, 8, {1e-8, 1e-8}), 4);
}

// Mean loads high enough that the teeth never separate (250x to 2500x the paper's Phi0; the scan of
// doc/nonlinear-dynamics.md §5 finds separation up to about 2500 m/s^2): after the transient every
// value is period-1, one Poincare point up to 1e-3 b and 1e-3 v_ref, v_ref = sqrt(2 Phi0 b).
// The mesh frequency, 333 Hz, is far below the contact's natural frequencies (8-11 kHz), away from
// the principal parametric resonances 2 f_n / j of low order.
TEST(Bifurcation, HighLoadIsPeriodOne) {
  const gd::ModelConfig base = paper_config();
  std::vector<double> loads;
  for (int i = 0; i <= 8; ++i) loads.push_back(5000.0 * std::pow(10.0, i / 8.0));
  gd::ScanOptions o;
  o.duration = 0.6;
  o.transient = 0.4;
  const auto r = gd::bifurcation_scan(base, gd::ScanParameter::Load, loads, o);
  ASSERT_EQ(r.size(), loads.size());
  for (const auto& v : r) {
    EXPECT_EQ(v.regime, "period-1, no separation") << v.value;
    EXPECT_GT(v.min_gap, 0.0) << v.value;
    EXPECT_EQ(v.period, 1) << v.value;
    EXPECT_GE(v.points.size(), 60u);
  }
}

// A cracked pinion tooth makes the mesh repeat after one pinion revolution (Z1 = 20 mesh periods).
// At a load where the teeth never separate the motion is locked to that forcing, so its Poincare
// points repeat after 20 mesh periods and not before: a period test stopping at 16 calls it
// aperiodic, the scan (which tests up to the schedule's period) finds 20. Tolerance as the scan's,
// 1e-3 of (b, v_ref); the crack changes K by far more than that per revolution.
TEST(Bifurcation, CrackedPinionIsPeriodOfOneRevolution) {
  gd::ModelConfig base = paper_config();
  base.gear.mesh_stiffness = gd::MeshStiffnessModel::kPotentialEnergy;
  base.gear.crack.gear = gd::FaultyGear::kPinion;
  base.gear.crack.depth = 1e-3;
  ASSERT_EQ(gd::schedule_mesh_periods(base.gear), base.gear.pinion_teeth);
  EXPECT_EQ(gd::period_search_limit(base.gear, 16), base.gear.pinion_teeth);
  gd::ScanOptions o;
  o.duration = 0.6;
  o.transient = 0.4;
  const auto r = gd::bifurcation_scan(base, gd::ScanParameter::Load, {20000.0}, o);
  ASSERT_EQ(r.size(), 1u);
  ASSERT_GE(r[0].points.size(), 2u * base.gear.pinion_teeth);
  EXPECT_GT(r[0].min_gap, 0.0);
  EXPECT_EQ(r[0].period, base.gear.pinion_teeth);
  EXPECT_EQ(r[0].regime, "period-20, no separation");
  const double b = base.gear.backlash, vref = std::sqrt(2.0 * 20000.0 * b);
  EXPECT_EQ(gd::detect_period(r[0].points, 16, {1e-3 * b, 1e-3 * vref}), 0);
}

// The speed path (GearLanes, one block per value) gives the same points as the Ensemble path for
// the parameters both can run: a load scan done both ways at one speed.
TEST(Bifurcation, SpeedPathMatchesEnsemblePath) {
  const gd::ModelConfig base = gd::with_parameter(paper_config(), gd::ScanParameter::Speed, 1000.0);
  gd::ScanOptions o;
  o.duration = 0.05;
  o.transient = 0.0;
  const auto a = gd::bifurcation_scan(base, gd::ScanParameter::Speed, {1000.0}, o);
  const auto b = gd::bifurcation_scan(base, gd::ScanParameter::Load, {base.load.initial_mean}, o);
  ASSERT_EQ(a[0].points.size(), b[0].points.size());
  for (std::size_t k = 0; k < a[0].points.size(); ++k) {
    EXPECT_EQ(a[0].points[k].x[0], b[0].points[k].x[0]);
    EXPECT_EQ(a[0].points[k].x[1], b[0].points[k].x[1]);
  }
}

TEST(Bifurcation, ParameterNames) {
  EXPECT_EQ(gd::parse_scan_parameter("speed"), gd::ScanParameter::Speed);
  EXPECT_EQ(gd::scan_parameter_name(gd::ScanParameter::Damping), "damping");
  EXPECT_THROW(gd::parse_scan_parameter("spead"), std::invalid_argument);
}
