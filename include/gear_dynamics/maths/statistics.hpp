// Sample statistics for the Monte Carlo analysis (doc/model.md §8) and the uncertainty the paper does
// not give: quantiles, box-plot statistics, proportions with Wilson intervals, a distribution-free
// interval for the median, density histograms and rank tests across groups. Pure functions on
// plain numbers: no units, no ROS.
#pragma once

#include <cstddef>
#include <string>
#include <vector>

namespace gear_dynamics {

// The default confidence level of every interval reported.
constexpr double kConfidence = 0.95;

// Equal-width bin edges lo, lo + w, ..., hi, computed as lo + i (hi - lo) / n like numpy.linspace,
// so an independent check can rebuild them. n = (hi - lo) / width must be a whole number.
struct BinSpec {
  double lo = 0, hi = 1, width = 1;
  std::size_t bins() const;
  std::vector<double> edges() const;
};
// Throws std::invalid_argument naming `name`, the values and the rule if the spec is unusable.
void validate(const BinSpec& spec, const std::string& name);

// A closed interval [lo, hi].
struct Interval {
  double lo = 0, hi = 0;  // closed
  bool contains(double x) const { return x >= lo && x <= hi; }
};

// Quantile of a sorted sample by linear interpolation (Hyndman-Fan type 7, numpy's and R's
// default): h = (n - 1) p, x[floor h] + (h - floor h) (x[floor h + 1] - x[floor h]).
// Throws std::invalid_argument for an empty sample or p outside [0, 1].
double quantile_sorted(const std::vector<double>& sorted, double p);

// Box-plot statistics as in the paper's Fig. 9 (whiskers from min to max), with an exact
// distribution-free interval for the median: [x(l), x(n+1-l)] with the largest l whose coverage
// 1 - 2 P(B <= l - 1), B ~ Binomial(n, 1/2), is at least the confidence level. When no l reaches
// it (n <= 5 at 95 %) the interval is [min, max] and `median_coverage` says what it covers.
struct BoxStats {
  std::size_t n = 0;
  double min = 0, q1 = 0, median = 0, q3 = 0, max = 0;  // NaN when n = 0
  double median_low = 0, median_high = 0, median_coverage = 0;
};
BoxStats box_stats(std::vector<double> values, double confidence = kConfidence);

// A proportion k/n with its Wilson score interval (NaN estimate and [0, 1] when n = 0).
struct Proportion {
  std::size_t successes = 0, trials = 0;
  double estimate = 0, low = 0, high = 0;
};
Proportion wilson(std::size_t successes, std::size_t trials, double confidence = kConfidence);

// Histogram with numpy's rule: bin i is [e_i, e_{i+1}), the last bin also holds e_n. Values
// outside [e_0, e_n] (and NaN) are counted apart, never dropped silently.
struct Histogram {
  std::vector<double> edges;
  std::vector<std::size_t> counts;
  std::size_t outside = 0, total = 0;
  double density(std::size_t i) const;  // count / (total * width): integrates to 1 - fraction_outside
  double fraction_outside() const;
};
Histogram histogram(const std::vector<double>& values, const BinSpec& spec);

// Joint histogram of pairs (x[k], y[k]); counts are x-major: counts[i * ny + j].
struct Histogram2D {
  std::vector<double> x_edges, y_edges;
  std::vector<std::size_t> counts;
  std::size_t outside = 0, total = 0;
  double density(std::size_t i, std::size_t j) const;  // count / (total * area)
  double fraction_outside() const;
};
Histogram2D histogram2d(const std::vector<double>& x, const std::vector<double>& y,
                        const BinSpec& x_spec, const BinSpec& y_spec);

// Upper tail P(X > x) of the chi-square distribution with `df` degrees of freedom.
double chi_square_sf(double x, double df);

// A rank test of "all groups come from one distribution", with its chi-square approximation.
// valid = false (statistic and p NaN) when the test is undefined: fewer than two groups or
// blocks, or every value tied.
struct RankTest {
  double statistic = 0, p_value = 0;
  std::size_t df = 0, n = 0;  // n: observations (Kruskal-Wallis) or complete blocks (Friedman)
  bool valid = false;
  bool exact = false;  // p_value from the exact distribution, not the chi-square approximation
};
// Kruskal-Wallis H with the tie correction, df = groups - 1 (empty groups ignored).
RankTest kruskal_wallis(const std::vector<std::vector<double>>& groups);
// Friedman's test for k treatments in n blocks: blocks[b][j] is treatment j in block b. With the
// tie correction; df = k - 1. For paired samples (common random numbers across treatments). For two
// treatments the test is the sign test, and p is its exact two-sided binomial value (tied blocks
// left out): the chi-square approximation errs at small n (4 blocks all one way: 0.046, exact 0.125).
RankTest friedman(const std::vector<std::vector<double>>& blocks);

// Mid-ranks (1-based, ties share the mean rank) of `values`, and sum of t^3 - t over tie groups.
std::vector<double> mid_ranks(const std::vector<double>& values, double* tie_sum = nullptr);

}  // namespace gear_dynamics
