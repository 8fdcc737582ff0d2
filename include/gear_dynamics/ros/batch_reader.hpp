// Reads Monte Carlo batch folders (doc/batch-folder.md §10: manifest*.yaml plus one bag
// per run) into one fixed-size record per run (batch/run_record.hpp), streaming each bag with
// rosbag::View; it writes nothing. A bag that is
// unfinished (.active), truncated, corrupted, of another batch or not listed is skipped with a
// warning naming the file and the reason; listed runs without a usable bag are reported missing.
#pragma once

#include <functional>
#include <stdexcept>
#include <string>
#include <vector>

#include "gear_dynamics/batch/manifest.hpp"
#include "gear_dynamics/batch/run_record.hpp"

namespace gear_dynamics {

// The batch cannot be read at all: no folder, no manifest, manifests of different batches, or a
// folder without a usable bag.
class BatchReadError : public std::runtime_error {
 public:
  explicit BatchReadError(const std::string& what) : std::runtime_error(what) {}
};

struct ReadOptions {
  // Which runs' /gear/state series are read (unset: none), each handed to on_series as its bag is
  // read and found to be that run (`inputs` holds the batch's configuration and points; its runs
  // are not read yet), so that a series can be reduced or written instead of kept. Calls come
  // from the reader threads one at a time.
  std::function<bool(const ManifestRun& run)> wants_series;
  std::function<void(const BatchInputs& inputs, const RunRecord& run, const RunSeries& series)> on_series;
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
