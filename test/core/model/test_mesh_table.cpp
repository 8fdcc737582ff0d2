// The tabulated mesh (doc/model.md §3, §5): friction that reverses at the pitch point, profile
// errors, the schedule period and the step plans at the jumps (the kernel with a transmission
// error: engine/test_rk4_kernel.cpp).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <numeric>
#include <string>
#include <vector>

#include "gear_dynamics/config/config.hpp"
#include "gear_dynamics/model/friction_law.hpp"
#include "gear_dynamics/model/mesh_schedule.hpp"
#include "gear_dynamics/model/mesh_table.hpp"

#include "paper_config.hpp"

namespace gd = gear_dynamics;

namespace {

gd::GearPair reversing_square_wave() {
  gd::GearInputs in;
  in.friction_direction = gd::FrictionDirection::kReversing;
  return gd::derive(in);
}

}  // namespace

TEST(MeshTable, PaperMeshNeedsNoTable) {
  EXPECT_TRUE(gd::is_paper_mesh(gd::GearInputs{}));
  EXPECT_EQ(gd::MeshSchedule(gd::derive(gd::GearInputs{}), 2.5e-6).table(), nullptr);
  EXPECT_FALSE(gd::is_paper_mesh(reversing_square_wave().in));
}

// The square wave through the table: k1 in single contact, k2 as two equal shares in double contact.
TEST(MeshTable, SquareWaveLevelsThroughTheTable) {
  const gd::GearPair g = reversing_square_wave();
  const gd::MeshTable t(g);
  EXPECT_EQ(t.mesh_periods(), 1);
  for (double u : {0.01, 0.3, 0.59}) EXPECT_EQ(t.at(u * g.single_pair_angle).stiffness, g.k1) << u;
  for (double u : {0.01, 0.5, 0.99}) {
    const double phi = g.single_pair_angle + u * (g.mesh_period_angle - g.single_pair_angle);
    EXPECT_EQ(t.at(phi).stiffness, g.k2) << u;
    const auto c = t.contacts(phi);
    ASSERT_EQ(c.size(), 2u);
    EXPECT_EQ(c[0].stiffness, 0.5 * g.k2);
  }
}

// Friction reverses at the pitch point: Q = q3 + mu sgn(x - x_p) (c0 + c1 x) for the one pair in
// single contact (doc/model.md §2), the paper's sign beyond it; the pitch point is a jump.
TEST(MeshTable, FrictionReversesAtThePitchPoint) {
  const gd::GearPair g = reversing_square_wave();
  const gd::MeshTable t(g);
  const double phi_p = (g.x_p - g.x_b) / g.base_radius1;
  ASSERT_GT(phi_p, 0.0);
  ASSERT_LT(phi_p, g.single_pair_angle);  // the pitch point lies in single contact for this gear
  bool has_break = false;
  for (double b : t.breaks()) has_break = has_break || std::abs(b - phi_p) < 1e-12;
  EXPECT_TRUE(has_break);
  for (double phi : {0.2 * phi_p, 0.9 * phi_p, 1.1 * phi_p, 0.5 * (phi_p + g.single_pair_angle)}) {
    const double x = g.x_b + g.base_radius1 * phi, sign = x >= g.x_p ? 1.0 : -1.0;
    EXPECT_NEAR(t.at(phi).friction, sign * (g.c0 + g.c1 * x), 1e-9 * g.c0) << phi;
  }
  // Double contact: both pairs past (or before) the pitch point, each with half the force.
  const double phi = g.single_pair_angle + 0.5 * (g.mesh_period_angle - g.single_pair_angle);
  const double xr = g.x_b + g.base_radius1 * phi, xn = g.x_a + g.base_radius1 * (phi - g.single_pair_angle);
  const double expected = 0.5 * ((xr >= g.x_p ? 1 : -1) * (g.c0 + g.c1 * xr) + (xn >= g.x_p ? 1 : -1) * (g.c0 + g.c1 * xn));
  EXPECT_NEAR(t.at(phi).friction, expected, 1e-9 * g.c0);
}

// Profile errors: the schedule covers the revolutions of the gears whose teeth differ, and e is
// the error of the pair in single contact, the stiffness-weighted mean of the two in double contact.
TEST(MeshTable, ProfileErrorsSetThePeriodAndTheExcitation) {
  gd::GearInputs in;
  in.profile_errors.pinion = {1e-6, 0.0, -2e-6};
  EXPECT_EQ(gd::schedule_mesh_periods(in), in.pinion_teeth);
  in.profile_errors.wheel = {0.0, 3e-7};
  EXPECT_EQ(gd::schedule_mesh_periods(in), std::lcm(in.pinion_teeth, in.gear_teeth));
  in.profile_errors.pinion.clear();
  EXPECT_EQ(gd::schedule_mesh_periods(in), in.gear_teeth);
  in.profile_errors.pinion = {1e-6, 0.0, -2e-6};
  const gd::GearPair g = gd::derive(in);
  const gd::MeshTable t(g);
  const double pn = g.mesh_period_angle, pm = g.single_pair_angle;
  const auto err = [&](long pair) {
    const long i = pair % in.pinion_teeth, j = pair % in.gear_teeth;
    return (i < 3 ? in.profile_errors.pinion[i] : 0.0) + (j < 2 ? in.profile_errors.wheel[j] : 0.0);
  };
  for (long m : {0L, 1L, 2L, 21L, 79L}) {
    EXPECT_NEAR(t.at(m * pn + 0.5 * pm).error, err(m), 1e-20) << m;
    EXPECT_NEAR(t.at(m * pn + 0.5 * (pm + pn)).error, 0.5 * (err(m) + err(m + 1)), 1e-20) << m;
  }
}

