// Safety over time, first passage, Kaplan-Meier and KDE (doc/nonlinear-dynamics.md §6, §7); the
// batch analysis over time that applies them is analysis/test_over_time.cpp's.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "gear_dynamics/maths/safety.hpp"

namespace gd = gear_dynamics;

// A hand-worked Kaplan-Meier table: times 1 2 2+ 3 4+ 5 (+ = censored).
// S(1) = 5/6, S(2) = 5/6 * 4/5 = 2/3, S(3) = 2/3 * 2/3 = 4/9, S(5) = 0.
TEST(KaplanMeier, HandExample) {
  const auto km = gd::kaplan_meier({2, 1, 3, 2, 5, 4}, {true, true, true, false, true, false});
  ASSERT_EQ(km.time.size(), 4u);
  EXPECT_DOUBLE_EQ(km.time[0], 1);
  EXPECT_NEAR(km.survival[0], 5.0 / 6, 1e-15);
  EXPECT_NEAR(km.survival[1], 2.0 / 3, 1e-15);
  EXPECT_NEAR(km.survival[2], 4.0 / 9, 1e-15);
  EXPECT_EQ(km.survival[3], 0.0);
  EXPECT_EQ(km.at_risk[0], 6u);
  EXPECT_EQ(km.at_risk[1], 5u);
  EXPECT_EQ(km.at_risk[2], 3u);
  EXPECT_EQ(km.at_risk[3], 1u);
  // Greenwood at t = 2: S^2 (1/(6*5) + 1/(5*4)) = 4/9 * 1/12; the log-log interval contains S.
  EXPECT_LT(km.low[1], km.survival[1]);
  EXPECT_GT(km.high[1], km.survival[1]);
  EXPECT_DOUBLE_EQ(gd::survival_at(km, 0.5), 1.0);
  EXPECT_NEAR(gd::survival_at(km, 3.5), 4.0 / 9, 1e-15);
}

// Brownian motion (sd 1 per sqrt time) from x0 = 0.5 in (0, 1): P(tau > t) =
// sum_{n odd} 4/(n pi) sin(n pi x0) exp(-n^2 pi^2 t / 2). Monitored every dt, the walk misses some
// excursions; the continuous-time equivalent has the barriers moved out by 0.5826 sqrt(dt)
// (Broadie, Glasserman & Kou 1997), so it is compared with the closed form on the widened interval.
// 4000 paths: the KM estimate's sd is at most 0.008; the test allows 4 of them.
TEST(KaplanMeier, BrownianFirstPassageMatchesClosedForm) {
  const int R = 4000;
  const double dt = 2.5e-5, T = 0.25, x0 = 0.5;
  const int steps = static_cast<int>(T / dt);
  std::mt19937_64 rng(2024);
  std::normal_distribution<double> z(0.0, std::sqrt(dt));
  std::vector<double> times;
  std::vector<bool> events;
  for (int r = 0; r < R; ++r) {
    double x = x0, t = T;
    bool hit = false;
    for (int n = 1; n <= steps; ++n) {
      x += z(rng);
      if (x < 0 || x > 1) { hit = true; t = n * dt; break; }
    }
    times.push_back(t);
    events.push_back(hit);
  }
  const auto km = gd::kaplan_meier(times, events);
  const double shift = 0.5826 * std::sqrt(dt), L = 1 + 2 * shift, y0 = x0 + shift;
  const auto exact = [&](double t) {
    double s = 0;
    for (int n = 1; n < 200; n += 2)
      s += 4.0 / (n * M_PI) * std::sin(n * M_PI * y0 / L) * std::exp(-n * n * M_PI * M_PI * t / (2 * L * L));
    return s;
  };
  for (double t : {0.02, 0.05, 0.1, 0.15, 0.2}) {
    const double S = exact(t), sd = std::sqrt(S * (1 - S) / R);
    EXPECT_NEAR(gd::survival_at(km, t), S, 4 * sd + 1e-3) << "t = " << t;
  }
}

TEST(Safety, OverTimeAndFirstPassage) {
  gd::RecordedRuns runs;
  runs.time = {0.0, 0.1, 0.2, 0.3};
  runs.delta = {{0, 1, 1, 1}, {0, 1, 5, 1}, {0, 1, 1, 1}};
  runs.velocity = {{0, 0, 0, 0}, {0, 0, 0, 0}, {0, 0, 0, 9}};
  const gd::Interval di{0.5, 2}, vi{-1, 1};
  const auto s = gd::safety_over_time(runs, di, vi);
  ASSERT_EQ(s.joint.size(), 4u);
  EXPECT_EQ(s.joint[0].successes, 0u);
  EXPECT_EQ(s.joint[1].successes, 3u);
  EXPECT_EQ(s.joint[2].successes, 2u);
  EXPECT_EQ(s.delta_only[2].successes, 2u);
  EXPECT_EQ(s.velocity_only[3].successes, 2u);
  EXPECT_EQ(s.joint[3].successes, 2u);
  const auto w = gd::wilson(2, 3);
  EXPECT_DOUBLE_EQ(s.joint[2].low, w.low);
  const auto f = gd::first_passage(runs, di, vi, 0.1);
  EXPECT_FALSE(f.event[0]);
  EXPECT_DOUBLE_EQ(f.time[0], 0.3);
  EXPECT_TRUE(f.event[1]);
  EXPECT_DOUBLE_EQ(f.time[1], 0.2);
  EXPECT_TRUE(f.event[2]);
  EXPECT_DOUBLE_EQ(f.time[2], 0.3);
}

// Silverman's rule and the KDE: one value gives the kernel itself; a normal sample's KDE
// integrates to 1 and, at 0, matches the N(0, 1 + bw^2) density within sampling error.
TEST(Kde, SilvermanAndNormalSample) {
  const auto one = gd::gaussian_kde({1.0}, {1.0, 1.5}, 0.5);
  EXPECT_NEAR(one[0], 1 / (0.5 * std::sqrt(2 * M_PI)), 1e-14);
  EXPECT_NEAR(one[1], std::exp(-0.5) / (0.5 * std::sqrt(2 * M_PI)), 1e-14);
  std::mt19937_64 rng(9);
  std::normal_distribution<double> z;
  std::vector<double> x(4000);
  for (double& v : x) v = z(rng);
  const double bw = gd::silverman_bandwidth(x);
  EXPECT_NEAR(bw, 0.9 * std::pow(4000.0, -0.2), 0.05 * bw);  // sd and IQR/1.34 both near 1
  std::vector<double> grid;
  for (double g = -8; g <= 8; g += 0.01) grid.push_back(g);
  const auto d = gd::gaussian_kde(x, grid);
  double integral = 0;
  for (double v : d) integral += v * 0.01;
  EXPECT_NEAR(integral, 1.0, 1e-6);
  const double at0 = d[800], expect = 1 / std::sqrt(2 * M_PI * (1 + bw * bw));
  EXPECT_NEAR(at0, expect, 0.05 * expect);  // sd of the estimate ~ 0.01 relative at n = 4000
}

// The aggregator reduces each run's series as it is read (SeriesDigests) instead of keeping them:
// safety over time and first passage must equal safety_over_time and first_passage on the series
// restricted to the times every run recorded, whatever order the runs arrive in. Run 3 lost the
// sample at 0.32 s and has one at 0.325 s instead, so neither time is common: run 0 is outside only
// at 0.32 s and 0.35 s (its first passage is 0.35 s), run 3 only at 0.325 s (censored). Run 5 is
// recorded every 1 ms (its times j * 1e-3 differ from k * 1e-2 in the last bits: matched within
// 1e-9 s), and its extra samples are never common.
