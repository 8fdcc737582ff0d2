// The square-wave mesh schedule's timing and its splits of a step at the stiffness jumps
// (doc/model.md §3).
#include <gtest/gtest.h>

#include <cmath>

#include "gear_dynamics/model/gear_pair.hpp"
#include "gear_dynamics/model/mesh_schedule.hpp"

namespace gd = gear_dynamics;

TEST(MeshSchedule, SquareWaveTimingAndSplits) {
  const gd::GearPair g = gd::derive(gd::GearInputs{});
  const double h = 1e-6;
  const gd::MeshSchedule mesh(g, h);
  // Mesh period 3.000 ms, single-pair time 0.92612 ms (doc/model.md §3).
  const double tm = g.mesh_period_angle / g.in.pinion_speed;
  const double ts = g.single_pair_angle / g.in.pinion_speed;
  EXPECT_NEAR(tm, 3.000e-3, 5e-7);
  EXPECT_NEAR(ts, 0.92612e-3, 5e-9);
  EXPECT_EQ(mesh.stiffness(0.5 * ts), g.k1);
  EXPECT_EQ(mesh.stiffness(0.5 * (ts + tm)), g.k2);
  EXPECT_EQ(mesh.stiffness(tm + 0.5 * ts), g.k1);

  // Count the split steps over one second: two switches per mesh period, each inside a step
  // unless it falls on a grid point (the k2 -> k1 switches at j * 3 ms do).
  int split = 0, on_grid_k1 = 0;
  for (std::int64_t n = 0; n < 30000; ++n) {
    const gd::StepPlan p = mesh.plan(n);
    ASSERT_LE(p.segments, 2);
    if (p.segments == 2) {
      ++split;
      const gd::StepSegment& a = p.segment[0];
      const gd::StepSegment& b = p.segment[1];
      EXPECT_EQ(a.end, b.begin);
      const double ts_exact = (a.end + static_cast<double>(n)) * h;
      // The cut is where the phase reaches phi_m (mod phi_n) or phi_n.
      const double ph = g.in.pinion_speed * ts_exact;
      const double r = std::fmod(ph, g.mesh_period_angle);
      EXPECT_TRUE(std::abs(r - g.single_pair_angle) < 1e-9 || r < 1e-9 || g.mesh_period_angle - r < 1e-9);
      EXPECT_NE(a.stiffness_mid, b.stiffness_mid);
      EXPECT_EQ(a.friction_start, a.friction_end);  // frozen at the sub-step midpoint
    }
    if (n > 0 && n % 3000 == 0) {  // k2 -> k1 exactly on the grid point n h = j * 3 ms
      EXPECT_EQ(p.segments, 1);
      EXPECT_EQ(mesh.plan(n - 1).segments, 1);
      EXPECT_EQ(p.segment[0].stiffness_mid, g.k1);
      EXPECT_EQ(mesh.plan(n - 1).segment[0].stiffness_mid, g.k2);
      ++on_grid_k1;
    }
  }
  EXPECT_EQ(split, 10);  // k1 -> k2 switches at 0.926, 3.926, ... ms: 10 in 30 ms
  EXPECT_EQ(on_grid_k1, 9);
  // An unsplit step evaluates the friction factor at its stage times, continuously within a cycle.
  const gd::StepPlan p = mesh.plan(100);
  EXPECT_LT(p.segment[0].friction_start, p.segment[0].friction_mid);
  EXPECT_LT(p.segment[0].friction_mid, p.segment[0].friction_end);
}
