// Reads Monte Carlo batch folders (doc/batch-folder.md §10: manifest*.yaml plus one bag
// per run) into one fixed-size record per run, streaming each bag with rosbag::View. A bag that is
// unfinished (.active), truncated, corrupted, of another batch or not listed is skipped with a
// warning naming the file and the reason; listed runs without a usable bag are reported missing.
#pragma once

#include <functional>
#include <stdexcept>
#include <string>
#include <vector>

#include "gear_dynamics/analysis/report.hpp"
#include "gear_dynamics/ros/conversions.hpp"  // topics of a run bag, manifest format

namespace gear_dynamics {

// The batch cannot be read at all: no folder, no manifest, manifests of different batches, or a
// folder without a usable bag.
class BatchReadError : public std::runtime_error {
 public:
  explicit BatchReadError(const std::string& what) : std::runtime_error(what) {}
};

struct ReadOptions {
  // Where the decimated series of S1, S2 and S3 (realizations 0 and 1) at friction series_mu go,
  // as CSV in the paper's units (for Figs. 5-7); empty: no series are read.
  std::string series_csv;
  double series_mu = 0.04;
  // Called with each stochastic run's /gear/state series [s], [m], [m/s] as its bag is read and
  // found to be that run (`inputs` holds the batch's configuration and points; its runs are not
  // read yet), so the series can be reduced instead of kept (SeriesDigests). Calls come from the
  // reader threads one at a time. Unset: the states are not read.
  std::function<void(const BatchInputs& inputs, const RunRecord& run, const std::vector<double>& time,
                     const std::vector<double>& delta, const std::vector<double>& delta_dot)>
      on_series;
};

// Reads and merges the folders (shards of one batch, or one folder several shards wrote into).
// Throws BatchReadError.
BatchInputs read_batches(const std::vector<std::string>& folders, const ReadOptions& options = {});

// True when the folder has a manifest and every run it lists has its finished bag (used to wait
// for a batch). Never throws.
bool batch_complete(const std::string& folder);

// The folder's manifests as they are on disk (names, inodes, sizes, modification times): it changes
// whenever a writer rewrites one, which it does after its last bag (doc/batch-folder.md §2.4). A
// waiter re-checks batch_complete only then, as parsing a large manifest is dear. Never throws.
std::string manifests_signature(const std::string& folder);

}  // namespace gear_dynamics
