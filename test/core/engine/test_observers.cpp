// Observers on synthetic signals with known answers.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <utility>

#include "gear_dynamics/engine/ensemble.hpp"
#include "gear_dynamics/engine/observers.hpp"
#include "gear_dynamics/engine/simulation.hpp"

namespace gd = gear_dynamics;

namespace {

// Two lanes of deterministic but irregular signals.
double sig_d(std::int64_t n, int lane) { return std::sin(0.013 * n + lane) + 0.3 * std::cos(0.0071 * static_cast<double>((n * n) % 97)); }
double sig_v(std::int64_t n, int lane) { return std::cos(0.029 * n - lane) * (1.0 + 0.001 * n); }

// Ranges (delta, delta_dot) of the signals over grid points first..last, by brute force.
std::pair<double, double> brute_ranges(std::int64_t first, std::int64_t last, int lane) {
  double dmax = -1e300, dmin = 1e300, vmax = -1e300, vmin = 1e300;
  for (std::int64_t k = first; k <= last; ++k) {
    dmax = std::max(dmax, sig_d(k, lane));
    dmin = std::min(dmin, sig_d(k, lane));
    vmax = std::max(vmax, sig_v(k, lane));
    vmin = std::min(vmin, sig_v(k, lane));
  }
  return {dmax - dmin, vmax - vmin};
}

}  // namespace

TEST(WindowRange, MatchesBruteForceAtBlockBoundaries) {
  const std::int64_t window = 120, block = 40;
  gd::WindowRange range(2, window, block);
  EXPECT_LE(range.capacity_blocks(), window / block + 2);
  for (std::int64_t n = 0; n <= 1000; ++n) {
    Eigen::ArrayXd d(2), v(2);
    for (int l = 0; l < 2; ++l) {
      d[l] = sig_d(n, l);
      v[l] = sig_v(n, l);
    }
    range.observe(n, d, v);
    if (n % block != 0) continue;
    for (int l = 0; l < 2; ++l) {
      const auto [dr, vr] = brute_ranges(std::max<std::int64_t>(0, n - window), n, l);
      ASSERT_EQ(range.delta_range()[l], dr) << "n " << n;
      ASSERT_EQ(range.velocity_range()[l], vr) << "n " << n;
      ASSERT_EQ(range.center_distance()[l], std::sqrt(dr * vr));
    }
  }
}

TEST(WindowRange, WindowEdgesAreInclusive) {
  // A spike exactly at the window's first point counts; one just before it does not.
  const std::int64_t window = 50, block = 10;
  for (const std::int64_t spike : {50, 49}) {
    gd::WindowRange range(1, window, block);
    for (std::int64_t n = 0; n <= 100; ++n) {
      Eigen::ArrayXd d = Eigen::ArrayXd::Constant(1, n == spike ? 1.0 : 0.0);
      range.observe(n, d, Eigen::ArrayXd::Constant(1, 1.0));
    }
    EXPECT_EQ(range.delta_range()[0], spike == 50 ? 1.0 : 0.0) << "spike at " << spike;
    EXPECT_EQ(range.velocity_range()[0], 0.0);
  }
  // Before the window has filled, it starts at t = 0.
  gd::WindowRange early(1, window, block);
  for (std::int64_t n = 0; n <= 20; ++n)
    early.observe(n, Eigen::ArrayXd::Constant(1, static_cast<double>(n)), Eigen::ArrayXd::Constant(1, -2.0 * n));
  EXPECT_EQ(early.delta_range()[0], 20.0);
  EXPECT_EQ(early.velocity_range()[0], 40.0);
}

// Read at every step, across many segments, observed from a late start (as simulate() does when it
// only needs the last window): the window is [n - W, n] widened back to the start of its first
// block, and clipped at the first observed step.
TEST(WindowRange, EveryStepAcrossSegmentsFromALateStart) {
  const std::int64_t window = 60, block = 20, start = 37;
  gd::WindowRange range(2, window, block);
  for (std::int64_t n = start; n <= 1000; ++n) {
    Eigen::ArrayXd d(2), v(2);
    for (int l = 0; l < 2; ++l) {
      d[l] = sig_d(n, l);
      v[l] = sig_v(n, l);
    }
    range.observe(n, d, v);
    const std::int64_t first = std::max(start, n - window < 0 ? 0 : (n - window) / block * block);
    for (int l = 0; l < 2; ++l) {
      const auto [dr, vr] = brute_ranges(first, n, l);
      ASSERT_EQ(range.delta_range()[l], dr) << "n " << n;
      ASSERT_EQ(range.velocity_range()[l], vr) << "n " << n;
    }
  }
  EXPECT_THROW(gd::WindowRange(1, 50, 20), std::invalid_argument);  // a block must divide the window
}

