// Where the model configuration comes from: the default files of the package's config folder,
// files overlaid on them and single "SECTION.KEY=VALUE" overrides (doc/configuration.md). What
// gear_run's --config/--set/--mu read, shared by the tools and the Python module.
#pragma once

#include <yaml-cpp/yaml.h>

#include <optional>
#include <string>
#include <vector>

namespace gear_dynamics {

// The files overlaid on the defaults, single overrides, and the friction coefficient.
struct ModelOptions {
  std::vector<std::string> files;
  std::vector<std::string> sets;
  std::optional<double> mu;  // else gear_pair.friction_coefficient
};

// "run.duration=0.1" as a YAML overlay of `root`; throws std::runtime_error on another form.
void apply_set(YAML::Node& root, const std::string& assignment);

// The folder holding gear_pair.yaml, load.yaml and run.yaml: $GEAR_DYNAMICS_CONFIG_DIR if set, else
// the installed share/gear_dynamics/config beside the executable, else gear_dynamics/config on
// $ROS_PACKAGE_PATH; never a path fixed at build time, so an installed tool finds its installed
// defaults. Throws std::runtime_error listing the folders tried.
std::string config_dir();

// The defaults (gear_pair, load, run and `extra` of config_dir()), the files, then the overrides
// and mu, not yet validated (parse_config does: a bad value is refused by name, not ignored).
YAML::Node model_yaml(const ModelOptions& options, const std::vector<std::string>& extra = {});

// Drops run.snapshot_times that lie after run.duration, so that a short run set with
// run.duration=... works without restating the snapshot list; returns the notice to give ("" when
// nothing was dropped). gear_run prints it, the Python module raises it as a warning.
std::string drop_late_snapshots(YAML::Node& root);

}  // namespace gear_dynamics
