// Writing a batch folder (doc/batch-folder.md §4-§9): one LZ4 bag per run, written as <name>.bag.active and
// renamed after a clean close (RunInfo first, the decimated GearState series, RunSummary last), the
// manifest (batch/manifest.hpp), and resume. Writer: gear_monte_carlo; reader: ros/batch_reader.
#pragma once

#include <yaml-cpp/yaml.h>

#include <atomic>
#include <condition_variable>
#include <deque>
#include <exception>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <tuple>
#include <unordered_map>
#include <variant>
#include <vector>

#include "gear_dynamics/batch/manifest.hpp"
#include "gear_dynamics/montecarlo/batch.hpp"
#include "gear_dynamics/ros/bag_writer.hpp"
#include "gear_dynamics/ros/conversions.hpp"

namespace gear_dynamics {

// The RunInfo a run's bag starts with. For a study with more than the friction axis its
// parameters_yaml also holds `study: {point: i, values: {key: value, ...}}` (doc/batch-folder.md §6.1).
RunInfo run_info(const ModelConfig& model, const RunSpec& run);
RunInfo run_info(const Study& study, const RunSpec& run);

// run_info for the many runs of a batch: the runs of one point, mu and mesh phase (S1 and the
// realizations) share their parameters_yaml, emitted once (yaml-cpp's emitter is a noticeable share of a
// batch's CPU). Keeps a reference to the model or study. Thread-safe.
class RunInfos {
 public:
  explicit RunInfos(const ModelConfig& model) : model_(model) {}
  explicit RunInfos(const Study& study) : model_(study.base), study_(&study) {}
  RunInfo operator()(const RunSpec& run);

 private:
  const std::string& parameters(const ModelConfig& config, const RunSpec& run);

  const ModelConfig& model_;
  const Study* study_ = nullptr;
  std::mutex mutex_;
  std::map<std::tuple<std::size_t, double, double>, std::string> parameters_;  // by (point, mu, mesh phase)
};

// The manifest format a study writes: gear_dynamics_batch/1 for the mu sweep (no points),
// gear_dynamics_batch/2 when it has further axes (doc/batch-folder.md §3).
const char* manifest_format(const Study& study);

// True if `path` is a complete bag of `expected`'s run: readable index, exactly one run_info equal
// to `expected`, exactly one summary, and with `with_section` at least one /gear/poincare point
// (a deterministic run's bag written before the section was recorded is redone).
bool bag_complete(const std::string& path, const RunInfo& expected, bool with_section = false);

// Whether a run's bag holds its Poincare section (doc/batch-folder.md §5): the deterministic runs
// (S1, phase) whose T reaches the first mesh period start.
bool records_section(const Study& study, const RunSpec& run);

// Makes settings.output_dir ready for `runs` (this shard's part of the batch) and returns the runs
// still to do. A folder of the same batch (and split into shards) is resumed: complete bags whose
// run_info matches are kept, the other runs' files are removed. Any other non-empty folder is
// refused (std::runtime_error saying why) unless settings.overwrite, which removes its bags and
// manifests.
std::vector<RunSpec> prepare_folder(const ModelConfig& model, const BatchSettings& settings,
                                    const std::vector<RunSpec>& runs);
std::vector<RunSpec> prepare_folder(const Study& study, const BatchSettings& settings,
                                    const std::vector<RunSpec>& runs);

// Writes this shard's manifest (batch/manifest.hpp) into settings.output_dir.
void write_manifest(const ModelConfig& model, const BatchSettings& settings,
                    const std::vector<RunSpec>& runs, bool complete);
void write_manifest(const Study& study, const BatchSettings& settings,
                    const std::vector<RunSpec>& runs, bool complete);

// Writes the bags on a thread of its own, fed through a bounded queue: bag writing overlaps with
// stepping, and memory stays bounded (the queue, plus one open bag per lane in flight). The bags
// are written by BagWriter, byte for byte what rosbag::Bag writes, at a fraction of its cost.
class BagSink : public BatchSink {
 public:
  BagSink(const ModelConfig& model, std::string folder, std::size_t queue_capacity = 1 << 15);
  // Runs of a study: RunInfo from each run's point.
  BagSink(const Study& study, std::string folder, std::size_t queue_capacity = 1 << 15);
  ~BagSink() override;

  void started(const std::vector<RunSpec>& block) override;
  void recorded(const std::vector<RunSpec>& block, const Ensemble& ensemble,
                const Eigen::ArrayXd& center_distance) override;
  void finished(const std::vector<RunSpec>& block, const std::vector<RunResult>& results) override;
  void abandoned(const std::vector<RunSpec>& block) override;

  // Writes what is queued and stops the writer; bags of runs that did not finish are closed and
  // stay .active. Rethrows the writer's first error.
  void finish();

  std::size_t bags_written() const { return written_; }  // renamed to .bag
  double writer_cpu_seconds() const { return cpu_seconds_; }  // CPU time of the writer, after finish()

 private:
  struct Open {
    std::string name;
    RunInfo info;
  };
  struct Close {
    std::vector<PoincarePoint> section;  // written before the summary
    RunSummary summary;
    std::optional<BearingSummary> bearings;  // the bearings model's, written after the summary
  };
  // The bearings model's outputs at a recorded state.
  struct BearingsSample {
    MeshState mesh;
    geometry_msgs::WrenchStamped pinion, wheel;
  };
  struct Abandon {};
  struct Item {
    std::size_t id;  // RunSpec::id
    std::variant<Open, GearState, BearingsSample, Close, Abandon> what;
  };

  void push(std::vector<Item>&& items);
  void loop();
  void write(Item& item);
  void write_bag(Item& item);

  ModelConfig model_;
  std::optional<Study> study_;
  RunInfos infos_;
  std::string folder_;
  std::size_t capacity_;

  std::mutex mutex_;
  std::condition_variable not_empty_, not_full_;
  std::deque<std::vector<Item>> queue_;
  std::size_t queued_ = 0;
  bool done_ = false;
  std::exception_ptr error_;

  struct OpenBag {
    std::string name;
    std::unique_ptr<BagWriter> bag;
  };
  std::unordered_map<std::size_t, OpenBag> open_;  // by RunSpec::id; writer thread only
  std::atomic<std::size_t> written_{0};
  double cpu_seconds_ = 0.0;
  std::thread thread_;
};

}  // namespace gear_dynamics