TEST(SteadyStateTime, LastExcursionBeyondTolerance) {
  gd::SteadyStateTime settle(2, 1.0, 0.1);
  for (int n = 0; n <= 100; ++n) {
    Eigen::ArrayXd d(2);
    d[0] = n <= 60 ? 1.5 : 1.05;  // last excursion at n = 60
    d[1] = 1.0;                   // never away from b
    settle.observe(n * 0.01, d);
  }
  EXPECT_DOUBLE_EQ(settle.time()[0], 0.60);
  EXPECT_EQ(settle.time()[1], 0.0);
}

TEST(Snapshots, TakesExactlyTheRequestedGridSteps) {
  gd::Snapshots snaps(1, {0, 5, 9});
  for (std::int64_t n = 0; n <= 10; ++n) {
    const Eigen::ArrayXd x = Eigen::ArrayXd::Constant(1, static_cast<double>(n));
    snaps.observe(n, x, 2.0 * x, 3.0 * x);
  }
  ASSERT_EQ(snaps.taken(), 3u);
  EXPECT_EQ(snaps.delta()(0, 1), 5.0);
  EXPECT_EQ(snaps.velocity()(0, 2), 18.0);
  EXPECT_EQ(snaps.load()(0, 0), 0.0);
}

TEST(WindowRange, FoldedExtremaAndOneLaneQueryMatchStepByStep) {
  // The live node's path: extrema folded per block (observe_extrema), merged at block ends and at
  // arbitrary stops (publish instants that do not divide the block), and center_distance(lane):
  // bit for bit what observing every step and center_distance()[0] give.
  const std::int64_t window = 120, block = 40;
  gd::WindowRange stepwise(1, window, block), folded(1, window, block);
  const double inf = std::numeric_limits<double>::infinity();
  double hd = -inf, ld = -inf, hv = -inf, lv = -inf;
  for (std::int64_t n = 0; n <= 1000; ++n) {
    const double d = sig_d(n, 0), v = sig_v(n, 0);
    stepwise.observe(n, Eigen::ArrayXd::Constant(1, d), Eigen::ArrayXd::Constant(1, v));
    hd = std::max(hd, d), ld = std::max(ld, -d), hv = std::max(hv, v), lv = std::max(lv, -v);
    if ((n + 1) % block == 0 || n % 17 == 0) {
      folded.observe_extrema(n, hd, ld, hv, lv);
      hd = ld = hv = lv = -inf;
      const double a = stepwise.center_distance()[0], b = folded.center_distance(0);
      ASSERT_EQ(std::memcmp(&a, &b, sizeof a), 0) << "n " << n;
      ASSERT_EQ(folded.center_distance()[0], b);
    }
  }
}

// simulate()'s pass in packets (observe_packet) keeps the same maxima and t_ss as the whole-array
// observers, bit for bit, for 16 lanes in two packets of 8 (and one of 16), NaN included.
TEST(WindowRange, PacketsMatchWholeArrays) {
  constexpr int kLanes = 16;
  using Packet = Eigen::Array<double, 8, 1>;
  using Wide = Eigen::Array<double, kLanes, 1>;
  gd::WindowRange whole(kLanes, 40, 8), packets(kLanes, 40, 8), wide(kLanes, 40, 8);
  gd::SteadyStateTime settle_whole(kLanes, 0.5, 0.2), settle_packets(kLanes, 0.5, 0.2), settle_wide(kLanes, 0.5, 0.2);
  for (std::int64_t n = 0; n < 300; ++n) {
    Eigen::ArrayXd d(kLanes), v(kLanes);
    for (int l = 0; l < kLanes; ++l) {
      d[l] = sig_d(n, l);
      v[l] = sig_v(n, l);
    }
    if (n == 123) d[3] = std::numeric_limits<double>::quiet_NaN();
    const double t = 0.001 * static_cast<double>(n);
    whole.observe(n, d, v);
    settle_whole.observe(t, d);
    packets.start(n);
    for (int p = 0; p < kLanes; p += 8) {
      packets.observe_packet(p, Packet(d.segment<8>(p)), Packet(v.segment<8>(p)));
      settle_packets.observe_packet(t, p, Packet(d.segment<8>(p)));
    }
    wide.start(n);
    wide.observe_packet(0, Wide(d), Wide(v));
    settle_wide.observe_packet(t, 0, Wide(d));
    if (n % 8 == 7) {
      for (int l = 0; l < kLanes; ++l) {
        for (const gd::WindowRange* other : {&packets, &wide}) {
          const double a = whole.center_distance(l), b = other->center_distance(l);
          EXPECT_EQ(std::memcmp(&a, &b, sizeof a), 0) << "step " << n << ", lane " << l;
        }
      }
    }
  }
  for (int l = 0; l < kLanes; ++l) {
    EXPECT_EQ(settle_whole.time()[l], settle_packets.time()[l]) << "lane " << l;
    EXPECT_EQ(settle_whole.time()[l], settle_wide.time()[l]) << "lane " << l;
  }
}
