// Sample statistics against hand-derived values, closed forms and identities between tests.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>

#include "gear_dynamics/maths/statistics.hpp"

namespace gd = gear_dynamics;

TEST(Quantile, Type7ByHand) {
  // h = (n - 1) p; R's quantile(c(1, 3, 7, 15, 31), 0.3) = 3 + 0.2 * (7 - 3).
  const std::vector<double> x{1, 3, 7, 15, 31};
  EXPECT_DOUBLE_EQ(gd::quantile_sorted(x, 0.3), 3.8);
  EXPECT_DOUBLE_EQ(gd::quantile_sorted(x, 0.0), 1.0);
  EXPECT_DOUBLE_EQ(gd::quantile_sorted(x, 1.0), 31.0);
  EXPECT_DOUBLE_EQ(gd::quantile_sorted(x, 0.5), 7.0);
  EXPECT_DOUBLE_EQ(gd::quantile_sorted({4.0}, 0.75), 4.0);
  EXPECT_THROW(gd::quantile_sorted({}, 0.5), std::invalid_argument);
  EXPECT_THROW(gd::quantile_sorted(x, 1.5), std::invalid_argument);
}

TEST(BoxStats, QuartilesAndWhiskersOfOneToTen) {
  std::vector<double> x{10, 9, 8, 7, 6, 5, 4, 3, 2, 1};  // unsorted on purpose
  const gd::BoxStats b = gd::box_stats(x);
  EXPECT_EQ(b.n, 10u);
  EXPECT_DOUBLE_EQ(b.min, 1.0);
  EXPECT_DOUBLE_EQ(b.q1, 3.25);  // h = 2.25
  EXPECT_DOUBLE_EQ(b.median, 5.5);
  EXPECT_DOUBLE_EQ(b.q3, 7.75);
  EXPECT_DOUBLE_EQ(b.max, 10.0);
  const gd::BoxStats e = gd::box_stats({});
  EXPECT_EQ(e.n, 0u);
  EXPECT_TRUE(std::isnan(e.median));
}

// The exact interval [x(l), x(n+1-l)]: l from the binomial(n, 1/2) tail, cross-checked with
// scipy.stats.binom: n = 100 -> (40, 61), coverage 0.9648; n = 64 -> (24, 41), 0.9672;
// n = 20 -> (6, 15), 0.9586. n = 6 reaches 95 % only with (1, 6); n = 5 cannot (0.9375).
TEST(BoxStats, ExactMedianInterval) {
  struct Case { std::size_t n, l; double coverage; };
  for (const Case c : {Case{100, 40, 0.9647997997822952}, Case{64, 24, 0.9672342409011767},
                       Case{20, 6, 0.9586105346679688}, Case{6, 1, 0.96875}, Case{5, 1, 0.9375}}) {
    std::vector<double> x(c.n);
    for (std::size_t i = 0; i < c.n; ++i) x[i] = static_cast<double>(i + 1);  // x(i) = i
    const gd::BoxStats b = gd::box_stats(x);
    EXPECT_DOUBLE_EQ(b.median_low, static_cast<double>(c.l)) << "n = " << c.n;
    EXPECT_DOUBLE_EQ(b.median_high, static_cast<double>(c.n + 1 - c.l)) << "n = " << c.n;
    EXPECT_NEAR(b.median_coverage, c.coverage, 1e-12) << "n = " << c.n;
  }
}

// The interval's coverage by simulation: it must hold the true median of a skewed distribution at
// least as often as claimed (within 4 binomial standard errors of 2000 trials).
TEST(BoxStats, MedianIntervalCoversTheTrueMedian) {
  std::mt19937_64 rng(7);
  std::exponential_distribution<double> expo(1.0);
  const double true_median = std::log(2.0);
  int covered = 0, trials = 2000;
  double claimed = 0;
  for (int t = 0; t < trials; ++t) {
    std::vector<double> x(30);
    for (double& v : x) v = expo(rng);
    const gd::BoxStats b = gd::box_stats(x);
    covered += (b.median_low <= true_median && true_median <= b.median_high) ? 1 : 0;
    claimed = b.median_coverage;
  }
  const double se = std::sqrt(claimed * (1 - claimed) / trials);
  EXPECT_GE(static_cast<double>(covered) / trials, claimed - 4 * se);
  EXPECT_GE(claimed, 0.95);
}

