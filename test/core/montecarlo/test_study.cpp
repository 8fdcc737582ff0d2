// Studies (doc/studies.md; the grid's axes are config/test_sweep.cpp's): validation
// of every point (key, value, point, allowed range), names and plan, blocks grouped by what lanes
// can share, common random numbers across points, a known effect (the mean load shifts Phi(T) by
// what the SDE says) and a key without effect (identical d at every point, bit for bit).
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <map>
#include <mutex>
#include <set>

#include "gear_dynamics/montecarlo/batch.hpp"
#include "sweeps.hpp"

namespace gd = gear_dynamics;
using gd::test::refusal;
using gd::test::sweep_of;

namespace {

gd::ModelConfig short_model(double duration, double time_step = 1e-6) {
  const std::string dir = GEAR_DYNAMICS_CONFIG_DIR;
  YAML::Node root = gd::read_yaml_files({dir + "/gear_pair.yaml", dir + "/load.yaml", dir + "/run.yaml"});
  root["run"]["duration"] = duration;
  root["run"]["time_step"] = time_step;
  root["run"]["window"] = duration / 2;
  root["run"]["snapshot_times"] = std::vector<double>{duration};
  return gd::parse_config(root);
}

class Collect : public gd::BatchSink {
 public:
  void started(const std::vector<gd::RunSpec>&) override {}
  void recorded(const std::vector<gd::RunSpec>&, const gd::Ensemble&, const Eigen::ArrayXd&) override {}
  void finished(const std::vector<gd::RunSpec>& block, const std::vector<gd::RunResult>& results) override {
    std::lock_guard<std::mutex> lock(mutex_);
    for (std::size_t i = 0; i < block.size(); ++i) out[block[i].name] = {block[i], results[i]};
  }
  void abandoned(const std::vector<gd::RunSpec>&) override {}
  std::map<std::string, std::pair<gd::RunSpec, gd::RunResult>> out;

 private:
  std::mutex mutex_;
};

gd::BatchSettings small_settings(std::vector<double> mu, std::vector<gd::SweepAxis> sweep, std::uint32_t r, bool phases) {
  gd::BatchSettings s;
  s.mu = std::move(mu);
  s.sweep = std::move(sweep);
  s.realizations = r;
  s.phase_ensemble = phases;
  s.record_rate = 0;
  s.record_realizations = 0;
  s.sparse_record_rate = 0;
  s.threads = 2;
  s.block_lanes = 8;
  return s;
}

bool same_bits(double a, double b) { return std::memcmp(&a, &b, sizeof a) == 0; }

}  // namespace

TEST(Study, TextAxisSetsTheKeyAtEachPoint) {
  const gd::ModelConfig model = short_model(0.01);
  const gd::Study st = gd::make_study(
      model, {0.0, 0.04}, sweep_of("{gear_pair.friction_model: [constant, benedict_kelley, xu], load.sigma: [1, 2]}"));
  ASSERT_EQ(st.points.size(), 12u);
  const std::vector<gd::FrictionModel> expected = {gd::FrictionModel::kConstant, gd::FrictionModel::kBenedictKelley,
                                                   gd::FrictionModel::kXu};
  for (const gd::StudyPoint& p : st.points) {
    // plan order: mu slowest, then friction_model, then sigma
    EXPECT_EQ(p.config.gear.friction_model, expected[(p.index / 2) % 3]) << p.index;
    EXPECT_EQ(p.config.load.sigma, 1.0 + static_cast<double>(p.index % 2)) << p.index;
    EXPECT_EQ(p.config.friction_coefficient, p.index < 6 ? 0.0 : 0.04) << p.index;
  }
  EXPECT_EQ(gd::point_text(st.axes, st.points[9].values),
            "gear_pair.friction_coefficient = 0.04, gear_pair.friction_model = benedict_kelley, load.sigma = 2");
}

TEST(Study, CartesianProductFirstAxisSlowest) {
  const gd::ModelConfig model = short_model(0.01);
  const gd::Study st = gd::make_study(model, {0.0, 0.04}, sweep_of("{load.sigma: [1, 2, 3]}"));
  ASSERT_EQ(st.points.size(), 6u);
  EXPECT_TRUE(st.swept());
  EXPECT_EQ(st.keys(), (std::vector<std::string>{"gear_pair.friction_coefficient", "load.sigma"}));
  EXPECT_EQ(st.points[4].values, (std::vector<double>{0.04, 2}));
  EXPECT_EQ(st.points[4].config.friction_coefficient, 0.04);
  EXPECT_EQ(st.points[4].config.load.sigma, 2.0);
  for (const auto& p : st.points) EXPECT_EQ(p.schedule, 0u);  // sigma and mu are lane parameters
  // The mu sweep is a study of one axis whose points are the base with each mu, bit for bit.
  const gd::Study mu = gd::make_study(model, {0.03, 0.0}, {});
  EXPECT_FALSE(mu.swept());
  ASSERT_EQ(mu.points.size(), 2u);
  gd::ModelConfig expected = model;
  expected.friction_coefficient = 0.03;
  YAML::Emitter a, b;
  a << gd::to_yaml(expected);
  b << gd::to_yaml(mu.points[0].config);
  EXPECT_EQ(std::string(a.c_str()), std::string(b.c_str()));
}

