#include "gear_dynamics/maths/statistics.hpp"

#include <algorithm>
#include <boost/math/distributions/binomial.hpp>
#include <boost/math/distributions/normal.hpp>
#include <boost/math/special_functions/gamma.hpp>
#include <cmath>
#include <limits>
#include <numeric>
#include <sstream>
#include <stdexcept>

namespace gear_dynamics {

std::size_t BinSpec::bins() const { return static_cast<std::size_t>(std::llround((hi - lo) / width)); }

std::vector<double> BinSpec::edges() const {
  const std::size_t n = bins();
  const double step = (hi - lo) / static_cast<double>(n);
  std::vector<double> e(n + 1);
  for (std::size_t i = 0; i < n; ++i) e[i] = lo + static_cast<double>(i) * step;
  e[n] = hi;
  return e;
}

void validate(const BinSpec& s, const std::string& name) {
  std::ostringstream e;
  e.precision(12);
  if (!(std::isfinite(s.lo) && std::isfinite(s.hi) && s.lo < s.hi)) {
    e << name << " = [" << s.lo << ", " << s.hi << "] is not an interval; needs finite lo < hi";
  } else if (!(s.width > 0.0 && s.width <= s.hi - s.lo)) {
    e << name << ".width = " << s.width << " is out of range; allowed (0, hi - lo = " << s.hi - s.lo << "]";
  } else {
    const double n = (s.hi - s.lo) / s.width;
    if (std::abs(n - std::round(n)) > 1e-6 * n || n > 1e6) {
      e << name << ": (hi - lo) / width = " << n << " is not a whole number of bins (at most 1e6)";
    } else {
      return;
    }
  }
  throw std::invalid_argument(e.str());
}

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

void check_confidence(double confidence) {
  if (!(confidence > 0.0 && confidence < 1.0)) {
    std::ostringstream e;
    e << "confidence = " << confidence << " is out of range; allowed (0, 1)";
    throw std::invalid_argument(e.str());
  }
}

// Index of the bin holding x, or bins() if x is outside [e_0, e_n] or NaN.
std::size_t bin_of(const std::vector<double>& edges, double x) {
  const std::size_t bins = edges.size() - 1;
  if (!(x >= edges.front() && x <= edges.back())) return bins;
  if (x == edges.back()) return bins - 1;
  return static_cast<std::size_t>(std::upper_bound(edges.begin(), edges.end(), x) - edges.begin()) - 1;
}

}  // namespace

double quantile_sorted(const std::vector<double>& x, double p) {
  if (x.empty()) throw std::invalid_argument("quantile of an empty sample");
  if (!(p >= 0.0 && p <= 1.0)) {
    std::ostringstream e;
    e << "quantile probability p = " << p << " is out of range; allowed [0, 1]";
    throw std::invalid_argument(e.str());
  }
  const double h = static_cast<double>(x.size() - 1) * p;
  const auto lo = static_cast<std::size_t>(std::floor(h));
  if (lo + 1 >= x.size()) return x.back();
  return x[lo] + (h - static_cast<double>(lo)) * (x[lo + 1] - x[lo]);
}

BoxStats box_stats(std::vector<double> v, double confidence) {
  check_confidence(confidence);
  BoxStats s;
  s.n = v.size();
  if (v.empty()) {
    s.min = s.q1 = s.median = s.q3 = s.max = s.median_low = s.median_high = kNaN;
    return s;
  }
  std::sort(v.begin(), v.end());
  s.min = v.front();
  s.q1 = quantile_sorted(v, 0.25);
  s.median = quantile_sorted(v, 0.5);
  s.q3 = quantile_sorted(v, 0.75);
  s.max = v.back();
  // Coverage of [x(l), x(n+1-l)] is P(l <= B <= n - l) = 1 - 2 P(B <= l - 1); it falls as l grows.
  const boost::math::binomial half(static_cast<double>(v.size()), 0.5);
  const auto coverage = [&](std::size_t l) { return 1.0 - 2.0 * boost::math::cdf(half, static_cast<double>(l - 1)); };
  std::size_t l = 1;
  while (2 * (l + 1) <= v.size() + 1 && coverage(l + 1) >= confidence) ++l;
  s.median_low = v[l - 1];
  s.median_high = v[v.size() - l];
  s.median_coverage = coverage(l);
  return s;
}

