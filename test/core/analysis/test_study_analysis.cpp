// A study's per-point and per-axis analysis (doc/studies.md), recomputed by hand on a small set.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <vector>

#include "gear_dynamics/analysis/study_analysis.hpp"

namespace gd = gear_dynamics;

// analyse_study: points, lines of the grid and their tests, recomputed by hand on a small set.
TEST(StudyAnalysis, PointsLinesAndTests) {
  gd::BatchInputs in;
  in.axes = {{"gear_pair.friction_coefficient", {0.0, 0.04}, {}}, {"load.sigma", {1, 2, 3}, {}}};
  for (double mu : {0.0, 0.04})
    for (double sg : {1.0, 2.0, 3.0}) in.points.push_back({mu, sg});
  for (std::size_t p = 0; p < in.points.size(); ++p)
    for (std::uint32_t r = 0; r < 10; ++r) {
      gd::RunRecord rec;
      rec.kind = gd::RunKind::Stochastic;
      rec.point = p;
      rec.mu = in.points[p][0];
      rec.index = r;
      // d grows with sigma at mu = 0.04 only, and is the same at every sigma for mu = 0.
      rec.center_distance = 1e-4 * (1 + r) + (rec.mu > 0 ? 1e-5 * in.points[p][1] * (1 + 0.1 * r) : 0);
      rec.final_delta = 4.5e-5;
      rec.final_delta_dot = p % 2 ? 0.0 : 0.03;
      rec.final_phi = 20 + r;
      rec.snapshot_times = {0.4};
      rec.snapshot_delta = {4.5e-5};
      rec.snapshot_delta_dot = {0};
      in.runs.push_back(rec);
    }
  gd::AnalysisSettings settings;
  settings.joint_times = {0.4};
  gd::StudyAnalysis st;
  const gd::BatchAnalysis a = gd::analyse_batch(in, settings, st);
  ASSERT_EQ(st.points.size(), 6u);
  ASSERT_EQ(a.mu.size(), 6u);
  EXPECT_EQ(a.key_header, "point,mu,load.sigma");
  EXPECT_EQ(a.keys[4], "4,0.04,2");
  EXPECT_EQ(st.points[1].both_in_interval.successes, 10u);
  EXPECT_EQ(st.points[0].both_in_interval.successes, 0u);
  EXPECT_DOUBLE_EQ(st.points[0].final_phi_mean, 24.5);
  // Lines: sigma at mu = 0 and at mu = 0.04 (3 points each); mu at each sigma (2 points each).
  ASSERT_EQ(st.slices.size(), 2u + 3u);
  std::size_t sigma_lines = 0;
  for (const gd::AxisSlice& l : st.slices) {
    if (l.axis != 1) continue;
    ++sigma_lines;
    ASSERT_EQ(l.points.size(), 3u);
    EXPECT_EQ(l.friedman.n, 10u);
    if (st.points[l.points[0]].values[0] == 0.0) {
      EXPECT_FALSE(l.friedman.valid);  // every realization tied across sigma: no effect to test
    } else {
      ASSERT_TRUE(l.friedman.valid);
      EXPECT_NEAR(l.friedman.statistic, 20.0, 1e-9);  // ranks 1, 2, 3 in every block: chi2 = n (k - 1)
      EXPECT_LT(l.friedman.p_value, 1e-4);
    }
  }
  EXPECT_EQ(sigma_lines, 2u);
}
