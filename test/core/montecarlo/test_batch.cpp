// Monte Carlo batches in the core: the run set, shards and blocks; bit-identical results whatever
// the threads, block size and shard split; common random numbers across mu; the load statistics;
// validation of the monte_carlo section.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <map>
#include <mutex>
#include <set>

#include "gear_dynamics/montecarlo/batch.hpp"

namespace gd = gear_dynamics;

namespace {

gd::ModelConfig short_model(double duration, std::vector<double> snapshots) {
  const std::string dir = GEAR_DYNAMICS_CONFIG_DIR;
  YAML::Node root = gd::read_yaml_files({dir + "/gear_pair.yaml", dir + "/load.yaml", dir + "/run.yaml"});
  root["run"]["duration"] = duration;
  root["run"]["window"] = duration / 2;
  root["run"]["snapshot_times"] = snapshots;
  return gd::parse_config(root);
}

YAML::Node shipped_batch_section() {
  return YAML::LoadFile(std::string(GEAR_DYNAMICS_CONFIG_DIR) + "/monte_carlo.yaml")["monte_carlo"];
}

// Everything a run produced: its result and its recorded series (delta, delta_dot, Phi, d, time).
struct RunOutput {
  gd::RunResult result;
  std::vector<double> series;
  bool finished = false;
};

class CollectSink : public gd::BatchSink {
 public:
  void started(const std::vector<gd::RunSpec>&) override {}
  void recorded(const std::vector<gd::RunSpec>& block, const gd::Ensemble& e, const Eigen::ArrayXd& d) override {
    std::lock_guard<std::mutex> lock(mutex_);
    for (std::size_t i = 0; i < block.size(); ++i) {
      const int l = static_cast<int>(i);
      auto& s = out[block[i].name].series;
      s.insert(s.end(), {e.time(), e.delta()[l], e.velocity()[l], e.load()[l], d[l]});
    }
  }
  void finished(const std::vector<gd::RunSpec>& block, const std::vector<gd::RunResult>& results) override {
    std::lock_guard<std::mutex> lock(mutex_);
    for (std::size_t i = 0; i < block.size(); ++i) {
      out[block[i].name].result = results[i];
      out[block[i].name].finished = true;
    }
  }
  void abandoned(const std::vector<gd::RunSpec>& block) override {
    std::lock_guard<std::mutex> lock(mutex_);
    for (const auto& r : block) abandoned_runs.insert(r.name);
  }
  std::map<std::string, RunOutput> out;
  std::set<std::string> abandoned_runs;

 private:
  std::mutex mutex_;
};

bool same_bits(double a, double b) { return std::memcmp(&a, &b, sizeof a) == 0; }

// Bit-for-bit equality of two runs' outputs, with a message naming the first difference.
::testing::AssertionResult identical(const RunOutput& a, const RunOutput& b) {
  const auto& x = a.result;
  const auto& y = b.result;
  const std::vector<std::pair<double, double>> fields = {
      {x.center_distance, y.center_distance}, {x.delta_range, y.delta_range},
      {x.delta_dot_range, y.delta_dot_range}, {x.steady_state_time, y.steady_state_time},
      {x.steady_state_time_fine, y.steady_state_time_fine}, {x.final_delta, y.final_delta},
      {x.final_delta_dot, y.final_delta_dot}, {x.final_load, y.final_load}};
  for (std::size_t k = 0; k < fields.size(); ++k)
    if (!same_bits(fields[k].first, fields[k].second)) return ::testing::AssertionFailure() << "result field " << k;
  if (x.snapshots.size() != y.snapshots.size()) return ::testing::AssertionFailure() << "snapshot count";
  for (std::size_t k = 0; k < x.snapshots.size(); ++k) {
    const auto &p = x.snapshots[k], &q = y.snapshots[k];
    if (!same_bits(p.delta, q.delta) || !same_bits(p.delta_dot, q.delta_dot) || !same_bits(p.load, q.load))
      return ::testing::AssertionFailure() << "snapshot " << k;
  }
  if (a.series.size() != b.series.size()) return ::testing::AssertionFailure() << "series length";
  if (std::memcmp(a.series.data(), b.series.data(), a.series.size() * sizeof(double)) != 0)
    return ::testing::AssertionFailure() << "series values";
  return ::testing::AssertionSuccess();
}

std::map<std::string, RunOutput> run(const gd::ModelConfig& model, const gd::BatchSettings& s) {
  CollectSink sink;
  gd::BatchControl control;
  gd::run_batch(model, gd::shard_runs(gd::plan_runs(model, s), s.shard_index, s.shard_count), s, sink, control);
  EXPECT_TRUE(sink.abandoned_runs.empty());
  return sink.out;
}

#define EXPECT_HAS(haystack, needle) \
  EXPECT_NE((haystack).find(needle), std::string::npos) << "message: " << (haystack) << "\nmissing: " << (needle)

std::string error_of(const YAML::Node& section, const gd::ModelConfig& model) {
  try {
    gd::parse_batch_settings(section, model);
    return "";
  } catch (const gd::ConfigError& e) {
    return e.what();
  }
}

}  // namespace

