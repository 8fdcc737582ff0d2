// The command-line tools' shared parts (gear_run, gear_analyze, gear_bench): one argument parser,
// CLI11, whose declarations also give --help; the options that pick the model configuration; and
// where the default configuration is found. Private to the tools, not a layer of the library.
#pragma once

#include <CLI/CLI.hpp>
#include <yaml-cpp/yaml.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <limits>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "gear_dynamics/config/config.hpp"

namespace gear_dynamics::tools {

// Parses argv into `app`'s options. --help prints the generated help and exits 0; a bad command
// line prints "NAME: reason (NAME --help)" and exits 1, as every other error of the tools.
inline void parse_or_exit(CLI::App& app, int argc, char** argv) {
  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp&) {
    std::fputs(app.help().c_str(), stdout);
    std::exit(0);
  } catch (const CLI::ParseError& e) {
    std::fprintf(stderr, "%s: %s (%s --help)\n", app.get_name().c_str(), e.what(), app.get_name().c_str());
    std::exit(1);
  }
}

// A number in [lo, hi] (hi omitted: no upper bound). CLI11 refuses any other value as
// "--name: VALUE is out of range; allowed ...", naming the option, the value and the range.
inline CLI::Validator in_range(double lo, double hi = std::numeric_limits<double>::infinity()) {
  std::ostringstream allowed;
  if (std::isinf(hi)) allowed << ">= " << lo;
  else allowed << "[" << lo << ", " << hi << "]";
  return CLI::Validator(
      [lo, hi, range = allowed.str()](std::string& text) -> std::string {
        double v = 0.0;
        if (!CLI::detail::lexical_cast(text, v)) return text + " is not a number";
        if (!(v >= lo && v <= hi)) return text + " is out of range; allowed " + range;
        return "";
      },
      allowed.str());
}

// A number > 0.
inline CLI::Validator positive() {
  return CLI::Validator(
      [](std::string& text) -> std::string {
        double v = 0.0;
        if (!CLI::detail::lexical_cast(text, v)) return text + " is not a number";
        if (!(v > 0.0)) return text + " is out of range; allowed > 0";
        return "";
      },
      "> 0");
}

// One value per occurrence, repeatable: --config a.yaml --config b.yaml.
inline CLI::Option* add_repeatable(CLI::App& app, const std::string& name, std::vector<std::string>& values,
                                   const std::string& description) {
  return app.add_option(name, values, description)->type_size(1)->allow_extra_args(false)->take_all();
}

// The options that select the model configuration: files overlaid on the defaults, single
// overrides, and the friction coefficient.
struct ModelOptions {
  std::vector<std::string> files;
  std::vector<std::string> sets;
  std::optional<double> mu;  // else gear_pair.friction_coefficient
};

inline void add_model_options(CLI::App& app, ModelOptions& o) {
  add_repeatable(app, "--config", o.files, "YAML file overlaid on the defaults (repeatable)")->type_name("FILE");
  add_repeatable(app, "--set", o.sets, "override one parameter, e.g. --set run.duration=0.1 (repeatable)")
      ->type_name("SEC.KEY=VAL");
  app.add_option("--mu", o.mu, "friction coefficient (default: gear_pair.friction_coefficient)")->type_name("X");
}

// "--set run.duration=0.1" as a YAML overlay.
inline void apply_set(YAML::Node& root, const std::string& assignment) {
  const auto eq = assignment.find('='), dot = assignment.find('.');
  if (eq == std::string::npos || dot == std::string::npos || dot > eq)
    throw std::runtime_error("--set expects SECTION.KEY=VALUE, got '" + assignment + "'");
  YAML::Node overlay;
  overlay[assignment.substr(0, dot)][assignment.substr(dot + 1, eq - dot - 1)] =
      YAML::Load(assignment.substr(eq + 1));
  merge_yaml(root, overlay);
}

// The folder holding gear_pair.yaml, load.yaml and run.yaml: $GEAR_DYNAMICS_CONFIG_DIR if set, else
// the installed share/gear_dynamics/config beside the executable, else gear_dynamics/config on
// $ROS_PACKAGE_PATH; never a path fixed at build time, so an installed tool finds its installed
// defaults.
inline std::string config_dir() {
  namespace fs = std::filesystem;
  std::vector<fs::path> tried;
  if (const char* env = std::getenv("GEAR_DYNAMICS_CONFIG_DIR")) tried.emplace_back(env);
  std::error_code ec;
  const fs::path exe = fs::read_symlink("/proc/self/exe", ec);  // <prefix>/lib/gear_dynamics/<tool>
  if (!ec) tried.push_back(exe.parent_path().parent_path().parent_path() / "share" / "gear_dynamics" / "config");
  if (const char* rpp = std::getenv("ROS_PACKAGE_PATH")) {
    std::stringstream paths(rpp);
    for (std::string root; std::getline(paths, root, ':');)
      if (!root.empty()) tried.push_back(fs::path(root) / "gear_dynamics" / "config");
  }
  std::string list;
  for (const fs::path& d : tried) {
    if (fs::is_regular_file(d / "gear_pair.yaml", ec)) return d.string();
    list += "\n  " + d.string();
  }
  throw std::runtime_error("cannot find the default configuration (gear_pair.yaml); looked in:" + list +
                           "\nset GEAR_DYNAMICS_CONFIG_DIR to the package's config folder");
}

// The defaults (gear_pair, load, run and `extra` of config_dir()), the files, then the --set
// overrides and --mu: validated with the rest, so a bad value is refused by name, not ignored.
inline YAML::Node model_yaml(const ModelOptions& o, const std::vector<std::string>& extra = {}) {
  const std::string dir = config_dir();
  std::vector<std::string> files = {dir + "/gear_pair.yaml", dir + "/load.yaml", dir + "/run.yaml"};
  for (const std::string& name : extra) files.push_back(dir + "/" + name);
  files.insert(files.end(), o.files.begin(), o.files.end());
  YAML::Node root = read_yaml_files(files);
  for (const std::string& s : o.sets) apply_set(root, s);
  if (o.mu) root["gear_pair"]["friction_coefficient"] = *o.mu;
  return root;
}

// Drops run.snapshot_times that lie after run.duration, so that a short run set with
// --set run.duration=... works without restating the snapshot list; returns the notice to give
// ("" when nothing was dropped). gear_run prints it, the Python module raises it as a warning.
inline std::string drop_late_snapshots(YAML::Node& root) {
  YAML::Node run = root["run"];
  double duration = 0.0;
  if (!run || !run["snapshot_times"] || !run["snapshot_times"].IsSequence() ||
      !detail::as_number(run["duration"], duration))
    return "";
  YAML::Node kept(YAML::NodeType::Sequence);
  std::string dropped;
  for (const YAML::Node& t : run["snapshot_times"]) {
    double v = 0.0;
    if (detail::as_number(t, v) && v > duration) dropped += (dropped.empty() ? "" : ", ") + detail::show(t);
    else kept.push_back(t);
  }
  if (dropped.empty()) return "";
  run["snapshot_times"] = kept;
  std::ostringstream text;
  text << "snapshot times " << dropped << " s lie after run.duration = " << duration << " s: dropped";
  return text.str();
}

}  // namespace gear_dynamics::tools
