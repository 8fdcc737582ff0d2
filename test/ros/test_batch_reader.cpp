// The batch reader on folders this test writes with rosbag::Bag (no master): a clean batch reads
// back exactly; unfinished, truncated, corrupted, foreign, unlisted and missing bags are skipped and
// counted; a folder without a usable bag is an error; shards merge into the single batch.
#include <gtest/gtest.h>
#include <rosbag/bag.h>
#include <ros/serialization.h>
#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <fstream>

#include "gear_dynamics/report/series_csv.hpp"
#include "gear_dynamics/ros/batch_reader.hpp"
#include "gear_dynamics/ros/conversions.hpp"
#include "gear_dynamics/ros/report_message.hpp"

namespace gd = gear_dynamics;
namespace fs = std::filesystem;

namespace {

gd::ModelConfig test_config() {
  const std::string dir = GEAR_DYNAMICS_CONFIG_DIR;
  YAML::Node root = gd::read_yaml_files({dir + "/gear_pair.yaml", dir + "/load.yaml", dir + "/run.yaml"});
  root["run"]["duration"] = 0.4;
  return gd::parse_config(root);
}

struct RunSpec {
  std::string name;
  gd::RunKind kind;
  double mu;
  std::uint32_t index;
};

std::string run_name(const RunSpec& r) {
  char buf[64];
  if (r.kind == gd::RunKind::S1) std::snprintf(buf, sizeof buf, "mu%.4f_S1", r.mu);
  else if (r.kind == gd::RunKind::Phase) std::snprintf(buf, sizeof buf, "mu%.4f_phase%02u", r.mu, r.index);
  else std::snprintf(buf, sizeof buf, "mu%.4f_r%05u", r.mu, r.index);
  return buf;
}

// The batch of this test: S1, 4 phase runs and 6 realizations at mu = 0 and 0.04.
std::vector<RunSpec> all_runs() {
  std::vector<RunSpec> runs;
  for (double mu : {0.0, 0.04}) {
    runs.push_back({"", gd::RunKind::S1, mu, 0});
    for (std::uint32_t j = 0; j < 4; ++j) runs.push_back({"", gd::RunKind::Phase, mu, j});
    for (std::uint32_t r = 0; r < 6; ++r) runs.push_back({"", gd::RunKind::Stochastic, mu, r});
  }
  for (RunSpec& r : runs) r.name = run_name(r);
  return runs;
}

// A deterministic, distinct value per run.
double value(const RunSpec& r, double scale) {
  return scale * (1.0 + 0.37 * r.index + 3.1 * r.mu + 0.011 * static_cast<int>(r.kind));
}

void write_bag(const fs::path& file, const RunSpec& r, const gd::ModelConfig& config) {
  rosbag::Bag bag(file.string(), rosbag::bagmode::Write);
  bag.setCompression(rosbag::compression::LZ4);
  const double T = config.run.duration;
  gd::RunInfo info = gd::make_run_info(config, r.kind, r.index, r.mu,
                                       r.kind == gd::RunKind::Stochastic ? config.load.sigma : 0.0, T);
  bag.write(gd::kRunInfoTopic, gd::sim_stamp(0.0), info);
  for (int k = 0; k <= 400; ++k) {  // enough messages for several chunks
    gd::GearState s;
    s.t = k * T / 400;
    s.header.stamp = gd::sim_stamp(s.t);
    s.delta = value(r, 1e-5) * std::sin(100 * s.t);
    s.delta_dot = value(r, 1e-3) * std::cos(100 * s.t);
    s.phi = 20.0 + s.t;
    s.realization = r.index;
    bag.write(gd::kStateTopic, s.header.stamp, s);
  }
  gd::RunSummary m;
  m.header.stamp = gd::sim_stamp(T);
  m.run_name = r.name;
  m.kind = gd::to_string(r.kind);
  m.realization = r.index;
  m.mu = r.mu;
  m.center_distance = value(r, 4e-4);
  m.steady_state_time = value(r, 0.1);
  m.steady_state_time_fine = value(r, 0.12);
  m.reached_steady_state = m.steady_state_time < T;
  m.final_delta = value(r, 4.5e-5);
  m.final_delta_dot = value(r, 1e-3) - 0.01;
  m.final_phi = value(r, 20);
  for (double t : config.run.snapshot_times) {
    m.snapshot_times.push_back(t);
    m.snapshot_delta.push_back(value(r, 4.4e-5) + 1e-7 * t);
    m.snapshot_delta_dot.push_back(value(r, 1e-3) - 0.01 * t);
  }
  bag.write(gd::kSummaryTopic, m.header.stamp, m);
  bag.close();
}

void write_manifest(const fs::path& file, const std::vector<RunSpec>& runs, const gd::ModelConfig& config, int shard,
                    int shards, int realizations = 6) {
  YAML::Node root;
  root["format"] = gd::kManifestFormat;
  root["package_version"] = GEAR_DYNAMICS_VERSION;
  root["config"] = gd::to_yaml(config);
  root["config"]["monte_carlo"]["realizations"] = realizations;
  root["shard_index"] = shard;
  root["shard_count"] = shards;
  root["runs"] = YAML::Node(YAML::NodeType::Sequence);
  for (const RunSpec& r : runs) {
    YAML::Node e;
    e["name"] = r.name;
    e["kind"] = gd::to_string(r.kind);
    e["mu"] = r.mu;
    e["realization"] = r.index;
    e["file"] = r.name + ".bag";
    root["runs"].push_back(e);
  }
  std::ofstream(file) << YAML::Dump(root) << '\n';
}

// A batch folder with `runs` (shard `shard` of `shards`).
void write_batch(const fs::path& folder, const std::vector<RunSpec>& runs, const gd::ModelConfig& config, int shard = 0,
                 int shards = 1, const std::string& manifest = "manifest.yaml") {
  fs::create_directories(folder);
  write_manifest(folder / manifest, runs, config, shard, shards);
  for (const RunSpec& r : runs) write_bag(folder / (r.name + ".bag"), r, config);
}

class BatchReader : public ::testing::Test {
 protected:
  void SetUp() override {
    ros::Time::init();
    root_ = fs::temp_directory_path() / ("gd_batch_reader_" + std::to_string(::getpid()));
    fs::remove_all(root_);
    config_ = test_config();
  }
  void TearDown() override { fs::remove_all(root_); }