TEST(Batch, PlanNamesKindsPhasesAndRecordIntervals) {
  const gd::ModelConfig model = short_model(0.01, {0.01});
  gd::BatchSettings s;
  s.mu = {0.0, 0.04};
  s.realizations = 12;
  s.record_rate = 1e5;
  s.sparse_record_rate = 1e3;
  const auto runs = gd::plan_runs(model, s);
  ASSERT_EQ(runs.size(), 2u * (1 + 64 + 12));
  const double phi_n = gd::derive(model.gear).mesh_period_angle;
  const std::int64_t dense_every = std::llround(1.0 / (s.record_rate * model.run.time_step)),
                     sparse_every = std::llround(1.0 / (s.sparse_record_rate * model.run.time_step));
  std::set<std::string> names;
  for (std::size_t i = 0; i < runs.size(); ++i) {
    const gd::RunSpec& r = runs[i];
    EXPECT_EQ(r.id, i);
    names.insert(r.name);
    if (r.kind == gd::RunKind::Phase) {
      EXPECT_EQ(r.mesh_phase, r.index * phi_n / 64);
      EXPECT_EQ(r.record_every, sparse_every);
    } else {
      EXPECT_EQ(r.mesh_phase, model.gear.mesh_phase);
      // S1, S2 and S3 get the dense series.
      EXPECT_EQ(r.record_every, r.kind == gd::RunKind::S1 || r.index < 2 ? dense_every : sparse_every) << r.name;
    }
  }
  EXPECT_EQ(names.size(), runs.size());
  EXPECT_EQ(runs[0].name, "mu0.0000_S1");
  EXPECT_EQ(runs[8].name, "mu0.0000_phase07");
  EXPECT_EQ(runs[77 + 65 + 11].name, "mu0.0400_r00011");
  EXPECT_EQ(runs[77 + 65 + 11].kind, gd::RunKind::Stochastic);

  s.phase_ensemble = false;
  EXPECT_EQ(gd::plan_runs(model, s).size(), 2u * (1 + 12));
}

TEST(Batch, ShardsPartitionTheBatchAndBlocksShareTheirMeshPhase) {
  const gd::ModelConfig model = short_model(0.01, {0.01});
  gd::BatchSettings s;
  const auto runs = gd::plan_runs(model, s);
  std::multiset<std::size_t> ids;
  for (int k = 0; k < 3; ++k) {
    const auto shard = gd::shard_runs(runs, k, 3);
    EXPECT_NEAR(static_cast<double>(shard.size()), runs.size() / 3.0, 1.0);
    for (const auto& r : shard) ids.insert(r.id);
  }
  ASSERT_EQ(ids.size(), runs.size());
  EXPECT_EQ(std::set<std::size_t>(ids.begin(), ids.end()).size(), runs.size());  // disjoint

  for (int lanes : {1, 5, 8}) {
    std::size_t total = 0;
    for (const auto& block : gd::make_blocks(runs, lanes)) {
      ASSERT_FALSE(block.empty());
      EXPECT_LE(static_cast<int>(block.size()), lanes);
      for (const auto& r : block) {
        EXPECT_EQ(r.mesh_phase, block.front().mesh_phase);
        EXPECT_EQ(r.record_every, block.front().record_every);
      }
      total += block.size();
    }
    EXPECT_EQ(total, runs.size());
  }
}

