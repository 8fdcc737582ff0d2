// Random streams: reproducible, independent of the block a realization runs in, independent
// across realizations.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <vector>

#include <Random123/philox.h>

#include "gear_dynamics/engine/ensemble.hpp"
#include "gear_dynamics/engine/normal_stream.hpp"

namespace gd = gear_dynamics;

namespace {

bool bit_equal(double a, double b) { return std::memcmp(&a, &b, sizeof a) == 0; }

gd::LaneSpec stochastic(std::uint64_t r, double mu) {
  gd::LaneSpec s;
  s.mu = mu;
  s.sigma = 5.0;
  s.load_mean = 20.0;
  s.load_sd = 5.0;
  s.realization = r;
  return s;
}

}  // namespace

// The SIMD Philox is Random123's Philox4x32-10, bit for bit, on the counters and keys of doc/model.md's
// (seed, realization) scheme, including high seed and realization bits.
TEST(NormalStream, PhiloxMatchesRandom123) {
  for (const std::uint64_t seed : {20180529ull, 0x123456789ABCDEFull}) {
    for (const std::uint64_t r : {0ull, 99ull, (1ull << 33) + 5}) {
      const gd::NormalStream s(seed, r);
      for (const std::uint64_t first : {0ull, 64ull, (1ull << 32) - 16}) {
        std::uint64_t w0[gd::NormalStream::kBlockPairs], w1[gd::NormalStream::kBlockPairs];
        s.philox(first, w0, w1);
        const std::uint32_t seed_high =
            static_cast<std::uint32_t>(seed >> 32) ^ static_cast<std::uint32_t>(r >> 32) * 0x9E3779B9u;
        for (int i = 0; i < gd::NormalStream::kBlockPairs; ++i) {
          const std::uint64_t p = first + i;
          const r123::Philox4x32::ctr_type ctr = {
              {static_cast<std::uint32_t>(p), static_cast<std::uint32_t>(p >> 32), seed_high, 0u}};
          const r123::Philox4x32::key_type key = {
              {static_cast<std::uint32_t>(r), static_cast<std::uint32_t>(seed)}};
          const auto out = r123::Philox4x32()(ctr, key);
          ASSERT_EQ(w0[i], (std::uint64_t{out[1]} << 32 | out[0])) << "counter " << p;
          ASSERT_EQ(w1[i], (std::uint64_t{out[3]} << 32 | out[2])) << "counter " << p;
        }
      }
    }
  }
}

// Ensemble's lane-major generator: each lane is its own realization's stream bit for bit, whatever
// the other lanes hold (high realization and seed bits included), at every block of counters.
TEST(NormalLanes, EachLaneIsItsRealizationsStream) {
  constexpr int kLanes = gd::NormalLanes::kLanes, kBlock = 2 * gd::NormalLanes::kBlockPairs;
  for (const std::uint64_t seed : {20180529ull, 0x123456789ABCDEFull}) {
    const std::uint64_t realizations[kLanes] = {0, 7, 3, (1ull << 33) + 5, 99, 1, 1000000, 2};
    const gd::NormalLanes lanes(seed, realizations);
    for (const std::uint64_t first_pair : {0ull, 32ull, (1ull << 32) - 32}) {
      double out[kBlock * kLanes];
      lanes.block(first_pair, out, kLanes);
      for (int l = 0; l < kLanes; ++l) {
        std::vector<double> expected(kBlock);
        gd::NormalStream(seed, realizations[l]).fill(2 * first_pair, expected.data(), kBlock);
        for (int k = 0; k < kBlock; ++k)
          ASSERT_TRUE(bit_equal(out[k * kLanes + l], expected[k])) << "lane " << l << ", normal " << k;
      }
    }
  }
}

TEST(NormalStream, FillEqualsAtFromAnyOffset) {
  const gd::NormalStream s(20180529, 3);
  for (std::uint64_t first : {0u, 1u, 2u, 7u, 63u, 64u, 130u}) {
    std::vector<double> out(150);
    s.fill(first, out.data(), out.size());
    for (std::size_t k = 0; k < out.size(); ++k) EXPECT_TRUE(bit_equal(out[k], s.at(first + k)));
  }
}