// Reference: scipy.stats.binomtest(93, 100).proportion_ci(method='wilson') = (0.862504852609, 0.965680738933).
TEST(Wilson, PaperCountAndClosedFormAtZero) {
  const gd::Proportion p = gd::wilson(93, 100);
  EXPECT_DOUBLE_EQ(p.estimate, 0.93);
  EXPECT_NEAR(p.low, 0.8625048526092649, 1e-12);
  EXPECT_NEAR(p.high, 0.9656807389327273, 1e-12);
  // k = 0: [0, z^2 / (n + z^2)].
  const double z = 1.959963984540054;
  const gd::Proportion q = gd::wilson(0, 10);
  EXPECT_EQ(q.low, 0.0);
  EXPECT_NEAR(q.high, z * z / (10 + z * z), 1e-12);
  const gd::Proportion all = gd::wilson(10, 10);
  EXPECT_EQ(all.high, 1.0);
  EXPECT_NEAR(all.low, 1 - z * z / (10 + z * z), 1e-12);
  const gd::Proportion none = gd::wilson(0, 0);
  EXPECT_TRUE(std::isnan(none.estimate));
  EXPECT_EQ(none.low, 0.0);
  EXPECT_EQ(none.high, 1.0);
  EXPECT_THROW(gd::wilson(3, 2), std::invalid_argument);
  EXPECT_THROW(gd::wilson(1, 2, 1.0), std::invalid_argument);
  // A wider confidence level gives a wider interval.
  const gd::Proportion w99 = gd::wilson(93, 100, 0.99);
  EXPECT_LT(w99.low, p.low);
  EXPECT_GT(w99.high, p.high);
}

TEST(Histogram, NumpyBinRuleAndOutsideCount) {
  const gd::BinSpec spec{0.0, 1.0, 0.25};
  ASSERT_EQ(spec.bins(), 4u);
  const std::vector<double> e = spec.edges();
  ASSERT_EQ(e.size(), 5u);
  EXPECT_EQ(e.back(), 1.0);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  // Left edges belong to their bin, the right-most edge to the last bin; outside and NaN apart.
  const gd::Histogram h = gd::histogram({0.0, 0.25, 0.3, 0.5, 0.99, 1.0, -0.01, 1.01, nan}, spec);
  EXPECT_EQ(h.counts, (std::vector<std::size_t>{1, 2, 1, 2}));
  EXPECT_EQ(h.outside, 3u);
  EXPECT_EQ(h.total, 9u);
  double integral = 0;
  for (std::size_t i = 0; i < h.counts.size(); ++i) integral += h.density(i) * 0.25;
  EXPECT_NEAR(integral, 1.0 - h.fraction_outside(), 1e-15);
}

TEST(Histogram, EdgesLikeLinspace) {
  // doc/model.md's delta edges 0.030:0.0005:0.060 mm (in m): 60 bins, lo + i (hi - lo) / n.
  const gd::BinSpec spec{3.0e-5, 6.0e-5, 5.0e-7};
  ASSERT_EQ(spec.bins(), 60u);
  const std::vector<double> e = spec.edges();
  for (std::size_t i = 0; i < 60; ++i) EXPECT_EQ(e[i], 3.0e-5 + static_cast<double>(i) * (3.0e-5 / 60.0));
  EXPECT_THROW(gd::validate(gd::BinSpec{0, 1, 0.3}, "x"), std::invalid_argument);  // 3.33 bins
  EXPECT_THROW(gd::validate(gd::BinSpec{1, 0, 0.1}, "x"), std::invalid_argument);
  EXPECT_THROW(gd::validate(gd::BinSpec{0, 1, 0}, "x"), std::invalid_argument);
  try {
    gd::validate(gd::BinSpec{0, 1, -1}, "analysis.delta_bins");
    FAIL() << "no error";
  } catch (const std::invalid_argument& ex) {
    EXPECT_NE(std::string(ex.what()).find("analysis.delta_bins.width = -1"), std::string::npos) << ex.what();
  }
}

TEST(Histogram2D, CountsAreXMajorAndIntegrate) {
  const gd::Histogram2D h = gd::histogram2d({0.1, 0.1, 0.9, 2.0}, {0.1, 0.6, 0.6, 0.5}, {0, 1, 0.5}, {0, 1, 0.5});
  ASSERT_EQ(h.counts.size(), 4u);
  EXPECT_EQ(h.counts, (std::vector<std::size_t>{1, 1, 0, 1}));  // (0,0), (0,1), (1,0), (1,1)
  EXPECT_EQ(h.outside, 1u);
  EXPECT_DOUBLE_EQ(h.density(0, 1), 1.0 / (4 * 0.25));
  EXPECT_THROW(gd::histogram2d({1.0}, {}, {0, 1, 0.5}, {0, 1, 0.5}), std::invalid_argument);
}

TEST(ChiSquare, ClosedForms) {
  for (double x : {0.1, 1.0, 3.0, 10.0, 40.0}) {
    EXPECT_NEAR(gd::chi_square_sf(x, 2), std::exp(-x / 2), 1e-14 * std::max(1.0, std::exp(-x / 2)) + 1e-300);
    EXPECT_NEAR(gd::chi_square_sf(x, 1) / std::erfc(std::sqrt(x / 2)), 1.0, 1e-12);
  }
  EXPECT_EQ(gd::chi_square_sf(0.0, 5), 1.0);
  EXPECT_THROW(gd::chi_square_sf(1.0, 0), std::invalid_argument);
}