  std::string reason_for(const gd::BatchInputs& in, const fs::path& file) {
    for (const auto& s : in.skipped)
      if (s.file == fs::weakly_canonical(file).string()) return s.reason;
    return "(not skipped)";
  }

  fs::path root_;
  gd::ModelConfig config_;
};

#define EXPECT_HAS(haystack, needle) \
  EXPECT_NE((haystack).find(needle), std::string::npos) << "text: " << (haystack) << "\nmissing: " << (needle)

// Serialized BatchReport, with what legitimately differs (stamp, folder names) blanked.
std::vector<std::uint8_t> bytes_of(gd::BatchReport m) {
  m.header.stamp = ros::Time(1);
  m.folders.clear();
  m.report_folder.clear();
  std::vector<std::uint8_t> buf(ros::serialization::serializationLength(m));
  ros::serialization::OStream out(buf.data(), static_cast<std::uint32_t>(buf.size()));
  ros::serialization::serialize(out, m);
  return buf;
}

}  // namespace

TEST_F(BatchReader, CleanBatchReadsBackExactly) {
  const auto runs = all_runs();
  write_batch(root_ / "a", runs, config_);
  // The reader writes nothing: the figures' series go to the report layer's FigureSeries.
  fs::create_directories(root_ / "report");
  gd::FigureSeries figure_series((root_ / "report").string(), 0.04);
  gd::ReadOptions options;
  options.wants_series = [&](const gd::ManifestRun& run) { return figure_series.wants(run.kind, run.mu, run.realization); };
  options.on_series = [&](const gd::BatchInputs&, const gd::RunRecord& run, const gd::RunSeries& series) {
    figure_series.add(run, series);
  };
  const gd::BatchInputs in = gd::read_batches({(root_ / "a").string()}, options);
  const std::string series_csv = figure_series.write(in.runs);
  EXPECT_EQ(in.expected_runs, runs.size());
  ASSERT_EQ(in.runs.size(), runs.size());
  EXPECT_TRUE(in.skipped.empty());
  EXPECT_TRUE(in.missing.empty());
  EXPECT_EQ(in.config.seed, config_.seed);
  for (const RunSpec& r : runs) {
    const auto it = std::find_if(in.runs.begin(), in.runs.end(), [&](const gd::RunRecord& x) { return x.name == r.name; });
    ASSERT_NE(it, in.runs.end()) << r.name;
    EXPECT_EQ(it->kind, r.kind);
    EXPECT_EQ(it->mu, r.mu);
    EXPECT_EQ(it->index, r.index);
    EXPECT_EQ(it->center_distance, value(r, 4e-4));
    EXPECT_EQ(it->final_delta, value(r, 4.5e-5));
    EXPECT_EQ(it->snapshot_times, config_.run.snapshot_times);
  }
  // Series of S1, S2 (r 0) and S3 (r 1) at mu = 0.04: 3 runs x 401 states, nothing else left.
  std::ifstream series(series_csv);
  std::string line;
  std::getline(series, line);
  EXPECT_EQ(line, "run,kind,mu,index,t[s],delta[mm],delta_dot[mm/s],phi[mm/s^2]");
  std::map<std::string, int> rows;
  while (std::getline(series, line)) ++rows[line.substr(0, line.find(','))];
  EXPECT_EQ(rows.size(), 3u);
  for (const char* name : {"mu0.0400_S1", "mu0.0400_r00000", "mu0.0400_r00001"})
    EXPECT_EQ(rows[name], 401) << name;
  EXPECT_EQ(std::distance(fs::directory_iterator(root_ / "report"), fs::directory_iterator()), 1);
}