TEST(NormalStream, MomentsAndIndependence) {
  const int n = 200000;
  const gd::NormalStream a(20180529, 0), b(20180529, 1), c(20180530, 0);
  std::vector<double> x(n), y(n), z(n);
  a.fill(0, x.data(), n);
  b.fill(0, y.data(), n);
  c.fill(0, z.data(), n);
  const auto mean = [&](const std::vector<double>& v) {
    double s = 0;
    for (double e : v) s += e;
    return s / n;
  };
  const auto moment = [&](const std::vector<double>& u, const std::vector<double>& v) {
    const double mu = mean(u), mv = mean(v);
    double s = 0;
    for (int i = 0; i < n; ++i) s += (u[i] - mu) * (v[i] - mv);
    return s / (n - 1);
  };
  // Standard normal: mean within 4 SE = 4/sqrt(n), variance within 4 sqrt(2/n).
  EXPECT_NEAR(mean(x), 0.0, 4.0 / std::sqrt(n));
  EXPECT_NEAR(moment(x, x), 1.0, 4.0 * std::sqrt(2.0 / n));
  // Shape: E[z^3] = 0 (sd sqrt(15 / n)), E[z^4] = 3 (sd sqrt(96 / n)), P(|z| > 2) = 0.0455003.
  double m3 = 0, m4 = 0, tail = 0;
  for (double e : x) {
    m3 += e * e * e / n;
    m4 += e * e * e * e / n;
    tail += (std::abs(e) > 2.0) / static_cast<double>(n);
  }
  EXPECT_NEAR(m3, 0.0, 4.0 * std::sqrt(15.0 / n));
  EXPECT_NEAR(m4, 3.0, 4.0 * std::sqrt(96.0 / n));
  EXPECT_NEAR(tail, 0.0455003, 4.0 * std::sqrt(0.0455003 * (1 - 0.0455003) / n));
  // Independent streams: the correlation of n pairs has standard error 1/sqrt(n).
  EXPECT_NEAR(moment(x, y) / std::sqrt(moment(x, x) * moment(y, y)), 0.0, 4.0 / std::sqrt(n));
  EXPECT_NEAR(moment(x, z) / std::sqrt(moment(x, x) * moment(z, z)), 0.0, 4.0 / std::sqrt(n));
  // Within a stream, consecutive normals (the two of a Box-Muller pair included) are uncorrelated.
  std::vector<double> lead(x.begin() + 1, x.end()), lag(x.begin(), x.end() - 1);
  lead.push_back(x[0]);
  lag.push_back(x[n - 1]);
  EXPECT_NEAR(moment(lead, lag), 0.0, 4.0 / std::sqrt(n));
}

// Normal 0 of each stream sets a realization's Phi(0), so its law across realizations (not along
// one stream) decides the tails of Phi at every time. Counts beyond +-3 and +-3.5 over 2e6
// streams are Poisson: within 5 of their standard deviations sqrt(expected).
TEST(NormalStream, FirstNormalAcrossRealizationsHasNormalTails) {
  const int n = 2000000;
  const double thresholds[] = {3.0, 3.5};
  for (double c : thresholds) {
    long below = 0, above = 0;
    for (int r = 0; r < n; ++r) {
      const double z = gd::NormalStream(20180529, static_cast<std::uint64_t>(r)).at(0);
      below += z < -c;
      above += z > c;
    }
    const double expected = n * 0.5 * std::erfc(c / std::sqrt(2.0));
    EXPECT_NEAR(below, expected, 5.0 * std::sqrt(expected)) << "z < -" << c;
    EXPECT_NEAR(above, expected, 5.0 * std::sqrt(expected)) << "z > " << c;
  }
}