// A step that holds a jump is split there; each piece takes its own side's values.
TEST(MeshTable, PlansSplitAtTheJumps) {
  const gd::GearPair g = reversing_square_wave();
  const double h = 2.5e-6;
  const gd::MeshSchedule mesh(g, h);
  const double phi_p = (g.x_p - g.x_b) / g.base_radius1;
  const std::int64_t n = static_cast<std::int64_t>(std::floor(phi_p / g.in.pinion_speed / h));
  const gd::StepPlan p = mesh.plan(n);
  ASSERT_EQ(p.segments, 2);
  EXPECT_NEAR(p.segment[0].end, (phi_p / g.in.pinion_speed - n * h) / h, 1e-9);
  EXPECT_LT(p.segment[0].friction_end, 0.0);  // before the pitch point: reversed
  EXPECT_GT(p.segment[1].friction_start, 0.0);
  // Each side is taken a billionth of its piece inside it: x moves by at most Rb1 1e-9 phi_n.
  EXPECT_NEAR(-p.segment[0].friction_end, p.segment[1].friction_start, 2.0 * g.c1 * g.base_radius1 * 1e-9 * g.mesh_period_angle);
  EXPECT_EQ(p.segment[0].stiffness_end, g.k1);
}

// The configuration refuses what the model cannot take, naming the key.
TEST(MeshTable, ConfigRefusesFaultsWithoutGeometry) {
  gd::ModelConfig c = paper_config();
  YAML::Node root = gd::to_yaml(c);
  root["gear_pair"]["crack_gear"] = "pinion";
  root["gear_pair"]["crack_depth"] = 0.5e-3;
  try {
    gd::parse_config(root);
    FAIL() << "a crack on the square wave was accepted";
  } catch (const gd::ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("gear_pair.crack_depth = 0.0005 m needs gear_pair.mesh_stiffness"),
              std::string::npos)
        << e.what();
  }
  root["gear_pair"]["mesh_stiffness"] = "potential_energy";
  root["gear_pair"]["crack_tooth"] = 20;
  try {
    gd::parse_config(root);
    FAIL() << "crack_tooth 20 of 20 teeth was accepted";
  } catch (const gd::ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("gear_pair.crack_tooth = 20 is out of range; allowed [0, 19]"),
              std::string::npos)
        << e.what();
  }
}

// Random profile errors come from the seed: the same seed, the same errors; another, others.
TEST(MeshTable, RandomProfileErrorsFollowTheSeed) {
  gd::ModelConfig c = paper_config();
  YAML::Node root = gd::to_yaml(c);
  root["gear_pair"]["profile_error_sd"] = 2e-6;
  const gd::ModelConfig a = gd::parse_config(root), b = gd::parse_config(root);
  ASSERT_EQ(a.gear.profile_errors.pinion.size(), static_cast<std::size_t>(c.gear.pinion_teeth));
  ASSERT_EQ(a.gear.profile_errors.wheel.size(), static_cast<std::size_t>(c.gear.gear_teeth));
  EXPECT_EQ(a.gear.profile_errors.wheel, b.gear.profile_errors.wheel);
  root["run"]["seed"] = 7;
  EXPECT_NE(gd::parse_config(root).gear.profile_errors.pinion, a.gear.profile_errors.pinion);
  // The YAML keeps the settings, not the draws: parsing it again gives the same errors.
  EXPECT_EQ(gd::parse_config(gd::to_yaml(a)).gear.profile_errors.pinion, a.gear.profile_errors.pinion);
}