TEST_F(BatchReader, BadBagsAreSkippedNamedAndCounted) {
  const auto runs = all_runs();
  const fs::path a = root_ / "a";
  write_batch(a, runs, config_);
  const auto bag = [&](const char* name) { return a / (std::string(name) + ".bag"); };

  // Truncated: the index at the end is gone.
  fs::resize_file(bag("mu0.0000_r00002"), fs::file_size(bag("mu0.0000_r00002")) * 2 / 3);
  // Corrupted: the middle of the file overwritten (chunk data and headers).
  {
    const fs::path f = bag("mu0.0000_r00003");
    std::fstream io(f, std::ios::in | std::ios::out | std::ios::binary);
    io.seekp(static_cast<std::streamoff>(fs::file_size(f) / 3));
    const std::string junk(2000, '\x5a');
    io.write(junk.data(), static_cast<std::streamsize>(junk.size()));
  }
  // Unfinished: still .active.
  fs::rename(bag("mu0.0400_r00004"), a / "mu0.0400_r00004.bag.active");
  // Of another batch: same run name, different load noise.
  gd::ModelConfig other = config_;
  other.load.sigma = 2.5;
  write_bag(bag("mu0.0400_r00005"), runs.back(), other);
  // Not listed, and a listed run without any bag.
  write_bag(a / "stray.bag", runs.front(), config_);
  fs::remove(bag("mu0.0400_phase03"));

  const gd::BatchInputs in = gd::read_batches({a.string()});
  EXPECT_EQ(in.expected_runs, runs.size());
  EXPECT_EQ(in.runs.size(), runs.size() - 5);
  EXPECT_EQ(in.skipped.size(), 5u);  // truncated, corrupted, .active, foreign, stray
  EXPECT_EQ(in.missing.size(), 5u);  // truncated, corrupted, .active, foreign, deleted
  EXPECT_HAS(reason_for(in, bag("mu0.0000_r00002")), "unreadable bag");
  EXPECT_HAS(reason_for(in, bag("mu0.0000_r00003")), "unreadable bag");
  EXPECT_HAS(reason_for(in, a / "mu0.0400_r00004.bag.active"), "unfinished (.active)");
  EXPECT_HAS(reason_for(in, bag("mu0.0400_r00005")), "load:'  sigma: 2.5' here vs '  sigma: 5'");
  EXPECT_HAS(reason_for(in, a / "stray.bag"), "not listed in any manifest");
  for (const char* m : {"mu0.0000_r00002", "mu0.0000_r00003", "mu0.0400_r00004", "mu0.0400_r00005", "mu0.0400_phase03"})
    EXPECT_NE(std::find(in.missing.begin(), in.missing.end(), m), in.missing.end()) << m;
  // The analysis and the message count what was left out.
  const gd::BatchReport msg = gd::make_report_message(in, gd::analyse(in.runs, gd::AnalysisSettings{}), "r");
  EXPECT_EQ(msg.runs_used, runs.size() - 5);
  EXPECT_EQ(msg.skipped_files.size(), 5u);
  EXPECT_EQ(msg.friction.at(0).stochastic_runs, 4u);
  EXPECT_EQ(msg.friction.at(1).phase_runs, 3u);
}

