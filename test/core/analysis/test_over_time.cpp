// The batch analysis over time (doc/nonlinear-dynamics.md §6): runs recorded on different grids
// reduce, in any order, to the safety and first passage of the series on their common times.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "gear_dynamics/analysis/over_time.hpp"
#include "gear_dynamics/maths/safety.hpp"

namespace gd = gear_dynamics;

TEST(OverTime, SeriesDigestsEqualTheCommonSeries) {
  const gd::Interval di{4e-5, 5.5e-5}, vi{-0.016, 0.016};
  std::mt19937_64 rng(16);
  std::uniform_real_distribution<double> inside_d(4.1e-5, 5.4e-5), any_d(3e-5, 6.5e-5), any_v(-0.03, 0.03);
  struct Series {
    std::vector<double> t, d, v;
  };
  std::vector<Series> series(6);
  for (std::size_t r = 0; r < series.size(); ++r) {
    const int n = r == 5 ? 401 : 41;
    for (int k = 0; k < n; ++k) {
      const double t = r == 5 ? k * 1e-3 : k * 1e-2;
      if (r == 3 && k == 32) {
        series[r].t.push_back(0.325);
        series[r].d.push_back(7e-5);  // outside, at a time no other run has
        series[r].v.push_back(0);
        continue;
      }
      const bool after = t > 0.295;  // runs 0 and 3 stay inside from 0.3 s except where set below
      series[r].t.push_back(t);
      series[r].d.push_back(after && (r == 0 || r == 3) ? inside_d(rng) : any_d(rng));
      series[r].v.push_back(after && (r == 0 || r == 3) ? 0.0 : any_v(rng));
    }
  }
  series[0].d[32] = 7e-5;
  series[0].d[35] = 7e-5;

  gd::BatchInputs in;
  gd::AnalysisSettings settings;
  settings.kde = false;
  gd::BatchAnalysis a;
  a.settings = settings;
  a.mu.emplace_back();
  a.mu[0].mu = 0.04;
  for (std::size_t r = 0; r < series.size(); ++r) {
    gd::RunRecord run;
    run.mu = 0.04;
    run.index = static_cast<std::uint32_t>(r);
    in.runs.push_back(run);
  }

  // Expected: the runs on the common times (those of run 0 but 0.32 s).
  gd::RecordedRuns common;
  for (int k = 0; k < 41; ++k)
    if (k != 32) common.time.push_back(k * 1e-2);
  for (const Series& s : series) {
    common.delta.emplace_back();
    common.velocity.emplace_back();
    for (double t : common.time) {
      std::size_t j = 0;
      while (std::abs(s.t[j] - t) > 1e-9) ++j;
      common.delta.back().push_back(s.d[j]);
      common.velocity.back().push_back(s.v[j]);
    }
  }
  const gd::SafetySeries expected = gd::safety_over_time(common, di, vi, settings.confidence);
  const gd::FirstPassage passage = gd::first_passage(common, di, vi, settings.first_passage_settle - 1e-9);
  ASSERT_TRUE(passage.event[0]);
  EXPECT_DOUBLE_EQ(passage.time[0], 0.35);
  EXPECT_FALSE(passage.event[3]);

  for (const std::vector<std::size_t>& order : {std::vector<std::size_t>{0, 1, 2, 3, 4, 5}, {5, 3, 1, 4, 0, 2}}) {
    gd::SeriesDigests digests(settings);
    for (std::size_t r : order) digests.add(in, in.runs[r], series[r].t, series[r].d, series[r].v);
    const gd::BatchOverTime o = gd::analyse_over_time(in, a, digests);
    ASSERT_EQ(o.groups.size(), 1u);
    const gd::GroupOverTime& g = o.groups[0];
    EXPECT_EQ(g.runs, 6u);
    ASSERT_EQ(g.safety.time, common.time);  // the shortest series' values, bit for bit
    for (std::size_t j = 0; j < common.time.size(); ++j) {
      EXPECT_EQ(g.safety.joint[j].successes, expected.joint[j].successes) << j;
      EXPECT_EQ(g.safety.delta_only[j].successes, expected.delta_only[j].successes) << j;
      EXPECT_EQ(g.safety.velocity_only[j].successes, expected.velocity_only[j].successes) << j;
      EXPECT_EQ(g.safety.joint[j].trials, 6u);
    }
    ASSERT_TRUE(g.passage);
    EXPECT_EQ(g.passage->time, passage.time);
    EXPECT_EQ(g.passage->event, passage.event);
  }
}