// The same runs with 1 and 2 threads, 8 and 1 lanes per block, as 1 and as 2 shards: every
// result and every recorded state is the same bit for bit.
TEST(Batch, BitIdenticalForAnyThreadsBlockSizeAndShards) {
  const gd::ModelConfig model = short_model(0.004, {0.002, 0.004});
  gd::BatchSettings s;
  s.mu = {0.0, 0.05};
  s.realizations = 5;
  s.record_rate = 1e5;
  s.sparse_record_rate = 1e4;
  s.threads = 1;
  s.block_lanes = 8;
  const auto reference = run(model, s);
  ASSERT_EQ(reference.size(), 2u * (1 + 64 + 5));

  std::vector<std::map<std::string, RunOutput>> others;
  s.threads = 2;
  others.push_back(run(model, s));
  s.block_lanes = 1;
  others.push_back(run(model, s));
  s.block_lanes = 3;
  std::map<std::string, RunOutput> sharded;
  for (int k : {1, 0}) {  // in either order
    s.shard_index = k;
    s.shard_count = 2;
    const auto part = run(model, s);
    sharded.insert(part.begin(), part.end());
  }
  others.push_back(sharded);

  for (const auto& other : others) {
    ASSERT_EQ(other.size(), reference.size());
    for (const auto& [name, out] : reference) {
      ASSERT_TRUE(out.finished && other.at(name).finished) << name;
      EXPECT_TRUE(identical(out, other.at(name))) << name;
    }
  }
  // Runs that differ do differ (the comparison can fail), and S1's load is constant.
  EXPECT_FALSE(identical(reference.at("mu0.0000_r00000"), reference.at("mu0.0000_r00001")));
  EXPECT_FALSE(identical(reference.at("mu0.0000_phase00"), reference.at("mu0.0000_phase01")));
  EXPECT_EQ(reference.at("mu0.0500_S1").result.final_load, model.load.initial_mean);
  // Common random numbers: realization r has the same load path at every mu (doc/model.md §4),
  // while the gear's response depends on mu.
  for (int r = 0; r < 5; ++r) {
    const auto& a = reference.at("mu0.0000_r0000" + std::to_string(r)).result;
    const auto& b = reference.at("mu0.0500_r0000" + std::to_string(r)).result;
    EXPECT_TRUE(same_bits(a.final_load, b.final_load));
    EXPECT_TRUE(same_bits(a.snapshots[0].load, b.snapshots[0].load));
    EXPECT_FALSE(same_bits(a.final_delta, b.final_delta));
  }
}

// doc/model.md §7 check 7 through the batch: E[Phi(t)] = Phi0 + lambda t, Var[Phi(t)] = sd0^2 + sigma^2 t,
// and the increment Phi(t) - Phi(0) ~ N(lambda t, sigma^2 t), over R = 2000 realizations at the
// snapshot times, within 4 standard errors (mean: sqrt(v/R); variance of a normal sample:
// v sqrt(2/(R-1))).
TEST(Batch, LoadStatisticsAtTheSnapshotTimes) {
  const std::vector<double> times{0.0, 0.004, 0.01};
  const gd::ModelConfig model = short_model(0.01, times);
  gd::BatchSettings s;
  s.mu = {0.04};
  s.realizations = 2000;
  s.phase_ensemble = false;
  s.record_realizations = 0;
  s.sparse_record_rate = 0.0;
  s.threads = 2;
  s.block_lanes = 16;
  const auto out = run(model, s);
  const double R = s.realizations, m0 = model.load.initial_mean, sd0 = model.load.initial_sd,
               sigma = model.load.sigma, drift = model.load.drift;
  ASSERT_EQ(sd0, 5.0);
  ASSERT_EQ(sigma, 5.0);
  for (std::size_t k = 0; k < times.size(); ++k) {
    Eigen::ArrayXd phi(s.realizations), inc(s.realizations);
    int i = 0;
    for (const auto& [name, o] : out) {
      if (name.find("_r") == std::string::npos) continue;
      ASSERT_EQ(o.result.snapshots.size(), times.size());
      phi[i] = o.result.snapshots[k].load;
      inc[i++] = o.result.snapshots[k].load - o.result.snapshots[0].load;
    }
    ASSERT_EQ(i, s.realizations);
    const double t = times[k], v = sd0 * sd0 + sigma * sigma * t, vi = sigma * sigma * t;
    const auto var = [](const Eigen::ArrayXd& x) { return (x - x.mean()).square().sum() / (x.size() - 1); };
    EXPECT_NEAR(phi.mean(), m0 + drift * t, 4 * std::sqrt(v / R)) << "t = " << t;
    EXPECT_NEAR(var(phi), v, 4 * v * std::sqrt(2 / (R - 1))) << "t = " << t;
    if (t == 0) continue;
    EXPECT_NEAR(inc.mean(), drift * t, 4 * std::sqrt(vi / R)) << "t = " << t;
    EXPECT_NEAR(var(inc), vi, 4 * vi * std::sqrt(2 / (R - 1))) << "t = " << t;
  }
}

