// gear_monitor_study: the condition monitor's detection study (doc/monitor_study.md): a healthy
// reference per load, held-out runs with a root crack of each depth at each load, and per detector
// the ROC, its area, the probability of detection with its interval, the a90/95 depth and the
// detection delay, as CSV files. No ROS master. Plots: scripts/plot_monitor_study.py.
#include <cmath>
#include <cstdio>
#include <set>

#include "cli.hpp"
#include "gear_dynamics/monitor/study.hpp"

namespace gd = gear_dynamics;

namespace {

// The `monitor_study` section of the study file: every key known, each checked by validate().
gd::StudySettings study_settings(const YAML::Node& node) {
  static const std::set<std::string> known = {
      "loads",           "crack_depths", "reference_realizations", "test_realizations", "first_test",
      "windows",         "signal",       "revolutions_per_window", "false_alarm",       "average_run_length",
      "warmup",          "decimation"};
  if (!node || !node.IsMap()) throw std::invalid_argument("the study file has no monitor_study section (a map)");
  for (const auto& kv : node)
    if (!known.count(kv.first.as<std::string>()))
      throw std::invalid_argument("monitor_study." + kv.first.as<std::string>() + " is not a key of the study");
  gd::StudySettings s;
  auto& r = s.reference;
  if (node["loads"]) r.load_means = node["loads"].as<std::vector<double>>();
  if (node["crack_depths"]) s.crack_depths = node["crack_depths"].as<std::vector<double>>();
  if (node["reference_realizations"]) r.realizations = node["reference_realizations"].as<int>();
  if (node["test_realizations"]) s.test_realizations = node["test_realizations"].as<int>();
  if (node["first_test"]) s.first_test = node["first_test"].as<std::uint64_t>();
  if (node["windows"]) r.windows = node["windows"].as<int>();
  if (node["signal"]) r.monitor.signal = gd::parse_monitored_signal(node["signal"].as<std::string>(), "monitor_study.signal");
  if (node["revolutions_per_window"]) r.monitor.revolutions_per_window = node["revolutions_per_window"].as<int>();
  if (node["false_alarm"]) r.false_alarm = node["false_alarm"].as<double>();
  if (node["average_run_length"]) r.average_run_length = node["average_run_length"].as<double>();
  if (node["warmup"]) r.warmup = node["warmup"].as<double>();
  if (node["decimation"]) r.monitor.decimation = node["decimation"].as<int>();
  return s;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Runs the condition monitor's detection study: ROC and AUC, probability of detection against crack "
               "depth with its a90/95, and detection delays, per indicator and load (CSV files).",
               "gear_monitor_study"};
  gd::tools::ModelOptions model;
  gd::tools::add_model_options(app, model);
  std::string study, prefix = "monitor_study";
  std::optional<int> reference_realizations, test_realizations, windows;
  app.add_option("--study", study, "the study file: model overlay and its monitor_study section "
                                   "(default config/monitor_study.yaml)")->type_name("FILE");
  app.add_option("--output", prefix, "write PREFIX_summary.csv, PREFIX_roc.csv, PREFIX_a9095.csv (default "
                                     "monitor_study)")->type_name("PREFIX");
  app.add_option("--reference-realizations", reference_realizations, "override monitor_study.reference_realizations");
  app.add_option("--test-realizations", test_realizations, "override monitor_study.test_realizations");
  app.add_option("--windows", windows, "override monitor_study.windows");
  gd::tools::parse_or_exit(app, argc, argv);
  try {
    if (study.empty()) study = gd::tools::config_dir() + "/monitor_study.yaml";
    model.files.insert(model.files.begin(), study);
    YAML::Node root = gd::tools::model_yaml(model);
    gd::StudySettings s = study_settings(root["monitor_study"]);
    root.remove("monitor_study");
    if (reference_realizations) s.reference.realizations = *reference_realizations;
    if (test_realizations) s.test_realizations = *test_realizations;
    if (windows) s.reference.windows = *windows;
    const gd::ModelConfig config = gd::parse_config(root);
    const gd::StudyResult result = gd::run_study(config, s);
    gd::write_study_csv(prefix, result);
    const double cpu = result.cpu_reference + result.cpu_simulation + result.cpu_assessment;
    std::printf("study %s: %zu load(s) x %zu depth(s), reference %d runs, test %d runs x %d windows (%.3f s each); "
                "CPU %.1f s (reference %.1f, test runs %.1f, assessment %.2f = %.1f us per window)\n",
                prefix.c_str(), result.reference.bands.size(), s.crack_depths.size(), s.reference.realizations,
                s.test_realizations, s.reference.windows, result.window_seconds, cpu, result.cpu_reference,
                result.cpu_simulation, result.cpu_assessment,
                1e6 * result.cpu_assessment / std::max(1L, result.windows_assessed));
    const auto rows = gd::summarize(result);
    for (const auto& band : result.reference.bands) {
      std::printf("load %g m/s^2: detector, a90/95 [mm], AUC at the deepest crack\n", band.load);
      for (const auto& r : rows)
        if (r.load == band.load && r.depth == s.crack_depths.back())
          std::printf("  %-15s %8.3g %6.3f\n", r.detector.c_str(), 1e3 * gd::a90_95(rows, band.load, r.detector),
                      r.auc);
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "gear_monitor_study: %s\n", e.what());
    return 1;
  }
  return 0;
}
