// The per-mu analysis on synthetic run records whose statistics are known.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>

#include "gear_dynamics/analysis/batch_analysis.hpp"
#include "gear_dynamics/config/config.hpp"
#include "run_records.hpp"

namespace gd = gear_dynamics;
using gear_dynamics::test::record;
using gear_dynamics::test::synthetic;


TEST(BatchAnalysis, PerMuStatisticsFromTheRecords) {
  const auto runs = synthetic();
  gd::AnalysisSettings s;
  const gd::BatchAnalysis a = gd::analyse(runs, s);
  ASSERT_EQ(a.mu.size(), 2u);
  EXPECT_EQ(a.mu[0].mu, 0.0);
  EXPECT_EQ(a.mu[1].mu, 0.04);
  for (const gd::MuAnalysis& m : a.mu) {
    std::vector<double> d;
    std::size_t above_s1 = 0, above_phase = 0, in_delta = 0, in_dot = 0, reached = 0;
    ASSERT_TRUE(m.s1);
    std::vector<double> phase_d;
    for (const auto& r : runs)
      if (r.mu == m.mu && r.kind == gd::RunKind::Phase) phase_d.push_back(r.center_distance);
    std::sort(phase_d.begin(), phase_d.end());
    const double phase_median = 0.5 * (phase_d[3] + phase_d[4]);  // n = 8
    for (const auto& r : runs) {
      if (r.mu != m.mu || r.kind != gd::RunKind::Stochastic) continue;
      d.push_back(r.center_distance);
      above_s1 += r.center_distance > m.s1->center_distance;
      above_phase += r.center_distance > phase_median;
      in_delta += r.final_delta >= 4.0e-5 && r.final_delta <= 5.5e-5;
      in_dot += r.final_delta_dot >= -0.016 && r.final_delta_dot <= 0.016;
      reached += r.reached_steady_state;
    }
    EXPECT_EQ(m.stochastic_runs, 12u);
    EXPECT_EQ(m.phase_runs, 8u);
    EXPECT_EQ(m.d_exceeds_s1.successes, above_s1);
    EXPECT_EQ(m.d_exceeds_s1.trials, 12u);
    EXPECT_DOUBLE_EQ(m.phase_center_distance.median, phase_median);
    EXPECT_EQ(m.d_exceeds_phase_median.successes, above_phase);
    EXPECT_EQ(m.delta_in_interval.successes, in_delta);
    EXPECT_EQ(m.delta_dot_in_interval.successes, in_dot);
    EXPECT_EQ(m.reached_steady_state.successes, reached);
    std::sort(d.begin(), d.end());
    EXPECT_DOUBLE_EQ(m.center_distance.min, d.front());
    EXPECT_DOUBLE_EQ(m.center_distance.median, 0.5 * (d[5] + d[6]));
    EXPECT_DOUBLE_EQ(*m.s2_center_distance, d[0]);  // realization 0 has the smallest d here
    EXPECT_DOUBLE_EQ(*m.s3_center_distance, d[1]);
    ASSERT_EQ(m.joint_pdf.size(), s.joint_times.size());
    for (const auto& h : m.joint_pdf) EXPECT_EQ(h.total, 12u);
    std::size_t hist_total = m.delta_pdf.outside;
    for (auto c : m.delta_pdf.counts) hist_total += c;
    EXPECT_EQ(hist_total, 12u);
  }
  // The synthetic d shifts by 4e-5 between the mu values at every realization: Friedman's test
  // sees 12 of 12 blocks ordered alike; Kruskal-Wallis sees two overlapping groups.
  EXPECT_EQ(a.friedman.n, 12u);
  EXPECT_NEAR(a.friedman.statistic, 12.0, 1e-12);  // sign test (12 - 0)^2 / 12
  EXPECT_TRUE(a.kruskal_wallis.valid);
  EXPECT_GT(a.kruskal_wallis.p_value, 0.3);
}

TEST(BatchAnalysis, StrictExceedanceAndClosedIntervals) {
  std::vector<gd::RunRecord> runs{record(gd::RunKind::S1, 0.02, 0, 1.0, 0, 0)};
  // d equal to d_S1 does not count; values on the interval ends do.
  runs.push_back(record(gd::RunKind::Stochastic, 0.02, 0, 1.0, 4.0e-5, -0.016));
  runs.push_back(record(gd::RunKind::Stochastic, 0.02, 1, 1.5, 5.5e-5, 0.016));
  runs.push_back(record(gd::RunKind::Stochastic, 0.02, 2, 0.5, 5.6e-5, 0.0161));
  const gd::BatchAnalysis a = gd::analyse(runs, gd::AnalysisSettings{});
  const gd::MuAnalysis& m = a.mu.at(0);
  EXPECT_EQ(m.d_exceeds_s1.successes, 1u);
  EXPECT_EQ(m.delta_in_interval.successes, 2u);
  EXPECT_EQ(m.delta_dot_in_interval.successes, 2u);
  // No phase ensemble: the robust comparison has no trials.
  EXPECT_EQ(m.d_exceeds_phase_median.trials, 0u);
  EXPECT_TRUE(std::isnan(m.d_exceeds_phase_median.estimate));
  EXPECT_FALSE(a.friedman.valid);  // one mu only
}

TEST(BatchAnalysis, JointTimeMustBeASnapshotTime) {
  gd::AnalysisSettings s;
  s.joint_times = {0.31};
  try {
    gd::analyse({record(gd::RunKind::Stochastic, 0.0, 0, 1, 0, 0)}, s);
    FAIL() << "no error";
  } catch (const std::invalid_argument& ex) {
    EXPECT_NE(std::string(ex.what()).find("analysis.joint_times: 0.31 s"), std::string::npos) << ex.what();
  }
}
