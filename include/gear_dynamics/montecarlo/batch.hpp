// Monte Carlo batches (doc/model.md §4, §6): the run set of a μ sweep, its split into shards, blocks of
// lanes that share a mesh phase, and running the blocks in parallel with TBB. No ROS: what happens
// to a run's states and result is up to a BatchSink (the batch node writes bags).
//
// A run's numbers depend only on (configuration, run): its random stream is keyed by (seed,
// realization) and the Ensemble keeps lanes independent, so the output is bit-identical for any
// block size, thread count, shard split and order.
#pragma once

#include <yaml-cpp/yaml.h>

#include <atomic>
#include <cstdint>
#include <string>
#include <vector>

#include "gear_dynamics/config/batch_settings.hpp"
#include "gear_dynamics/config/config.hpp"
#include "gear_dynamics/engine/ensemble.hpp"
#include "gear_dynamics/engine/simulation.hpp"
#include "gear_dynamics/batch/run_kind.hpp"

namespace gear_dynamics {

struct RunSpec {
  std::size_t id = 0;           // position in the whole batch (plan order)
  std::string name;             // mu0.0400_S1, mu0.0400_phase07, mu0.0400_r00012
  RunKind kind = RunKind::S1;
  double mu = 0.0;
  std::uint32_t index = 0;      // realization r, phase member j, 0 for S1
  double mesh_phase = 0.0;      // phi0 [rad]
  std::int64_t record_every = 0;  // grid steps between recorded states; 0 = no series
  std::size_t point = 0;        // the study point (config/sweep.hpp); for the mu sweep, mu's position
  std::size_t schedule = 0;     // runs of one schedule may share an Ensemble (StudyPoint::schedule)
};

// The study of a batch: settings.mu x settings.sweep, every point validated (throws ConfigError).
Study make_study(const ModelConfig& model, const BatchSettings& settings);

// Every run of the batch: for each mu, S1, the phase ensemble (if on), realizations 0..R-1.
// For a study with more than the friction axis, names are p<iiii>_mu<μ>_..., point i first;
// otherwise as for the mu sweep (doc/batch-folder.md §4).
std::vector<RunSpec> plan_runs(const Study& study, const BatchSettings& settings);
std::vector<RunSpec> plan_runs(const ModelConfig& model, const BatchSettings& settings);
// Runs i with i % count == index: shards are disjoint, their union is the batch, and each gets
// a like share of every kind and mu.
std::vector<RunSpec> shard_runs(const std::vector<RunSpec>& runs, int index, int count);
// The model configuration of one run (its mu and phi0), and its lane.
ModelConfig run_config(const ModelConfig& model, const RunSpec& run);
LaneSpec run_lane(const ModelConfig& model, const RunSpec& run);
// The same from the run's study point.
ModelConfig run_config(const Study& study, const RunSpec& run);
LaneSpec run_lane(const Study& study, const RunSpec& run);

// Groups of at most `lanes` runs that share schedule, phi0 and record interval, in the order given.
std::vector<std::vector<RunSpec>> make_blocks(const std::vector<RunSpec>& runs, int lanes);

// Receives what a batch produces. Calls for one block come from one thread, in order (started,
// recorded..., then finished or abandoned); different blocks call concurrently. Lane i of the
// ensemble is block[i].
class BatchSink {
 public:
  virtual ~BatchSink() = default;
  virtual void started(const std::vector<RunSpec>& block) = 0;
  // At every grid step that is a multiple of the block's record_every (t = 0 and T included).
  virtual void recorded(const std::vector<RunSpec>& block, const Ensemble& ensemble,
                        const Eigen::ArrayXd& center_distance) = 0;
  // results[i].section: the Poincare section at mesh phase 0 of every lane of a block that holds a
  // deterministic run (S1 or phase), empty in blocks of stochastic runs only.
  virtual void finished(const std::vector<RunSpec>& block, const std::vector<RunResult>& results) = 0;
  // Stopped before the end (BatchControl::stop).
  virtual void abandoned(const std::vector<RunSpec>& block) = 0;
};

struct BatchControl {
  std::atomic<bool> stop{false};  // set from anywhere: no new block starts, recording blocks stop
  std::atomic<std::int64_t> realization_steps{0};  // stepped so far (lanes x steps)
};

// Threads a batch runs on: settings.threads, or all cores available to the process if 0.
int batch_threads(const BatchSettings& settings);

// Steps `runs` in blocks of settings.block_lanes on settings.threads threads, densely recorded
// blocks first (their output takes longest to write). After `stop`, blocks
// that record are abandoned at their next recorded step; blocks without a series finish.
// Rethrows the first error (e.g. DivergenceError) after the blocks in flight have ended.
void run_batch(const Study& study, const std::vector<RunSpec>& runs,
               const BatchSettings& settings, BatchSink& sink, BatchControl& control);
// The same for the study of (model, settings).
void run_batch(const ModelConfig& model, const std::vector<RunSpec>& runs,
               const BatchSettings& settings, BatchSink& sink, BatchControl& control);

}  // namespace gear_dynamics