// rosbag trusts the message offsets of a bag's index records; one pointing past its chunk makes
// it read out of bounds (SIGSEGV, found by the fault suite's random byte flips). The reader reads
// bags in a child process, so such a bag is skipped and the rest is read.
TEST_F(BatchReader, BagWhoseIndexCrashesRosbagIsSkipped) {
  const auto runs = all_runs();
  const fs::path a = root_ / "a";
  write_batch(a, runs, config_);
  const fs::path damaged = a / (runs.front().name + ".bag");
  {  // The first index data record (op 0x04): its first entry's offset (time 8 bytes, offset 4).
    std::fstream io(damaged, std::ios::in | std::ios::out | std::ios::binary);
    const auto u32 = [&](std::streamoff at) {
      std::uint32_t v = 0;
      io.seekg(at);
      io.read(reinterpret_cast<char*>(&v), 4);
      return static_cast<std::streamoff>(v);
    };
    std::streamoff pos = 13;  // after "#ROSBAG V2.0\n": records of header length, header, data length, data
    bool found = false;
    while (!found && pos < static_cast<std::streamoff>(fs::file_size(damaged))) {
      const std::streamoff header = u32(pos), data = pos + 4 + header + 4;
      std::string h(static_cast<std::size_t>(header), '\0');
      io.seekg(pos + 4);
      io.read(h.data(), header);
      found = h.find(std::string("op=\x04", 4)) != std::string::npos && u32(data - 4) >= 12;
      if (found) {
        const std::uint32_t past_the_chunk = 0xfffffff0u;
        io.seekp(data + 8);
        io.write(reinterpret_cast<const char*>(&past_the_chunk), 4);
      }
      pos = data + u32(data - 4);
    }
    ASSERT_TRUE(found);
  }
  const gd::BatchInputs in = gd::read_batches({a.string()});
  EXPECT_EQ(in.runs.size(), runs.size() - 1);
  EXPECT_HAS(reason_for(in, damaged), "crashed the bag reader");
}

