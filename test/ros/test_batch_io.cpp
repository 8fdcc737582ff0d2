// The batch folder contract without a master: bag layout, manifest, byte-identical summaries for
// any threads / block size / shard split, resume, refusal of another batch, abandoned runs.
#include <gtest/gtest.h>
#include <rosbag/bag.h>
#include <rosbag/view.h>
#include <sys/resource.h>

#include <csignal>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>

#include "gear_dynamics/engine/instruction_set.hpp"
#include "gear_dynamics/ros/batch_io.hpp"

namespace gd = gear_dynamics;
namespace fs = std::filesystem;

namespace {

gd::ModelConfig short_model() {
  const std::string dir = GEAR_DYNAMICS_CONFIG_DIR;
  YAML::Node root = gd::read_yaml_files({dir + "/gear_pair.yaml", dir + "/load.yaml", dir + "/run.yaml"});
  root["run"]["duration"] = 0.004;
  root["run"]["window"] = 0.002;
  root["run"]["snapshot_times"] = std::vector<double>{0.002, 0.004};
  return gd::parse_config(root);
}

gd::BatchSettings small_batch(const std::string& dir) {
  gd::BatchSettings s;
  s.mu = {0.0, 0.04};
  s.realizations = 4;
  s.phase_ensemble = false;
  s.record_rate = 5e4;           // every 20 steps: S1, r0, r1
  s.sparse_record_rate = 1e3;    // every 1000 steps: r2, r3
  s.output_dir = dir;
  s.threads = 2;
  return s;
}

struct TempDir {
  fs::path path;
  TempDir() {
    char tmpl[] = "/tmp/gd_batch_io_XXXXXX";
    path = mkdtemp(tmpl);
  }
  ~TempDir() { fs::remove_all(path); }
};

// Runs `s` into its folder (resuming what is there); the runs it did.
std::vector<gd::RunSpec> run_batch(const gd::ModelConfig& model, const gd::BatchSettings& s) {
  const auto runs = gd::shard_runs(gd::plan_runs(model, s), s.shard_index, s.shard_count);
  const auto todo = gd::prepare_folder(model, s, runs);
  gd::write_manifest(model, s, runs, false);
  gd::BagSink sink(model, s.output_dir);
  gd::BatchControl control;
  gd::run_batch(model, todo, s, sink, control);
  sink.finish();
  EXPECT_EQ(sink.bags_written(), todo.size());
  gd::write_manifest(model, s, runs, true);
  return todo;
}

// The serialized RunSummary of every bag in `dir`, by file name.
std::map<std::string, std::vector<std::uint8_t>> summaries(const fs::path& dir) {
  std::map<std::string, std::vector<std::uint8_t>> out;
  for (const auto& f : fs::directory_iterator(dir)) {
    if (f.path().extension() != ".bag") continue;
    rosbag::Bag bag(f.path().string(), rosbag::bagmode::Read);
    for (const rosbag::MessageInstance& m : rosbag::View(bag, rosbag::TopicQuery(gd::kSummaryTopic))) {
      std::vector<std::uint8_t> bytes(m.size());
      ros::serialization::OStream stream(bytes.data(), static_cast<std::uint32_t>(bytes.size()));
      m.write(stream);
      out[f.path().filename().string()] = bytes;
    }
  }
  return out;
}

std::string read_text(const fs::path& p) {
  std::ifstream f(p, std::ios::binary);
  std::stringstream s;
  s << f.rdbuf();
  return s.str();
}

}  // namespace

