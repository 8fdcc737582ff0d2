// The one-lane path (Realization, the live node's) against the SIMD batch (Ensemble): the same
// realization has bit for bit the same path in both, at any lane position of any block, for S1, a
// stochastic realization and mu != 0, through run-time changes (mu, sigma, lambda, an external
// load, a state), reset, and steps around the stiffness switches and the normal-chunk edges.
#include <gtest/gtest.h>

#include <cstring>
#include <limits>
#include <string>
#include <vector>

#include "gear_dynamics/config/config.hpp"
#include "gear_dynamics/engine/ensemble.hpp"
#include "gear_dynamics/engine/realization.hpp"

namespace gd = gear_dynamics;

namespace {

gd::ModelConfig shipped() {
  const std::string dir = GEAR_DYNAMICS_CONFIG_DIR;
  return gd::parse_config(gd::read_yaml_files({dir + "/gear_pair.yaml", dir + "/load.yaml", dir + "/run.yaml"}));
}

bool same_bits(double a, double b) { return std::memcmp(&a, &b, sizeof a) == 0; }

// A block of `lanes` lanes, `target` at lane `at`, the others different realizations and mu.
gd::Ensemble block_with(const gd::ModelConfig& c, const gd::LaneSpec& target, int lanes, int at) {
  std::vector<gd::LaneSpec> specs;
  for (int i = 0; i < lanes; ++i) {
    if (i == at) {
      specs.push_back(target);
    } else {
      specs.push_back(gd::stochastic_lane(c, 0.01 * (i % 5), 100 + static_cast<std::uint64_t>(i)));
    }
  }
  return gd::Ensemble(derive(c.gear), c.run.time_step, c.initial, specs, c.seed);
}

// Steps both `steps` times (calling `change` before each step) and compares every state.
template <class Change>
void expect_same_path(gd::Ensemble& e, int at, gd::Realization& r, std::int64_t steps, Change change) {
  for (std::int64_t k = 0; k < steps; ++k) {
    change(e, r);
    e.step();
    r.step();
    ASSERT_EQ(e.step_index(), r.step_index());
    ASSERT_TRUE(same_bits(e.delta()[at], r.delta()) && same_bits(e.velocity()[at], r.velocity()) &&
                same_bits(e.load()[at], r.load()))
        << "step " << e.step_index() << ": delta " << e.delta()[at] << " vs " << r.delta() << ", delta_dot "
        << e.velocity()[at] << " vs " << r.velocity() << ", Phi " << e.load()[at] << " vs " << r.load();
  }
}

constexpr std::int64_t kSteps = 200000;  // 0.2 s at the shipped h = 1 us

void same_over_02s(const gd::LaneSpec& lane, int lanes, int at) {
  const gd::ModelConfig c = shipped();
  gd::Ensemble e = block_with(c, lane, lanes, at);
  gd::Realization r(derive(c.gear), c.run.time_step, c.initial, lane, c.seed);
  ASSERT_TRUE(same_bits(e.load()[at], r.load()));
  expect_same_path(e, at, r, kSteps, [](gd::Ensemble&, gd::Realization&) {});
  EXPECT_GT(r.delta(), 0.0);  // in contact by then: the path went somewhere
}

}  // namespace

TEST(Realization, SameAsEnsembleS1) {
  const gd::ModelConfig c = shipped();
  same_over_02s(gd::deterministic_lane(c, 0.0), 8, 3);
}

TEST(Realization, SameAsEnsembleStochastic) {
  const gd::ModelConfig c = shipped();
  same_over_02s(gd::stochastic_lane(c, 0.0, 1), 11, 9);  // the second packet of a padded block
}

TEST(Realization, SameAsEnsembleStochasticWithFriction) {
  const gd::ModelConfig c = shipped();
  ASSERT_NE(c.friction_coefficient, 0.0);
  same_over_02s(gd::stochastic_lane(c, c.friction_coefficient, 7), 1, 0);
  same_over_02s(gd::deterministic_lane(c, 0.08), 16, 15);
}

TEST(Realization, SameThroughChangesAndReset) {
  const gd::ModelConfig c = shipped();
  const gd::LaneSpec lane = gd::stochastic_lane(c, 0.02, 3);
  const int at = 5;
  gd::Ensemble e = block_with(c, lane, 8, at);
  gd::Realization r(derive(c.gear), c.run.time_step, c.initial, lane, c.seed);
  const auto changes = [&](gd::Ensemble& en, gd::Realization& re) {
    switch (en.step_index()) {
      case 12345: en.set_mu(at, 0.1), re.set_mu(0.1); break;
      case 23456: en.set_sigma(at, 40.0), re.set_sigma(40.0); break;
      case 34567: en.set_drift(at, 100.0), re.set_drift(100.0); break;
      case 45678: en.set_load(at, 35.0), re.set_load(35.0); break;
      case 56789: en.set_state(at, 1e-5, -0.01), re.set_state(1e-5, -0.01); break;
      default: break;
    }
  };
  expect_same_path(e, at, r, 60000, changes);
  e.reset();
  r.reset();
  ASSERT_TRUE(same_bits(e.load()[at], r.load()));
  // Both keep the changed mu, sigma and lambda over a reset (as the lane's spec); the same again.
  expect_same_path(e, at, r, 60000, changes);
}

TEST(Realization, DivergenceThrowsLikeEnsemble) {
  const gd::ModelConfig c = shipped();
  const gd::LaneSpec lane = gd::stochastic_lane(c, 0.0, 0);
  gd::Realization r(derive(c.gear), c.run.time_step, c.initial, lane, c.seed);
  r.step();
  r.set_state(std::numeric_limits<double>::infinity(), 0.0);
  EXPECT_THROW(r.step(), gd::DivergenceError);
}
