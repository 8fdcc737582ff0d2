// What several gear_analyze subcommands share: the model configuration, the CSV files, a parameter
// range (bifurcation, lyapunov) and a live node's bag (--bag of spectrum, poincare, safety).
#pragma once

#include <chrono>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "gear_dynamics/config/config.hpp"
#include "gear_dynamics/engine/bearings.hpp"
#include "gear_dynamics/report/report_file.hpp"
#include "gear_dynamics/ros/live_bag.hpp"
#include "subcommand.hpp"

namespace gear_dynamics::tools::analyze {

// The model of --config, --set and --mu; `duration` (when given) replaces run.duration. Snapshot
// times after the run are dropped: the tools do not use them.
ModelConfig load_config(const Common& c, std::optional<double> duration = std::nullopt);

// The output a --signal names beyond the mesh force: an entry of kBearingsOutputs for the bearings
// model; null for mesh_force (either model). Throws naming the allowed names otherwise.
const BearingsOutputSpec* signal_output(const std::string& signal, GearModel model);

// PREFIX_<name>.csv, opened through the report layer (its write checked when it closes) with every
// digit of a double (17), announced on stdout.
std::unique_ptr<ReportFile> open_csv(const Common& c, const std::string& name);

double seconds_since(std::chrono::steady_clock::time_point t0);

// --parameter, --from, --to, --values, --log: the values of one parameter.
struct ParameterRange {
  std::string parameter = "speed";
  std::optional<double> from, to;
  int values = 400;
  bool log = false;
  CLI::Option* parameter_option = nullptr;  // whether --parameter was given (lyapunov)
  CLI::Option *from_option = nullptr, *to_option = nullptr;
};
void add_parameter_options(CLI::App& app, ParameterRange& r);
std::vector<double> parameter_values(const ParameterRange& r);

// "LO,HI" of a pair, for --help.
std::string pair_text(const std::pair<double, double>& p);

void print_box(const char* what, const std::vector<double>& x);

// --bag FILE: a live node's run instead of a simulation, with its configuration from the bag's
// run_info (else the model options).
void add_bag_option(CLI::App& app, std::string& bag);
struct BagRun {
  ModelConfig config;
  LiveBagRun run;
  double period = 0;  // the recording period [s]
};
BagRun load_bag(const std::string& bag, const Common& c);
// The first recorded state at or after `transient`.
std::size_t first_after(const BagRun& b, double transient);

}  // namespace gear_dynamics::tools::analyze