TEST(BatchBags, OneLz4BagPerRunWithRunInfoFirstSeriesAndSummaryLast) {
  TempDir dir;
  const gd::ModelConfig model = short_model();
  const gd::BatchSettings s = small_batch(dir.path.string());
  const auto runs = run_batch(model, s);
  ASSERT_EQ(runs.size(), 2u * 5);

  for (const gd::RunSpec& r : runs) {
    const fs::path path = dir.path / (r.name + ".bag");
    ASSERT_TRUE(fs::exists(path)) << path;
    EXPECT_FALSE(fs::exists(dir.path / (r.name + ".bag.active")));
    EXPECT_NE(read_text(path).find("compression=lz4"), std::string::npos) << "chunks are LZ4: " << path;
    rosbag::Bag bag(path.string(), rosbag::bagmode::Read);
    rosbag::View view(bag);
    std::vector<std::string> topics;
    std::vector<double> times;
    for (const rosbag::MessageInstance& m : view) {
      topics.push_back(m.getTopic());
      if (m.getTopic() == gd::kRunInfoTopic) {
        EXPECT_EQ(*m.instantiate<gd::RunInfo>(), gd::run_info(model, r));
      }
      if (m.getTopic() != gd::kStateTopic) continue;
      const auto state = m.instantiate<gd::GearState>();
      ASSERT_TRUE(state);
      EXPECT_EQ(m.getTime(), gd::sim_stamp(state->t));
      EXPECT_EQ(state->mu, r.mu);
      times.push_back(state->t);
    }
    ASSERT_GE(topics.size(), 3u);
    // The Poincare section (doc/batch-folder.md §5): S1 only here (phi0 = 0, T_m = 3 ms, T = 4 ms:
    // t = 0 and 3 ms, grid states); none for stochastic runs.
    std::vector<double> section;
    for (const rosbag::MessageInstance& m : rosbag::View(bag, rosbag::TopicQuery(gd::kPoincareTopic))) {
      const auto p = m.instantiate<gd::PoincarePoint>();
      ASSERT_TRUE(p);
      EXPECT_EQ(m.getTime(), gd::sim_stamp(p->t));
      EXPECT_EQ(p->mesh_phase, 0.0);
      section.push_back(p->t);
    }
    const std::vector<double> expected_section =
        r.kind == gd::RunKind::S1 ? std::vector<double>{0.0, std::llround(0.003 / model.run.time_step) * model.run.time_step}
                                   : std::vector<double>{};
    EXPECT_EQ(section, expected_section) << r.name;
    EXPECT_EQ(topics.front(), gd::kRunInfoTopic) << r.name;
    EXPECT_EQ(topics.back(), gd::kSummaryTopic) << r.name;
    EXPECT_EQ(std::count(topics.begin(), topics.end(), gd::kSummaryTopic), 1);
    EXPECT_EQ(std::count(topics.begin(), topics.end(), gd::kRunInfoTopic), 1);
    // The series: every record_every steps, t = 0 and T included.
    const std::size_t expected = static_cast<std::size_t>(model.run.steps() / r.record_every + 1);
    ASSERT_EQ(times.size(), expected) << r.name;
    EXPECT_EQ(times.front(), 0.0);
    EXPECT_DOUBLE_EQ(times.back(), model.run.duration);
    const auto summary = rosbag::View(bag, rosbag::TopicQuery(gd::kSummaryTopic)).begin()->instantiate<gd::RunSummary>();
    EXPECT_EQ(summary->run_name, r.name);
    EXPECT_EQ(summary->kind, gd::to_string(r.kind));
    EXPECT_EQ(summary->realization, r.index);
    EXPECT_EQ(summary->snapshot_times.size(), 2u);
  }

  const YAML::Node m = YAML::LoadFile((dir.path / "manifest.yaml").string());
  EXPECT_EQ(m["format"].as<std::string>(), gd::kManifestFormat);
  EXPECT_EQ(m["package_version"].as<std::string>(), GEAR_DYNAMICS_VERSION);
  // The writing process's instruction set, and the reader returns it.
  EXPECT_EQ(m["instruction_set"].as<std::string>(), gd::to_string(gd::active_instruction_set()));
  EXPECT_EQ(gd::read_manifest((dir.path / "manifest.yaml").string()).instruction_set,
            gd::to_string(gd::active_instruction_set()));
  EXPECT_TRUE(m["complete"].as<bool>());
  EXPECT_EQ(m["shard_index"].as<int>(), 0);
  EXPECT_EQ(m["shard_count"].as<int>(), 1);
  EXPECT_EQ(m["config"]["monte_carlo"]["realizations"].as<int>(), 4);
  EXPECT_EQ(gd::parse_config(m["config"]).seed, model.seed);  // the model config, as to_yaml wrote it
  ASSERT_EQ(m["runs"].size(), runs.size());
  EXPECT_EQ(m["runs"][3]["name"].as<std::string>(), "mu0.0000_r00002");
  EXPECT_EQ(m["runs"][3]["kind"].as<std::string>(), "stochastic");
  EXPECT_EQ(m["runs"][3]["realization"].as<int>(), 2);
  EXPECT_EQ(m["runs"][3]["file"].as<std::string>(), "mu0.0000_r00002.bag");
  EXPECT_FALSE(fs::exists(dir.path / "manifest.yaml.tmp"));
}