TEST_F(BatchReader, FoldersWithoutUsableBagsAreErrors) {
  const auto error_of = [](const std::vector<std::string>& folders) {
    try {
      gd::read_batches(folders);
    } catch (const gd::BatchReadError& ex) {
      return std::string(ex.what());
    }
    return std::string("no error");
  };
  fs::create_directories(root_ / "empty");
  EXPECT_HAS(error_of({(root_ / "empty").string()}), "has no manifest.yaml");
  EXPECT_HAS(error_of({(root_ / "nowhere").string()}), "does not exist");
  EXPECT_HAS(error_of({}), "no batch folder");
  // A manifest whose bags are all unusable.
  const auto runs = all_runs();
  write_batch(root_ / "bad", {runs[0], runs[1]}, config_);
  for (const RunSpec& r : {runs[0], runs[1]}) fs::resize_file(root_ / "bad" / (r.name + ".bag"), 100);
  EXPECT_HAS(error_of({(root_ / "bad").string()}), "has no usable bag (2 skipped, 2 runs missing)");
  // A broken manifest names its file and the problem.
  std::ofstream(root_ / "empty" / "manifest.yaml") << "format: gear_dynamics_batch/1\nconfig: {}\n";
  EXPECT_HAS(error_of({(root_ / "empty").string()}), "manifest.yaml: shard_index is missing");
  std::ofstream(root_ / "empty" / "manifest.yaml")
      << "format: gear_dynamics_batch/1\nconfig: {}\nshard_index: 0\nshard_count: 1\nruns: []\n";
  EXPECT_HAS(error_of({(root_ / "empty").string()}), "manifest.yaml: its config is not a valid model configuration");
  std::ofstream(root_ / "empty" / "manifest.yaml")
      << "format: gear_dynamics_batch/1\nconfig: {}\nshard_index: 0\nshard_count: 1\n"
         "runs: [{name: a, kind: S1, mu: x, realization: 0, file: a.bag}]\n";
  EXPECT_HAS(error_of({(root_ / "empty").string()}), "manifest.yaml: runs[0].mu = 'x' is not of the expected type");
  // Manifests of different batches.
  gd::ModelConfig other = config_;
  other.seed = 7;
  write_batch(root_ / "other", {runs[2]}, other);
  EXPECT_HAS(error_of({(root_ / "bad").string(), (root_ / "other").string()}), "belong to different batches");
}

TEST_F(BatchReader, ShardsMergeIntoTheSingleBatch) {
  const auto runs = all_runs();
  std::vector<RunSpec> shard[2];
  for (std::size_t i = 0; i < runs.size(); ++i) shard[i % 2].push_back(runs[i]);
  write_batch(root_ / "single", runs, config_);
  write_batch(root_ / "s0", shard[0], config_, 0, 2);
  write_batch(root_ / "s1", shard[1], config_, 1, 2);
  // One folder both shards wrote into, each with its own manifest.
  write_batch(root_ / "both", shard[0], config_, 0, 2, "manifest_shard0.yaml");
  write_batch(root_ / "both", shard[1], config_, 1, 2, "manifest_shard1.yaml");

  const gd::AnalysisSettings s;
  const auto report = [&](const std::vector<std::string>& folders) {
    const gd::BatchInputs in = gd::read_batches(folders);
    EXPECT_TRUE(in.skipped.empty());
    EXPECT_TRUE(in.missing.empty());
    EXPECT_EQ(in.runs.size(), runs.size());
    return bytes_of(gd::make_report_message(in, gd::analyse(in.runs, s), ""));
  };
  const auto single = report({(root_ / "single").string()});
  EXPECT_EQ(report({(root_ / "s0").string(), (root_ / "s1").string()}), single);
  EXPECT_EQ(report({(root_ / "s1").string(), (root_ / "s0").string()}), single);
  EXPECT_EQ(report({(root_ / "both").string()}), single);

  // One shard alone: the other is reported missing, not silently ignored.
  const gd::BatchInputs half = gd::read_batches({(root_ / "s0").string()});
  ASSERT_EQ(half.missing.size(), 1u);
  EXPECT_HAS(half.missing[0], "shard 1 of 2");
  // Shards of two batches that hold different runs (here R) are refused, not merged.
  write_batch(root_ / "other", shard[1], config_, 1, 2);
  write_manifest(root_ / "other" / "manifest.yaml", shard[1], config_, 1, 2, 7);
  try {
    gd::read_batches({(root_ / "s0").string(), (root_ / "other").string()});
    ADD_FAILURE() << "shards of different batches were merged";
  } catch (const gd::BatchReadError& ex) {
    EXPECT_HAS(std::string(ex.what()), "their monte_carlo sections differ");
  }
  // The same runs twice: the second copies are skipped as duplicates, not read.
  const gd::BatchInputs twice = gd::read_batches({(root_ / "single").string(), (root_ / "both").string()});
  EXPECT_EQ(twice.runs.size(), runs.size());
  ASSERT_EQ(twice.skipped.size(), runs.size());
  EXPECT_HAS(twice.skipped[0].reason, "duplicate of");
}

