// A study's batch folder without a master (doc/batch-folder.md, doc/studies.md): format-2 manifest
// with its axes and points, p<iiii>_ names, the point in RunInfo, resume of a study (complete bags
// kept, a missing one redone byte for byte), refusal of another grid, and the reader's points.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <iterator>

#include "gear_dynamics/ros/batch_io.hpp"
#include "gear_dynamics/ros/batch_reader.hpp"

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

gd::BatchSettings study_settings(const std::string& dir, std::vector<double> sigma) {
  gd::BatchSettings s;
  s.mu = {0.0, 0.04};
  // In schema order, as parse_batch_settings gives them.
  s.sweep = {{"gear_pair.pinion_speed", {104.71975511965977, 150.0}, {}}, {"load.sigma", std::move(sigma), {}}};
  s.realizations = 3;
  s.phase_ensemble = false;
  s.record_rate = 5e4;
  s.sparse_record_rate = 1e3;
  s.output_dir = dir;
  s.threads = 2;
  return s;
}

struct TempDir {
  fs::path path;
  TempDir() {
    char tmpl[] = "/tmp/gd_study_io_XXXXXX";
    path = mkdtemp(tmpl);
  }
  ~TempDir() { fs::remove_all(path); }
};

std::vector<gd::RunSpec> run_study(const gd::ModelConfig& model, const gd::BatchSettings& s) {
  const gd::Study study = gd::make_study(model, s);
  const auto runs = gd::plan_runs(study, s);
  const auto todo = gd::prepare_folder(study, s, runs);
  gd::write_manifest(study, s, runs, false);
  gd::BagSink sink(study, s.output_dir);
  gd::BatchControl control;
  gd::run_batch(study, todo, s, sink, control);
  sink.finish();
  gd::write_manifest(study, s, runs, true);
  return todo;
}

std::string bytes(const fs::path& p) {
  std::ifstream f(p, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(f), {});
}

}  // namespace

TEST(StudyFolder, ManifestNamesResumeRefusalAndReader) {
  TempDir dir;
  const gd::ModelConfig model = short_model();
  const gd::BatchSettings s = study_settings(dir.path.string(), {0.0, 5.0});
  const auto first = run_study(model, s);
  ASSERT_EQ(first.size(), 8u * (1 + 3));  // 2 mu x 2 sigma x 2 speeds
  EXPECT_EQ(first.front().name, "p0000_mu0.0000_S1");
  EXPECT_EQ(first.back().name, "p0007_mu0.0400_r00002");

  const YAML::Node m = YAML::LoadFile((dir.path / "manifest.yaml").string());
  EXPECT_EQ(m["format"].as<std::string>(), "gear_dynamics_batch/2");
  EXPECT_EQ(m["axes"].as<std::vector<std::string>>(),
            (std::vector<std::string>{"gear_pair.friction_coefficient", "gear_pair.pinion_speed", "load.sigma"}));
  ASSERT_EQ(m["points"].size(), 8u);
  EXPECT_EQ(m["points"][5]["values"].as<std::vector<double>>(), (std::vector<double>{0.04, 104.71975511965977, 5.0}));
  EXPECT_EQ(m["runs"][4]["point"].as<std::size_t>(), 1u);
  EXPECT_EQ(m["config"]["monte_carlo"]["sweep"]["load.sigma"].as<std::vector<double>>(), (std::vector<double>{0, 5}));

  // RunInfo carries the point's configuration and its index.
  const gd::Study study = gd::make_study(model, s);
  const auto runs = gd::plan_runs(study, s);
  const YAML::Node p = YAML::Load(gd::run_info(study, runs[7]).parameters_yaml);
  EXPECT_EQ(p["study"]["point"].as<std::size_t>(), 1u);
  EXPECT_EQ(p["load"]["sigma"].as<double>(), 5.0);
  EXPECT_EQ(p["study"]["values"]["load.sigma"].as<double>(), 5.0);

  // Resume: everything complete; a lost bag is redone, byte for byte.
  EXPECT_TRUE(gd::prepare_folder(study, s, runs).empty());
  const fs::path lost = dir.path / (runs[13].name + ".bag");
  const std::string before = bytes(lost);
  fs::remove(lost);
  const auto redone = run_study(model, s);
  ASSERT_EQ(redone.size(), 1u);
  EXPECT_EQ(redone.front().name, runs[13].name);
  EXPECT_EQ(bytes(lost), before);

  // Another grid is another batch.
  const gd::BatchSettings other = study_settings(dir.path.string(), {0.0, 6.0});
  try {
    gd::prepare_folder(gd::make_study(model, other), other, gd::plan_runs(gd::make_study(model, other), other));
    ADD_FAILURE() << "another grid was accepted";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("different configuration"), std::string::npos) << e.what();
  }

  // The reader: the grid, and every run at its point.
  const gd::BatchInputs in = gd::read_batches({dir.path.string()});
  EXPECT_EQ(in.runs.size(), runs.size());
  EXPECT_TRUE(in.skipped.empty());
  ASSERT_EQ(in.axes.size(), 3u);
  EXPECT_EQ(in.axes[2].key, "load.sigma");
  ASSERT_EQ(in.points.size(), 8u);
  EXPECT_EQ(in.points[5], (std::vector<double>{0.04, 104.71975511965977, 5.0}));
  for (const gd::RunRecord& r : in.runs) {
    ASSERT_LT(r.point, in.points.size());
    EXPECT_EQ(r.name.substr(0, 5), "p000" + std::to_string(r.point));
    EXPECT_EQ(r.mu, in.points[r.point][0]);
  }
}