Proportion wilson(std::size_t k, std::size_t n, double confidence) {
  check_confidence(confidence);
  if (k > n) throw std::invalid_argument("wilson: successes exceed trials");
  Proportion p{k, n, kNaN, 0.0, 1.0};
  if (n == 0) return p;
  const double z = boost::math::quantile(boost::math::normal(), 0.5 + confidence / 2.0);
  const double nn = static_cast<double>(n), ph = static_cast<double>(k) / nn, z2 = z * z;
  const double centre = (ph + z2 / (2 * nn)) / (1 + z2 / nn);
  const double half = z / (1 + z2 / nn) * std::sqrt(ph * (1 - ph) / nn + z2 / (4 * nn * nn));
  p.estimate = ph;
  // The interval always contains the estimate; clamping only removes rounding at 0 and 1.
  p.low = std::max(0.0, std::min(ph, centre - half));
  p.high = std::min(1.0, std::max(ph, centre + half));
  return p;
}

double Histogram::density(std::size_t i) const {
  return static_cast<double>(counts[i]) / (static_cast<double>(total) * (edges[i + 1] - edges[i]));
}

double Histogram::fraction_outside() const {
  return static_cast<double>(outside) / static_cast<double>(total);
}

Histogram histogram(const std::vector<double>& values, const BinSpec& spec) {
  validate(spec, "histogram");
  Histogram h;
  h.edges = spec.edges();
  h.counts.assign(h.edges.size() - 1, 0);
  h.total = values.size();
  for (double x : values) {
    const std::size_t i = bin_of(h.edges, x);
    if (i < h.counts.size()) ++h.counts[i];
    else ++h.outside;
  }
  return h;
}

double Histogram2D::density(std::size_t i, std::size_t j) const {
  const std::size_t ny = y_edges.size() - 1;
  const double area = (x_edges[i + 1] - x_edges[i]) * (y_edges[j + 1] - y_edges[j]);
  return static_cast<double>(counts[i * ny + j]) / (static_cast<double>(total) * area);
}

double Histogram2D::fraction_outside() const {
  return static_cast<double>(outside) / static_cast<double>(total);
}

Histogram2D histogram2d(const std::vector<double>& x, const std::vector<double>& y,
                        const BinSpec& x_spec, const BinSpec& y_spec) {
  if (x.size() != y.size()) throw std::invalid_argument("histogram2d: x and y differ in length");
  validate(x_spec, "histogram2d x");
  validate(y_spec, "histogram2d y");
  Histogram2D h;
  h.x_edges = x_spec.edges();
  h.y_edges = y_spec.edges();
  const std::size_t nx = h.x_edges.size() - 1, ny = h.y_edges.size() - 1;
  h.counts.assign(nx * ny, 0);
  h.total = x.size();
  for (std::size_t k = 0; k < x.size(); ++k) {
    const std::size_t i = bin_of(h.x_edges, x[k]), j = bin_of(h.y_edges, y[k]);
    if (i < nx && j < ny) ++h.counts[i * ny + j];
    else ++h.outside;
  }
  return h;
}

double chi_square_sf(double x, double df) {
  if (!(df > 0.0)) throw std::invalid_argument("chi_square_sf: degrees of freedom must be > 0");
  if (std::isnan(x)) return kNaN;
  if (x <= 0.0) return 1.0;
  return boost::math::gamma_q(df / 2.0, x / 2.0);
}