TEST_F(BatchReader, BatchCompleteWaitsForEveryListedBag) {
  const auto runs = all_runs();
  EXPECT_FALSE(gd::batch_complete((root_ / "a").string()));
  write_batch(root_ / "a", runs, config_);
  EXPECT_TRUE(gd::batch_complete((root_ / "a").string()));
  fs::rename(root_ / "a" / (runs[3].name + ".bag"), root_ / "a" / (runs[3].name + ".bag.active"));
  EXPECT_FALSE(gd::batch_complete((root_ / "a").string()));
}

// The reader parses a manifest's runs item by item (no yaml-cpp tree of the whole list): block
// items indented (YAML::Dump's), block items at column 0 between comments and blank lines, and a
// flow list (parsed whole) read the same runs; each stochastic run's series goes to on_series once
// as its bag is read, with its 401 states.
TEST_F(BatchReader, ManifestStylesReadTheSameRunsAndSeriesStreamOut) {
  const auto runs = all_runs();
  write_batch(root_ / "a", runs, config_);
  std::ifstream in_file(root_ / "a" / "manifest.yaml");
  const std::string dumped((std::istreambuf_iterator<char>(in_file)), std::istreambuf_iterator<char>());
  const std::size_t at = dumped.find("\nruns:\n");
  ASSERT_NE(at, std::string::npos);
  const std::string head = dumped.substr(0, at + 1);
  std::string column0 = head + "runs:\n# the runs\n", flow = head + "runs: [";
  for (const RunSpec& r : runs) {
    char mu[32];
    std::snprintf(mu, sizeof mu, "%.17g", r.mu);
    column0 += "- name: " + r.name + "\n  kind: " + gd::to_string(r.kind) + "\n  mu: " + mu + "\n\n  realization: " +
               std::to_string(r.index) + "\n  file: " + r.name + ".bag\n";
    flow += std::string(&r == &runs.front() ? "" : ", ") + "{name: " + r.name + ", kind: " + gd::to_string(r.kind) +
            ", mu: " + mu + ", realization: " + std::to_string(r.index) + ", file: " + r.name + ".bag}";
  }
  flow += "]\n";
  const auto names_of = [](const gd::BatchInputs& in) {
    std::vector<std::string> names;
    for (const gd::RunRecord& r : in.runs) names.push_back(r.name + "/" + gd::to_string(r.kind) + "/" + std::to_string(r.index));
    return names;
  };
  std::size_t series_runs = 0, states = 0;
  gd::ReadOptions options;
  options.wants_series = [](const gd::ManifestRun& run) { return run.kind == gd::RunKind::Stochastic; };
  options.on_series = [&](const gd::BatchInputs&, const gd::RunRecord& run, const gd::RunSeries& series) {
    EXPECT_EQ(run.kind, gd::RunKind::Stochastic);
    EXPECT_EQ(series.delta.size(), series.t.size());
    EXPECT_EQ(series.delta_dot.size(), series.t.size());
    EXPECT_EQ(series.phi.size(), series.t.size());
    ++series_runs;
    states += series.t.size();
  };
  const gd::BatchInputs reference = gd::read_batches({(root_ / "a").string()}, options);
  EXPECT_EQ(series_runs, 12u);
  EXPECT_EQ(states, 12u * 401);
  ASSERT_EQ(reference.runs.size(), runs.size());
  for (const std::string& text : {column0, flow}) {
    std::ofstream(root_ / "a" / "manifest.yaml") << text;
    const gd::BatchInputs in = gd::read_batches({(root_ / "a").string()});
    EXPECT_EQ(names_of(in), names_of(reference)) << text;
    EXPECT_TRUE(in.skipped.empty()) << text;
    EXPECT_EQ(in.expected_runs, runs.size());
  }
  // A syntax error in one item is the whole manifest's, reported as before.
  std::ofstream(root_ / "a" / "manifest.yaml") << column0 << "- {name: [unclosed\n";
  try {
    gd::read_batches({(root_ / "a").string()});
    ADD_FAILURE() << "a broken manifest was read";
  } catch (const gd::BatchReadError& ex) {
    EXPECT_HAS(std::string(ex.what()), "not readable as YAML");
  }
}