// A bag of another point under this point's name is skipped by the reader.
TEST(StudyFolder, ReaderSkipsABagOfAnotherPoint) {
  TempDir dir;
  const gd::ModelConfig model = short_model();
  const gd::BatchSettings s = study_settings(dir.path.string(), {0.0, 5.0});
  run_study(model, s);
  fs::copy_file(dir.path / "p0001_mu0.0000_r00000.bag", dir.path / "p0000_mu0.0000_r00000.bag",
                fs::copy_options::overwrite_existing);
  const gd::BatchInputs in = gd::read_batches({dir.path.string()});
  ASSERT_EQ(in.skipped.size(), 1u);
  EXPECT_NE(in.skipped[0].reason.find("another batch"), std::string::npos) << in.skipped[0].reason;
  ASSERT_EQ(in.missing.size(), 1u);
  EXPECT_EQ(in.missing[0], "p0000_mu0.0000_r00000");
}

// The mu sweep through the study path writes the mu sweep's folder: format 1, no points.
TEST(StudyFolder, MuSweepKeepsFormatOne) {
  TempDir dir;
  const gd::ModelConfig model = short_model();
  gd::BatchSettings s = study_settings(dir.path.string(), {});
  s.sweep.clear();
  run_study(model, s);
  const YAML::Node m = YAML::LoadFile((dir.path / "manifest.yaml").string());
  EXPECT_EQ(m["format"].as<std::string>(), "gear_dynamics_batch/1");
  EXPECT_FALSE(m["points"]);
  EXPECT_FALSE(m["config"]["monte_carlo"]["sweep"]);
  EXPECT_FALSE(m["runs"][0]["point"]);
  EXPECT_TRUE(fs::exists(dir.path / "mu0.0400_r00002.bag"));
  const gd::BatchInputs in = gd::read_batches({dir.path.string()});
  ASSERT_EQ(in.axes.size(), 1u);
  EXPECT_EQ(in.points, (std::vector<std::vector<double>>{{0.0}, {0.04}}));
}

// Shards of a study share a folder: each writes its manifest with the grid; the reader joins them.
TEST(StudyFolder, ShardsJoinIntoOneStudy) {
  TempDir dir;
  const gd::ModelConfig model = short_model();
  std::size_t total = 0;
  for (int i = 0; i < 2; ++i) {
    gd::BatchSettings s = study_settings(dir.path.string(), {0.0, 5.0});
    s.shard_index = i;
    s.shard_count = 2;
    const gd::Study study = gd::make_study(model, s);
    const auto runs = gd::shard_runs(gd::plan_runs(study, s), i, 2);
    const auto todo = gd::prepare_folder(study, s, runs);
    EXPECT_EQ(todo.size(), runs.size());
    gd::write_manifest(study, s, runs, false);
    gd::BagSink sink(study, s.output_dir);
    gd::BatchControl control;
    gd::run_batch(study, todo, s, sink, control);
    sink.finish();
    gd::write_manifest(study, s, runs, true);
    total += runs.size();
  }
  EXPECT_TRUE(fs::exists(dir.path / "manifest_shard1of2.yaml"));
  const gd::BatchInputs in = gd::read_batches({dir.path.string()});
  EXPECT_EQ(in.runs.size(), total);
  EXPECT_EQ(in.expected_runs, total);
  EXPECT_TRUE(in.missing.empty());
  EXPECT_EQ(in.points.size(), 8u);
}