std::vector<double> mid_ranks(const std::vector<double>& values, double* tie_sum) {
  std::vector<std::size_t> order(values.size());
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return values[a] < values[b]; });
  std::vector<double> rank(values.size());
  double ties = 0.0;
  for (std::size_t i = 0; i < order.size();) {
    std::size_t j = i;
    while (j + 1 < order.size() && values[order[j + 1]] == values[order[i]]) ++j;
    const double r = 0.5 * static_cast<double>(i + j) + 1.0;  // mean of ranks i+1 .. j+1
    for (std::size_t k = i; k <= j; ++k) rank[order[k]] = r;
    const double t = static_cast<double>(j - i + 1);
    ties += t * t * t - t;
    i = j + 1;
  }
  if (tie_sum) *tie_sum = ties;
  return rank;
}

RankTest kruskal_wallis(const std::vector<std::vector<double>>& groups) {
  RankTest r;
  r.statistic = r.p_value = kNaN;
  std::vector<double> all;
  std::vector<std::size_t> sizes;
  for (const auto& g : groups) {
    if (g.empty()) continue;
    all.insert(all.end(), g.begin(), g.end());
    sizes.push_back(g.size());
  }
  r.n = all.size();
  if (sizes.size() < 2) return r;
  r.df = sizes.size() - 1;
  double ties = 0.0;
  const std::vector<double> rank = mid_ranks(all, &ties);
  const double n = static_cast<double>(all.size());
  const double correction = 1.0 - ties / (n * n * n - n);
  if (!(correction > 0.0)) return r;  // every value tied
  double sum = 0.0;
  std::size_t at = 0;
  for (std::size_t s : sizes) {
    const double rs = std::accumulate(rank.begin() + static_cast<std::ptrdiff_t>(at),
                                      rank.begin() + static_cast<std::ptrdiff_t>(at + s), 0.0);
    sum += rs * rs / static_cast<double>(s);
    at += s;
  }
  r.statistic = (12.0 / (n * (n + 1.0)) * sum - 3.0 * (n + 1.0)) / correction;
  r.p_value = chi_square_sf(r.statistic, static_cast<double>(r.df));
  r.valid = true;
  return r;
}

namespace {

// Two-sided exact sign test of pairs (b[0], b[1]); pairs with b[0] == b[1] carry no sign.
double sign_test_p(const std::vector<std::vector<double>>& blocks) {
  std::size_t plus = 0, minus = 0;
  for (const auto& b : blocks) {
    if (b[1] > b[0]) ++plus;
    else if (b[1] < b[0]) ++minus;
  }
  const boost::math::binomial_distribution<double> signs(static_cast<double>(plus + minus), 0.5);
  return std::min(1.0, 2.0 * boost::math::cdf(signs, static_cast<double>(std::min(plus, minus))));
}

}  // namespace

RankTest friedman(const std::vector<std::vector<double>>& blocks) {
  RankTest r;
  r.statistic = r.p_value = kNaN;
  r.n = blocks.size();
  if (blocks.size() < 2 || blocks.front().size() < 2) return r;
  const std::size_t k = blocks.front().size();
  r.df = k - 1;
  // Conover's form, exact with ties: (k-1) sum_j (R_j - n (k+1)/2)^2 / (sum r^2 - n k (k+1)^2 / 4).
  std::vector<double> rank_sum(k, 0.0);
  double square_sum = 0.0;
  for (const auto& b : blocks) {
    if (b.size() != k) throw std::invalid_argument("friedman: blocks differ in the number of treatments");
    const std::vector<double> rank = mid_ranks(b);
    for (std::size_t j = 0; j < k; ++j) {
      rank_sum[j] += rank[j];
      square_sum += rank[j] * rank[j];
    }
  }
  const double kk = static_cast<double>(k), n = static_cast<double>(blocks.size());
  const double c = n * kk * (kk + 1) * (kk + 1) / 4.0;
  double between = 0.0;
  for (double rs : rank_sum) between += (rs - n * (kk + 1) / 2.0) * (rs - n * (kk + 1) / 2.0);
  if (!(square_sum - c > 0.0)) return r;  // every block entirely tied
  r.statistic = (kk - 1.0) * between / (square_sum - c);
  r.p_value = k == 2 ? sign_test_p(blocks) : chi_square_sf(r.statistic, kk - 1.0);
  r.exact = k == 2;
  r.valid = true;
  return r;
}

}  // namespace gear_dynamics