TEST(BatchBags, SummariesAreByteIdenticalForAnyThreadsBlockSizeAndShards) {
  TempDir a, b, c;
  const gd::ModelConfig model = short_model();
  gd::BatchSettings s = small_batch(a.path.string());
  s.threads = 1;
  s.block_lanes = 8;
  run_batch(model, s);
  s.output_dir = b.path.string();
  s.threads = 2;
  s.block_lanes = 1;
  run_batch(model, s);
  s.output_dir = c.path.string();  // two shards sharing one folder
  s.block_lanes = 3;
  s.shard_count = 2;
  for (int k : {1, 0}) {
    s.shard_index = k;
    run_batch(model, s);
  }
  EXPECT_TRUE(fs::exists(c.path / "manifest_shard0of2.yaml"));
  EXPECT_TRUE(fs::exists(c.path / "manifest_shard1of2.yaml"));

  const auto ref = summaries(a.path);
  ASSERT_EQ(ref.size(), 10u);
  EXPECT_EQ(summaries(b.path), ref);
  EXPECT_EQ(summaries(c.path), ref);
  EXPECT_NE(ref.at("mu0.0400_r00000.bag"), ref.at("mu0.0400_r00001.bag"));
}

TEST(BatchBags, ResumeRedoesOnlyMissingBrokenAndUnfinishedRuns) {
  TempDir dir;
  const gd::ModelConfig model = short_model();
  gd::BatchSettings s = small_batch(dir.path.string());
  run_batch(model, s);
  const auto before = summaries(dir.path);

  fs::remove(dir.path / "mu0.0000_S1.bag");                                           // missing
  fs::rename(dir.path / "mu0.0000_r00001.bag", dir.path / "mu0.0000_r00001.bag.active");  // unfinished
  fs::resize_file(dir.path / "mu0.0400_r00003.bag", 3000);                             // truncated
  const auto redone = run_batch(model, s);
  std::set<std::string> names;
  for (const auto& r : redone) names.insert(r.name);
  EXPECT_EQ(names, (std::set<std::string>{"mu0.0000_S1", "mu0.0000_r00001", "mu0.0400_r00003"}));
  EXPECT_FALSE(fs::exists(dir.path / "mu0.0000_r00001.bag.active"));
  EXPECT_EQ(summaries(dir.path), before);

  // Complete: nothing to do.
  EXPECT_TRUE(gd::prepare_folder(model, s, gd::plan_runs(model, s)).empty());

  // A different configuration is refused, with the reason, unless overwrite.
  gd::ModelConfig other = model;
  other.seed += 1;
  try {
    gd::prepare_folder(other, s, gd::plan_runs(other, s));
    ADD_FAILURE() << "another batch was not refused";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("is refused: it holds a batch with a different configuration"), std::string::npos)
        << e.what();
    EXPECT_NE(std::string(e.what()).find("overwrite:=true"), std::string::npos) << e.what();
  }
  // A folder written by a build whose numbers differ (a manifest of generation 1 has no `numbers`)
  // is refused too: resuming it would mix old and new results.
  const fs::path manifest = dir.path / "manifest.yaml";
  YAML::Node m = YAML::LoadFile(manifest.string());
  m.remove("numbers");
  std::ofstream(manifest) << m;
  try {
    gd::prepare_folder(model, s, gd::plan_runs(model, s));
    ADD_FAILURE() << "a batch of older numbers was not refused";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("numbers of generation 1"), std::string::npos) << e.what();
  }
  m["numbers"] = gd::kNumbersGeneration;
  std::ofstream(manifest) << m;
  EXPECT_TRUE(gd::prepare_folder(model, s, gd::plan_runs(model, s)).empty());

  gd::BatchSettings more = s;
  more.realizations = 5;  // the batch settings are part of its identity too
  EXPECT_THROW(gd::prepare_folder(model, more, gd::plan_runs(model, more)), std::runtime_error);
  more.shard_count = 2;   // a different split of the same batch cannot share the folder either
  more.realizations = 4;
  EXPECT_THROW(gd::prepare_folder(model, more, gd::plan_runs(model, more)), std::runtime_error);
  s.overwrite = true;
  const auto plan = gd::plan_runs(other, s);
  EXPECT_EQ(gd::prepare_folder(other, s, plan).size(), plan.size());
  EXPECT_TRUE(fs::is_empty(dir.path));

  // A non-empty folder without a manifest is not ours.
  std::ofstream(dir.path / "notes.txt") << "mine";
  s.overwrite = false;
  EXPECT_THROW(gd::prepare_folder(model, s, gd::plan_runs(model, s)), std::runtime_error);
}

