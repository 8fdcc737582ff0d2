// The batch folder's manifest (doc/batch-folder.md §3): what a batch is (its configuration, its
// grid of study points), which shard of it a writer made, the runs it lists and whether all their
// bags were written. This is the one place that writes and parses it; the bags' encoding (ROS) is
// the batch node's and the reader's. No ROS.
#pragma once

#include <yaml-cpp/yaml.h>

#include <cstddef>
#include <cstdint>
#include <stdexcept>
#include <map>
#include <string>
#include <vector>

#include "gear_dynamics/batch/run_kind.hpp"
#include "gear_dynamics/config/batch_settings.hpp"
#include "gear_dynamics/config/config.hpp"

namespace gear_dynamics {

constexpr const char* kManifestFormat = "gear_dynamics_batch/1";
// A study with more axes than mu (config/sweep.hpp): points, a point per run, names p<iiii>_...
// Readers of format 1 refuse it rather than pool its points by mu.
constexpr const char* kManifestFormatStudy = "gear_dynamics_batch/2";

// A manifest that cannot be read, or whose content breaks the schema: the message names the file.
class ManifestError : public std::runtime_error {
 public:
  explicit ManifestError(const std::string& what) : std::runtime_error(what) {}
};

// One run a manifest lists.
struct ManifestRun {
  std::string name, file;  // file: name + ".bag", inside the folder
  RunKind kind = RunKind::Stochastic;
  double mu = 0;
  std::uint32_t realization = 0;  // realization r, phase member j, 0 for S1
  std::size_t point = 0;          // format 2 only (a format 1 reader sets it from mu)
};

struct Manifest {
  bool study = false;  // format 2: the grid below, a point per run
  std::string package_version;
  // The instruction set of the engine's hot paths in the process that wrote it (engine/
  // instruction_set.hpp): a record only, every one gives the same bags. Empty: not recorded.
  std::string instruction_set;
  int numbers = 0;        // the numbers generation of its bags (engine/ensemble.hpp); 1 if absent
  bool complete = false;  // every listed run's bag was written
  YAML::Node config;      // the model plus the monte_carlo settings (manifest_config)
  int shard_index = 0, shard_count = 1;
  std::vector<std::string> axes;            // format 2: the swept keys, friction first
  std::vector<std::vector<double>> points;  // format 2: each point's value on every axis
  // format 2: the labels of each text axis (gear_pair.friction_model, ...); its values are their positions
  std::map<std::string, std::vector<std::string>> axis_labels;
  std::vector<ManifestRun> runs;
  const char* format() const { return study ? kManifestFormatStudy : kManifestFormat; }
};

// manifest.yaml, or manifest_shard<i>of<n>.yaml for shard i of n > 1 (shards may share a folder).
std::string manifest_file_name(int shard_index, int shard_count);
bool is_manifest_file(const std::string& file_name);  // manifest*.yaml
std::string bag_file_name(const std::string& run_name);     // <run>.bag, a finished run
std::string active_file_name(const std::string& run_name);  // <run>.bag.active, being written
bool is_bag_file(const std::string& file_name);        // *.bag
bool is_active_file(const std::string& file_name);     // *.bag.active: in flight, or abandoned
bool is_temporary_file(const std::string& file_name);  // *.tmp: a manifest being written

// The manifest's `config`: the model (to_yaml) plus the `monte_carlo` settings that define the
// batch's content. Two batches are the same batch if these are equal.
YAML::Node manifest_config(const ModelConfig& model, const BatchSettings& settings);
// This build's package version, written into every manifest.
const char* package_version();

// The manifest as text (the writer's one emitter).
std::string manifest_text(const Manifest& manifest);
// Writes it into `folder` under manifest_file_name, atomically (temporary file, then rename).
// Throws std::runtime_error if it cannot be written.
void write_manifest_file(const std::string& folder, const Manifest& manifest);
// Reads and checks a manifest: YAML, format, shard range, the grid (format 2) and every run's
// fields. Its config is not parsed (manifest_model). Throws ManifestError.
Manifest read_manifest(const std::string& path);
// The model configuration of a manifest read by read_manifest. Throws ManifestError naming `path`.
ModelConfig manifest_model(const Manifest& manifest, const std::string& path);

// The manifests of a folder (manifest*.yaml, regular files), sorted.
std::vector<std::string> manifests_in(const std::string& folder);

}  // namespace gear_dynamics