TEST(Batch, StopAbandonsRecordingBlocks) {
  const gd::ModelConfig model = short_model(0.004, {0.004});
  gd::BatchSettings s;
  s.mu = {0.04};
  s.realizations = 4;
  s.record_realizations = 4;  // one block of five recording runs
  s.phase_ensemble = false;
  s.threads = 1;
  CollectSink sink;
  gd::BatchControl control;
  control.stop = true;
  gd::run_batch(model, gd::plan_runs(model, s), s, sink, control);
  EXPECT_TRUE(sink.out.empty());  // nothing started

  // Stopped from inside: the block in flight is abandoned at its next recorded step.
  struct StopSink : CollectSink {
    gd::BatchControl* control = nullptr;
    void recorded(const std::vector<gd::RunSpec>& b, const gd::Ensemble& e, const Eigen::ArrayXd& d) override {
      CollectSink::recorded(b, e, d);
      if (e.step_index() >= 1000) control->stop = true;
    }
  } stopper;
  gd::BatchControl control2;
  stopper.control = &control2;
  gd::run_batch(model, gd::plan_runs(model, s), s, stopper, control2);
  EXPECT_EQ(stopper.abandoned_runs.size(), 5u);
  for (const auto& [name, o] : stopper.out) EXPECT_FALSE(o.finished) << name;
}

TEST(Batch, ShippedSettingsParse) {
  const gd::ModelConfig model = short_model(0.4, {0.3, 0.4});
  const gd::BatchSettings s = gd::parse_batch_settings(shipped_batch_section(), model);
  EXPECT_EQ(s.mu, (std::vector<double>{0.0, 0.01, 0.02, 0.03, 0.04, 0.05}));
  EXPECT_EQ(s.realizations, 100u);
  EXPECT_TRUE(s.phase_ensemble);
  EXPECT_EQ(s.shard_count, 1);
  // The content round-trips through content_yaml.
  YAML::Node again = shipped_batch_section();
  for (const auto& kv : gd::content_yaml(s)) again[kv.first.as<std::string>()] = kv.second;
  EXPECT_EQ(gd::parse_batch_settings(again, model).record_rate, s.record_rate);
}

TEST(Batch, BadSettingsNameKeyValueAndRange) {
  const gd::ModelConfig model = short_model(0.4, {0.3, 0.4});
  const auto with = [&](const std::string& key, const std::string& value) {
    YAML::Node n = shipped_batch_section();
    n[key] = YAML::Load(value);
    return error_of(n, model);
  };
  EXPECT_HAS(with("mu", "[]"), "monte_carlo.mu = [] is not allowed: expected a non-empty list");
  EXPECT_HAS(with("mu", "[0.04, 0.5]"), "monte_carlo.mu[1] = 0.5 is out of range; allowed [0, 0.2]");
  EXPECT_HAS(with("mu", "[0.04, 0.04]"), "repeats 0.04");
  EXPECT_HAS(with("realizations", "0"), "monte_carlo.realizations = 0 is out of range; allowed [1, 1000000] (integer)");
  EXPECT_HAS(with("realizations", "2.5"), "monte_carlo.realizations = 2.5 is not an integer");
  EXPECT_HAS(with("record_rate", "30000"), "monte_carlo.record_rate = 30000 Hz does not fit the grid");
  EXPECT_HAS(with("record_rate", "0"), "monte_carlo.record_rate = 0 is out of range; allowed (0, ");
  EXPECT_HAS(with("sparse_record_rate", "3e6"), "monte_carlo.sparse_record_rate = 3000000 Hz does not fit the grid");
  EXPECT_HAS(with("record_realizations", "101"), "monte_carlo.record_realizations = 101 is out of range; allowed [0, 100]");
  EXPECT_HAS(with("shard_index", "2"), "monte_carlo.shard_index = 2 is out of range; allowed [0, 0]");
  EXPECT_HAS(with("phase_ensemble", "maybe"), "monte_carlo.phase_ensemble = maybe has the wrong type: expected true or false");
  EXPECT_HAS(with("threads", "'two'"), "monte_carlo.threads = two has the wrong type");
  EXPECT_HAS(with("output_dir", "''"), "monte_carlo.output_dir");
  EXPECT_HAS(with("realisations", "5"), "monte_carlo.realisations is not a known key (a typo?)");
  YAML::Node missing = shipped_batch_section();
  missing.remove("block_lanes");
  EXPECT_HAS(error_of(missing, model), "monte_carlo.block_lanes is missing");
  EXPECT_HAS(error_of(YAML::Node(), model), "missing section 'monte_carlo'");
  EXPECT_EQ(with("record_rate", "50000"), "");  // 20 steps: fits
}