// A root crack in pinion tooth 0 lowers K only while that tooth is in contact (pair 0: mesh period
// 0 throughout, and the double contact at the end of mesh period Z1 - 1), and lowers it more the
// deeper the crack; elsewhere K is the healthy gear's.
TEST(MeshTable, CrackLowersOnlyTheCrackedToothsPairs) {
  gd::GearInputs in;
  in.mesh_stiffness = gd::MeshStiffnessModel::kPotentialEnergy;
  const gd::GearPair healthy = gd::derive(in);
  const gd::MeshTable h(healthy);
  ASSERT_EQ(h.mesh_periods(), 1);
  const double pn = healthy.mesh_period_angle, pm = healthy.single_pair_angle;
  const int Z1 = in.pinion_teeth;
  std::vector<double> previous;
  for (double depth : {0.25e-3, 0.5e-3, 1.0e-3, 1.5e-3}) {
    in.crack = {gd::FaultyGear::kPinion, 0, depth, 0.7853981633974483};
    const gd::MeshTable t(gd::derive(in));
    ASSERT_EQ(t.mesh_periods(), Z1);
    std::vector<double> lowered;
    for (int i = 0; i < 40 * Z1; ++i) {
      const double a = (i + 0.5) * pn / 40, local = std::fmod(a, pn);
      const int m = static_cast<int>(a / pn);
      const bool in_contact = m == 0 || (m == Z1 - 1 && local > pm);
      // The model at the table's nodes' angles, without the interpolation (within 1e-4 of it).
      const double K = t.exact(t.piece_of(a), a).stiffness, K0 = h.exact(h.piece_of(local), local).stiffness;
      if (in_contact) {
        EXPECT_LT(K, K0) << "depth " << depth << " at " << a << " rad";
        lowered.push_back(K);
      } else {
        EXPECT_EQ(K, K0) << "depth " << depth << " at " << a << " rad";
      }
    }
    for (std::size_t k = 0; k < lowered.size() && !previous.empty(); ++k) {
      EXPECT_LT(lowered[k], previous[k]) << "depth " << depth;
    }
    previous = lowered;
  }
}

// The table's linear interpolation stays within 0.1 % of the model everywhere (the nodes are
// refined to 1e-4 at the midpoints; checked here at other points, on a cracked gear).
TEST(MeshTable, InterpolationWithinATenthOfAPercent) {
  gd::GearInputs in;
  in.mesh_stiffness = gd::MeshStiffnessModel::kPotentialEnergy;
  in.friction_direction = gd::FrictionDirection::kReversing;
  in.crack = {gd::FaultyGear::kPinion, 3, 1.0e-3, 0.7853981633974483};
  const gd::GearPair g = gd::derive(in);
  const gd::MeshTable t(g);
  double worst = 0.0;
  for (int i = 0; i < 20000; ++i) {
    const double a = (i + 0.37) * t.period() / 20000;
    const int p = t.piece_of(a);
    const double K = t.at(p, a).stiffness, exact = t.exact(p, a).stiffness;
    worst = std::max(worst, std::abs(K - exact) / exact);
  }
  EXPECT_LT(worst, 1e-3);
  std::printf("table: %d pieces, %d nodes over %d mesh periods; largest interpolation error %.2e of K\n",
              t.pieces(), t.nodes(), t.mesh_periods(), worst);
}

// The bearings model's friction share sigma, tabulated beside K on the nodes K sets: within 1e-3
// (of its scale, 1) of sigma computed independently from the exact contacts, sum_j s_j k_j / K with
// s_j the side of the pitch point (reversing), and sum_j of the law's weight of each pair's share.
TEST(MeshTable, FrictionShareInterpolatedWithinATenthOfAPercent) {
  for (gd::FrictionModel law : {gd::FrictionModel::kConstant, gd::FrictionModel::kBenedictKelley}) {
    gd::GearInputs in;
    in.mesh_stiffness = gd::MeshStiffnessModel::kPotentialEnergy;
    in.friction_direction = gd::FrictionDirection::kReversing;
    in.friction_model = law;
    in.crack = {gd::FaultyGear::kPinion, 3, 1.0e-3, 0.7853981633974483};
    const gd::GearPair g = gd::derive(in);
    const gd::MeshTable t(g);
    double worst = 0.0, lowest = 1.0, highest = -1.0;
    for (int i = 0; i < 20000; ++i) {
      const double a = (i + 0.37) * t.period() / 20000;
      double total = 0.0, sigma = 0.0;
      const std::vector<gd::MeshContact> contacts = t.contacts(a);
      for (const gd::MeshContact& c : contacts) total += c.stiffness;
      for (const gd::MeshContact& c : contacts)
        sigma += law == gd::FrictionModel::kConstant ? (c.x >= g.x_p ? 1.0 : -1.0) * c.stiffness / total
                                                     : gd::pair_friction_weight(g, c.x, c.x, c.stiffness / total);
      const double tabulated = t.at(a).share;
      worst = std::max(worst, std::abs(tabulated - sigma));
      lowest = std::min(lowest, tabulated), highest = std::max(highest, tabulated);
    }
    EXPECT_LT(worst, 1e-3) << "law " << static_cast<int>(law);
    EXPECT_LT(lowest, 0.0);  // it reverses
    EXPECT_GT(highest, 0.0);
    std::printf("sigma (%s): largest interpolation error %.2e, range [%.3f, %.3f]\n",
                law == gd::FrictionModel::kConstant ? "reversing" : "benedict_kelley", worst, lowest, highest);
  }
}

