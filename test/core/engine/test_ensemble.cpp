// The ensemble's lanes: the same seed gives the same bits, a realization's numbers do not depend on
// its block, run-time changes apply at the next step, divergence names its lane and time.
#include <gtest/gtest.h>

#include <cstring>
#include <string>
#include <vector>

#include "gear_dynamics/engine/ensemble.hpp"

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