TEST(Ensemble, SameSeedGivesBitIdenticalRuns) {
  const gd::GearPair g = gd::derive(gd::GearInputs{});
  gd::Ensemble a(g, 1e-6, {}, {stochastic(5, 0.04)}, 99);
  gd::Ensemble b(g, 1e-6, {}, {stochastic(5, 0.04)}, 99);
  gd::Ensemble other_seed(g, 1e-6, {}, {stochastic(5, 0.04)}, 100);
  for (int n = 0; n < 5000; ++n) {
    a.step();
    b.step();
    other_seed.step();
  }
  EXPECT_TRUE(bit_equal(a.delta()[0], b.delta()[0]));
  EXPECT_TRUE(bit_equal(a.velocity()[0], b.velocity()[0]));
  EXPECT_TRUE(bit_equal(a.load()[0], b.load()[0]));
  EXPECT_NE(a.load()[0], other_seed.load()[0]);
  // reset() repeats the run bit for bit.
  const double d = a.delta()[0];
  a.reset();
  for (int n = 0; n < 5000; ++n) a.step();
  EXPECT_TRUE(bit_equal(a.delta()[0], d));
}

TEST(Ensemble, RealizationDoesNotDependOnItsBlock) {
  const gd::GearPair g = gd::derive(gd::GearInputs{});
  gd::Ensemble alone(g, 1e-6, {}, {stochastic(7, 0.03)}, 42);
  std::vector<gd::LaneSpec> crowd;  // lane 7 is realization 7 at mu = 0.03, among others
  for (std::uint64_t r = 0; r < 13; ++r) crowd.push_back(stochastic(r, r == 7 || r % 2 == 0 ? 0.03 : 0.05));
  gd::Ensemble block(g, 1e-6, {}, crowd, 42);
  // Past a normal-buffer refill and several stiffness switches.
  for (int n = 0; n < 8000; ++n) {
    alone.step();
    block.step();
  }
  EXPECT_TRUE(bit_equal(alone.delta()[0], block.delta()[7]));
  EXPECT_TRUE(bit_equal(alone.velocity()[0], block.velocity()[7]));
  EXPECT_TRUE(bit_equal(alone.load()[0], block.load()[7]));
  // Common random numbers: the same realization at another mu sees the same load path.
  gd::Ensemble other_mu(g, 1e-6, {}, {stochastic(7, 0.05)}, 42);
  for (int n = 0; n < 8000; ++n) other_mu.step();
  EXPECT_TRUE(bit_equal(other_mu.load()[0], alone.load()[0]));
  EXPECT_NE(other_mu.delta()[0], alone.delta()[0]);
}

TEST(Ensemble, RunTimeChangesTakeEffectAtTheNextStep) {
  const gd::GearPair g = gd::derive(gd::GearInputs{});
  gd::Ensemble e(g, 1e-6, {}, {stochastic(0, 0.0)}, 1);
  for (int n = 0; n < 100; ++n) e.step();
  const double before = e.load()[0];
  e.set_sigma(0, 0.0);
  e.set_drift(0, 1000.0);
  e.step();
  EXPECT_DOUBLE_EQ(e.load()[0], before + 1000.0 * 1e-6);
}

TEST(Ensemble, DivergenceStopsWithLaneAndTime) {
  gd::GearInputs in;
  const gd::GearPair g = gd::derive(in);
  gd::LaneSpec s;
  s.stochastic = false;
  s.load_mean = 20.0;
  s.realization = 3;
  // h far beyond the RK4 stability limit (the config validator refuses this; the core still
  // must not hand out NaN).
  gd::Ensemble e(g, 2e-4, {1e-4, 0.0}, {s}, 1);
  try {
    for (int n = 0; n < 100000; ++n) e.step();
    FAIL() << "no divergence reported";
  } catch (const gd::DivergenceError& err) {
    EXPECT_EQ(err.realization, 3u);
    EXPECT_GT(err.time, 0.0);
    EXPECT_NE(std::string(err.what()).find("realization 3"), std::string::npos);
  }
}