TEST(Study, EveryPointValidatedWithKeyValuePointAndRange) {
  const gd::ModelConfig model = short_model(0.01);
  const std::string sigma = refusal([&] { gd::make_study(model, {0.04}, sweep_of("{load.sigma: [5, 200]}")); });
  EXPECT_NE(sigma.find("point 1 (gear_pair.friction_coefficient = 0.04, load.sigma = 200)"), std::string::npos) << sigma;
  EXPECT_NE(sigma.find("load.sigma = 200 is out of range; allowed [0, 100]"), std::string::npos) << sigma;
  // At h = 20 us a step spans the shorter stiffness interval above about 4850 rad/s.
  const gd::ModelConfig coarse = short_model(0.01, 2e-5);
  const std::string speed =
      refusal([&] { gd::make_study(coarse, {0.04}, sweep_of("{gear_pair.pinion_speed: [100, 6000]}")); });
  EXPECT_NE(speed.find("point 1"), std::string::npos) << speed;
  EXPECT_NE(speed.find("gear_pair.pinion_speed = 6000 rad/s is out of range at run.time_step = 2e-05 s"),
            std::string::npos)
      << speed;
  EXPECT_NE(speed.find("allowed [0, 48"), std::string::npos) << speed;
  // A cross check of the model: a contact ratio outside (1, 2).
  const std::string teeth = refusal([&] { gd::make_study(model, {0.04}, sweep_of("{gear_pair.addendum_coefficient: [1, 2]}")); });
  EXPECT_NE(teeth.find("point 1"), std::string::npos) << teeth;
  EXPECT_NE(teeth.find("contact ratio"), std::string::npos) << teeth;
}

TEST(Study, NamesPlanAndBlocks) {
  const gd::ModelConfig model = short_model(0.01);
  // The mu sweep keeps its names.
  const auto mu_runs = gd::plan_runs(model, small_settings({0.0, 0.04}, {}, 2, true));
  EXPECT_EQ(mu_runs.front().name, "mu0.0000_S1");
  EXPECT_EQ(mu_runs[1].name, "mu0.0000_phase00");
  EXPECT_EQ(mu_runs.back().name, "mu0.0400_r00001");
  EXPECT_EQ(mu_runs.back().point, 1u);
  // A study: p<iiii>_ first, point order, then S1, phases, realizations.
  const auto s = small_settings({0.04}, sweep_of("{gear_pair.pinion_speed: [104.71975511965977, 209.43951023931953]}"), 3, true);
  const gd::Study st = gd::make_study(model, s);
  const auto runs = gd::plan_runs(st, s);
  ASSERT_EQ(runs.size(), 2u * (1 + 64 + 3));
  EXPECT_EQ(runs[0].name, "p0000_mu0.0400_S1");
  EXPECT_EQ(runs[68].name, "p0001_mu0.0400_S1");
  EXPECT_EQ(runs.back().name, "p0001_mu0.0400_r00002");
  std::set<std::string> names;
  for (const auto& r : runs) names.insert(r.name);
  EXPECT_EQ(names.size(), runs.size());
  EXPECT_NE(st.points[0].schedule, st.points[1].schedule);  // another speed, another mesh schedule
  // The phase ensemble covers each point's own mesh period.
  const double period = gd::derive(st.points[1].config.gear).mesh_period_angle;
  EXPECT_DOUBLE_EQ(runs[68 + 1 + 63].mesh_phase, 63 * period / 64);
  for (const auto& block : gd::make_blocks(runs, 32))
    for (const auto& r : block) {
      EXPECT_EQ(r.schedule, block.front().schedule);
      EXPECT_EQ(r.point, block.front().point);
    }
  // Lane parameters share blocks across points.
  const auto s2 = small_settings({0.0, 0.04}, sweep_of("{load.sigma: [1, 2]}"), 4, false);
  const auto runs2 = gd::plan_runs(gd::make_study(model, s2), s2);
  std::set<std::size_t> points_in_first;
  const auto blocks2 = gd::make_blocks(runs2, 32);
  for (const auto& r : blocks2.front()) points_in_first.insert(r.point);
  EXPECT_EQ(points_in_first.size(), 4u);
}