// A deterministic run's bag without /gear/poincare (written before the section was recorded) is
// not complete for the writer: a resume redoes it, and only it.
TEST(BatchBags, ResumeRedoesDeterministicBagsWithoutTheSection) {
  TempDir dir;
  const gd::ModelConfig model = short_model();
  const gd::BatchSettings s = small_batch(dir.path.string());
  const auto runs = run_batch(model, s);
  const gd::RunSpec& s1 = runs.front();
  ASSERT_EQ(s1.kind, gd::RunKind::S1);
  const fs::path path = dir.path / (s1.name + ".bag"), old = dir.path / "old.tmp";
  {
    rosbag::Bag in(path.string(), rosbag::bagmode::Read), out(old.string(), rosbag::bagmode::Write);
    for (const rosbag::MessageInstance& m : rosbag::View(in))
      if (m.getTopic() != gd::kPoincareTopic) out.write(m.getTopic(), m.getTime(), m);
  }
  fs::rename(old, path);
  EXPECT_FALSE(gd::bag_complete(path.string(), gd::run_info(model, s1), true));
  EXPECT_TRUE(gd::bag_complete(path.string(), gd::run_info(model, s1), false));
  const auto redone = run_batch(model, s);
  ASSERT_EQ(redone.size(), 1u);
  EXPECT_EQ(redone.front().name, s1.name);
  rosbag::Bag bag(path.string(), rosbag::bagmode::Read);
  EXPECT_EQ(rosbag::View(bag, rosbag::TopicQuery(gd::kPoincareTopic)).size(), 2u);
}

TEST(BatchBags, AbandonedRunsStayActive) {
  TempDir dir;
  const gd::ModelConfig model = short_model();
  gd::BatchSettings s = small_batch(dir.path.string());
  s.threads = 1;
  // Blocks in the order they run (densely recorded first): S1 r0 r1 (mu 0) + S1 (mu 0.04);
  // r0 r1 (mu 0.04), stopped in flight; r2 r3 of both, never started.
  s.block_lanes = 4;
  const auto runs = gd::plan_runs(model, s);
  gd::write_manifest(model, s, runs, false);
  struct Stopper : gd::BagSink {
    using gd::BagSink::BagSink;
    gd::BatchControl* control = nullptr;
    double model_duration = 0.0;
    void recorded(const std::vector<gd::RunSpec>& b, const gd::Ensemble& e, const Eigen::ArrayXd& d) override {
      gd::BagSink::recorded(b, e, d);
      if (b.front().name == "mu0.0400_r00000" && e.time() >= 0.5 * model_duration) control->stop = true;
    }
  } sink(model, s.output_dir);
  gd::BatchControl control;
  sink.control = &control;
  sink.model_duration = model.run.duration;
  gd::run_batch(model, runs, s, sink, control);
  sink.finish();
  std::size_t active = 0, done = 0;
  for (const auto& f : fs::directory_iterator(dir.path)) {
    const std::string name = f.path().filename().string();
    active += name.size() > 7 && name.substr(name.size() - 7) == ".active";
    done += f.path().extension() == ".bag";
  }
  EXPECT_EQ(done, sink.bags_written());
  EXPECT_EQ(done, 4u);
  EXPECT_EQ(active, 2u);
  // Resuming finishes exactly the rest.
  EXPECT_EQ(run_batch(model, s).size(), runs.size() - done);
}

