// The model configuration's files and overrides (config/model_files.hpp).
#include "gear_dynamics/config/model_files.hpp"

#include <cstdlib>
#include <filesystem>
#include <sstream>
#include <stdexcept>

#include "gear_dynamics/config/config.hpp"

namespace gear_dynamics {

void apply_set(YAML::Node& root, const std::string& assignment) {
  const auto eq = assignment.find('='), dot = assignment.find('.');
  if (eq == std::string::npos || dot == std::string::npos || dot > eq)
    throw std::runtime_error("--set expects SECTION.KEY=VALUE, got '" + assignment + "'");
  YAML::Node overlay;
  overlay[assignment.substr(0, dot)][assignment.substr(dot + 1, eq - dot - 1)] =
      YAML::Load(assignment.substr(eq + 1));
  merge_yaml(root, overlay);
}

std::string config_dir() {
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

YAML::Node model_yaml(const ModelOptions& o, const std::vector<std::string>& extra) {
  const std::string dir = config_dir();
  std::vector<std::string> files = {dir + "/gear_pair.yaml", dir + "/load.yaml", dir + "/run.yaml"};
  for (const std::string& name : extra) files.push_back(dir + "/" + name);
  files.insert(files.end(), o.files.begin(), o.files.end());
  YAML::Node root = read_yaml_files(files);
  for (const std::string& s : o.sets) apply_set(root, s);
  if (o.mu) root["gear_pair"]["friction_coefficient"] = *o.mu;
  return root;
}

std::string drop_late_snapshots(YAML::Node& root) {
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

}  // namespace gear_dynamics