TEST(Ranks, MidRanksAndTies) {
  double ties = 0;
  const std::vector<double> r = gd::mid_ranks({3.0, 1.0, 3.0, 2.0, 3.0}, &ties);
  EXPECT_EQ(r, (std::vector<double>{4, 1, 4, 2, 4}));
  EXPECT_DOUBLE_EQ(ties, 27 - 3);
}

// Two groups without ties: H equals z^2 of the Mann-Whitney test without continuity correction.
TEST(KruskalWallis, TwoGroupsEqualMannWhitneySquared) {
  const std::vector<double> a{1.2, 3.4, 0.5, 7.7, 2.2, 9.1}, b{4.4, 5.5, 8.8, 6.1, 10.3};
  const gd::RankTest t = gd::kruskal_wallis({a, b});
  double u = 0;  // pairs (x in a, y in b) with x > y
  for (double x : a)
    for (double y : b) u += x > y ? 1 : 0;
  const double n1 = 6, n2 = 5, z = (u - n1 * n2 / 2) / std::sqrt(n1 * n2 * (n1 + n2 + 1) / 12);
  ASSERT_TRUE(t.valid);
  EXPECT_NEAR(t.statistic, z * z, 1e-12);
  EXPECT_EQ(t.df, 1u);
  EXPECT_NEAR(t.p_value, std::erfc(std::abs(z) / std::sqrt(2.0)), 1e-12);
}

// Four groups with ties. Reference: scipy.stats.kruskal -> H = 0.9454710144927513, p = 0.8144430142746263.
TEST(KruskalWallis, TiesAgainstScipy) {
  const gd::RankTest t = gd::kruskal_wallis(
      {{2.9, 3.0, 2.5, 2.6, 3.2}, {3.8, 2.7, 4.0, 2.4}, {2.8, 3.4, 3.7, 2.2, 2.0}, {2.9, 3.0, 2.5, 4.1}, {}});
  ASSERT_TRUE(t.valid);
  EXPECT_NEAR(t.statistic, 0.9454710144927513, 1e-12);
  EXPECT_NEAR(t.p_value, 0.8144430142746263, 1e-12);
  EXPECT_EQ(t.df, 3u);  // the empty group does not count
  EXPECT_EQ(t.n, 18u);
  EXPECT_FALSE(gd::kruskal_wallis({{1.0, 2.0}}).valid);
  EXPECT_FALSE(gd::kruskal_wallis({{1.0, 1.0}, {1.0}}).valid);  // all tied
}

// k = 2 without ties: Friedman's statistic is the sign test's (n+ - n-)^2 / n.
TEST(Friedman, TwoTreatmentsEqualSignTest) {
  const std::vector<std::vector<double>> blocks{{1, 2}, {3, 1}, {5, 6}, {2, 9}, {4, 3}, {0, 7}, {8, 9}};
  int plus = 0;
  for (const auto& b : blocks) plus += b[1] > b[0] ? 1 : 0;
  const double n = 7, expected = (2.0 * plus - n) * (2.0 * plus - n) / n;
  const gd::RankTest t = gd::friedman(blocks);
  ASSERT_TRUE(t.valid);
  EXPECT_NEAR(t.statistic, expected, 1e-12);
  EXPECT_EQ(t.df, 1u);
  // Its p is the sign test's exact one: 5 of 7 up, 2 P(X <= 2), X ~ Bin(7, 1/2) = 2 (1 + 7 + 21) / 128.
  EXPECT_TRUE(t.exact);
  EXPECT_NEAR(t.p_value, 58.0 / 128.0, 1e-15);
  // Four blocks all one way: chi-square 4 would say p = 0.0455; exactly it is 2 / 16. A tied block
  // carries no sign.
  EXPECT_NEAR(gd::friedman({{1, 2}, {1, 3}, {0, 5}, {2, 4}, {7, 7}}).p_value, 0.125, 1e-15);
  EXPECT_NEAR(gd::friedman({{2, 1}, {1, 3}}).p_value, 1.0, 1e-15);
}

// With ties. Reference: scipy.stats.friedmanchisquare -> 1.7272727272727222, p = 0.42162610548700463.
TEST(Friedman, TiesAgainstScipy) {
  const gd::RankTest t = gd::friedman({{1, 2, 3}, {2, 2, 1}, {3, 1, 2}, {1, 3, 2}, {2, 3, 3}, {1, 2, 3.5}});
  ASSERT_TRUE(t.valid);
  EXPECT_NEAR(t.statistic, 1.7272727272727222, 1e-12);
  EXPECT_NEAR(t.p_value, 0.42162610548700463, 1e-12);
  EXPECT_FALSE(t.exact);
  EXPECT_EQ(t.n, 6u);
  EXPECT_FALSE(gd::friedman({{1, 2}}).valid);
  EXPECT_THROW(gd::friedman({{1, 2}, {1, 2, 3}}), std::invalid_argument);
}