// A write that fails (the file size limit here, as a full disk in the fault suite) ends the batch
// with the error naming the file: the process does not abort, finished bags are complete, the
// others stay .active, and a resume once writing works again completes the batch.
TEST(BatchBags, FailedWritesEndTheBatchWithAnErrorNotACrash) {
  TempDir dir;
  const gd::ModelConfig model = short_model();
  const gd::BatchSettings s = small_batch(dir.path.string());
  const auto runs = gd::plan_runs(model, s);
  rlimit saved{};
  ASSERT_EQ(getrlimit(RLIMIT_FSIZE, &saved), 0);
  const auto old_handler = std::signal(SIGXFSZ, SIG_IGN);  // the write fails with EFBIG instead
  rlimit small = saved;
  small.rlim_cur = 16 * 1024;  // [bytes] the sparse runs' bags fit, the densely recorded ones do not
  ASSERT_EQ(setrlimit(RLIMIT_FSIZE, &small), 0);
  std::string error;
  try {
    run_batch(model, s);
  } catch (const std::exception& e) {
    error = e.what();
  }
  setrlimit(RLIMIT_FSIZE, &saved);
  std::signal(SIGXFSZ, old_handler);
  EXPECT_NE(error.find("cannot write " + dir.path.string() + "/mu0."), std::string::npos) << error;
  std::size_t complete = 0;
  for (const gd::RunSpec& r : runs) {
    const fs::path bag = dir.path / (r.name + ".bag");
    if (!fs::exists(bag)) continue;
    EXPECT_TRUE(gd::bag_complete(bag.string(), gd::run_info(model, r))) << bag;
    ++complete;
  }
  EXPECT_LT(complete, runs.size());
  EXPECT_EQ(run_batch(model, s).size(), runs.size() - complete);
}

// BagWriter writes rosbag's bytes: the same calls through rosbag::Bag (LZ4) and BagWriter give
// identical files, over several chunks (past rosbag's 768 KiB threshold), three topics, a
// connection first seen in a later chunk and bag times that go back (a chunk's start time).
TEST(BatchBags, BagWriterWritesRosbagsBytes) {
  TempDir dir;
  const std::string ours = (dir.path / "ours.bag").string(), theirs = (dir.path / "rosbag.bag").string();
  rosbag::Bag reference;
  reference.open(theirs, rosbag::bagmode::Write);
  reference.setCompression(rosbag::compression::LZ4);
  gd::BagWriter writer;
  writer.open(ours);
  const auto both = [&](const std::string& topic, const ros::Time& time, const auto& message) {
    reference.write(topic, time, message);
    writer.write(topic, time, message);
  };
  gd::RunInfo info;
  info.parameters_yaml = "run: {}";
  both(gd::kRunInfoTopic, ros::Time(1, 0), info);
  for (std::uint32_t i = 0; i < 20000; ++i) {  // about 2.5 MB of states: four chunks
    gd::GearState s;
    s.header.stamp = ros::Time(1.0 + 1e-5 * i);
    s.t = 1e-5 * i;
    s.delta = std::sin(0.01 * i);
    s.realization = i;
    both(gd::kStateTopic, i % 7 == 3 ? ros::Time(1, 5) : s.header.stamp, s);
  }
  gd::RunSummary summary;
  summary.run_name = "mu0.0400_r00000";
  both(gd::kSummaryTopic, ros::Time(2, 1), summary);
  reference.close();
  writer.close();
  EXPECT_GT(fs::file_size(ours), 4 * 4096u);
  EXPECT_TRUE(read_text(ours) == read_text(theirs)) << "BagWriter's bag differs from rosbag's";
}