// Common random numbers: realization r has one load path at every point. The mean load shifts
// Phi(T) by exactly its change (per realization, to rounding), and its mean over R realizations is
// Phi0 + lambda T within sampling error; sigma scales the Wiener part: sd(Phi(T)) = sqrt(sd0^2 + sigma^2 T).
TEST(Study, LoadAxesShiftPhiAsTheSdePredicts) {
  const gd::ModelConfig model = short_model(0.02);
  const std::uint32_t R = 200;
  auto s = small_settings({0.04}, sweep_of("{load.initial_mean: [10, 20, 30], load.drift: [0, 500]}"), R, false);
  const gd::Study st = gd::make_study(model, s);
  Collect sink;
  gd::BatchControl control;
  gd::run_batch(st, gd::plan_runs(st, s), s, sink, control);
  std::map<std::size_t, std::vector<double>> phi;  // by point, by realization
  for (const auto& [name, out] : sink.out)
    if (out.first.kind == gd::RunKind::Stochastic) {
      auto& v = phi[out.first.point];
      v.resize(R);
      v[out.first.index] = out.second.final_load;
    }
  const double T = model.run.duration;
  const double sd = std::sqrt(model.load.initial_sd * model.load.initial_sd + model.load.sigma * model.load.sigma * T);
  for (const auto& p : st.points) {
    const double phi0 = p.values[1], lambda = p.values[2];
    double mean = 0;
    for (double x : phi[p.index]) mean += x / R;
    EXPECT_NEAR(mean, phi0 + lambda * T, 4 * sd / std::sqrt(R)) << gd::point_text(st.keys(), p.values);
    // Against point 0 (Phi0 = 10, lambda = 0): the same path shifted by exactly the change.
    for (std::uint32_t r = 0; r < R; ++r)
      EXPECT_NEAR(phi[p.index][r] - phi[0][r], (phi0 - 10) + lambda * T, 1e-9) << "r " << r;
  }
  auto s2 = small_settings({0.04}, sweep_of("{load.sigma: [0, 10]}"), R, false);
  const gd::Study st2 = gd::make_study(model, s2);
  Collect sink2;
  gd::run_batch(st2, gd::plan_runs(st2, s2), s2, sink2, control);
  for (std::size_t p = 0; p < 2; ++p) {
    const double sigma = st2.points[p].values[1];
    const double expected = std::sqrt(model.load.initial_sd * model.load.initial_sd + sigma * sigma * T);
    double m = 0, m2 = 0;
    for (const auto& [name, out] : sink2.out)
      if (out.first.point == p) m += out.second.final_load / R;
    for (const auto& [name, out] : sink2.out)
      if (out.first.point == p) m2 += (out.second.final_load - m) * (out.second.final_load - m) / (R - 1);
    EXPECT_NEAR(std::sqrt(m2), expected, 4 * expected / std::sqrt(2.0 * (R - 1))) << "sigma " << sigma;
  }
}

// poisson_ratio does not enter the ISO stiffness (doc/model.md D6): every point gives the same d,
// bit for bit, though the points run in blocks of their own.
TEST(Study, KeyWithoutEffectGivesIdenticalResults) {
  const gd::ModelConfig model = short_model(0.02);
  auto s = small_settings({0.04}, sweep_of("{gear_pair.poisson_ratio: [0.25, 0.3, 0.35]}"), 12, true);
  const gd::Study st = gd::make_study(model, s);
  EXPECT_NE(st.points[0].schedule, st.points[2].schedule);
  Collect sink;
  gd::BatchControl control;
  gd::run_batch(st, gd::plan_runs(st, s), s, sink, control);
  ASSERT_EQ(sink.out.size(), 3u * (1 + 64 + 12));
  std::size_t compared = 0;
  for (const auto& [name, out] : sink.out) {
    if (out.first.point == 0) continue;
    const std::string twin = "p0000" + name.substr(5);
    ASSERT_TRUE(sink.out.count(twin)) << twin;
    const auto& a = sink.out.at(twin).second;
    const auto& b = out.second;
    EXPECT_TRUE(same_bits(a.center_distance, b.center_distance) && same_bits(a.final_delta, b.final_delta) &&
                same_bits(a.final_delta_dot, b.final_delta_dot) && same_bits(a.steady_state_time, b.steady_state_time))
        << name;
    ++compared;
  }
  EXPECT_EQ(compared, 2u * 77);
}
