#include "common.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <sstream>
#include <stdexcept>

#include "gear_dynamics/dynamics/bifurcation.hpp"
#include "gear_dynamics/maths/statistics.hpp"

namespace gear_dynamics::tools::analyze {

const BearingsOutputSpec* signal_output(const std::string& signal, GearModel model) {
  if (signal == "mesh_force") return nullptr;
  const BearingsOutputSpec* output = find_bearings_output(signal);
  if (model == GearModel::kBearings && output) return output;
  std::string allowed = "mesh_force";
  if (model == GearModel::kBearings)
    for (const BearingsOutputSpec& o : kBearingsOutputs)
      if (std::string(o.name) != "mesh_force") allowed += std::string(", ") + o.name;
  throw std::runtime_error("--signal " + signal + " is not an output of the " +
                           (model == GearModel::kBearings ? "bearings" : "torsional") +
                           " model (gear_pair.model); allowed: " + allowed +
                           (output ? " (the bearing outputs need gear_pair.model = bearings)" : ""));
}

ModelConfig load_config(const Common& c, std::optional<double> duration) {
  YAML::Node root = model_yaml(c.model);
  if (duration) {
    root["run"]["duration"] = *duration;
    if (root["run"]["window"] && root["run"]["window"].as<double>() > *duration) root["run"]["window"] = *duration;
  }
  const double T = root["run"]["duration"].as<double>();
  YAML::Node kept(YAML::NodeType::Sequence);
  for (const YAML::Node& t : root["run"]["snapshot_times"])
    if (t.as<double>() <= T) kept.push_back(t);
  if (kept.size() == 0) kept.push_back(T);
  root["run"]["snapshot_times"] = kept;
  return parse_config(root);
}

std::unique_ptr<ReportFile> open_csv(const Common& c, const std::string& name) {
  std::vector<std::string> written;
  auto f = std::make_unique<ReportFile>(c.output + "_" + name + ".csv", written);
  f->out().precision(17);
  std::cout << "wrote " << written.front() << "\n";
  return f;
}

double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

void add_parameter_options(CLI::App& app, ParameterRange& r) {
  r.parameter_option =
      app.add_option("--parameter", r.parameter, "speed [rpm], load = Phi0 [m/s^2], mu, damping = zeta_ref")
          ->check(CLI::IsMember({"speed", "load", "mu", "damping"}))
          ->capture_default_str();
  r.from_option = app.add_option("--from", r.from, "first value of the parameter")->type_name("X");
  r.to_option = app.add_option("--to", r.to, "last value of the parameter")->type_name("Y");
  app.add_option("--values", r.values, "number of values")->type_name("N")->check(in_range(1))->capture_default_str();
  app.add_flag("--log", r.log, "values spaced logarithmically");
}

std::vector<double> parameter_values(const ParameterRange& r) {
  if (!r.from || !r.to) throw std::runtime_error("--from, --to and --values are needed");
  const double a = *r.from, b = *r.to;
  const int n = r.values;
  if (r.log && !(a > 0 && b > 0))
    throw std::runtime_error("--log needs --from and --to > 0, got " + std::to_string(a) + " and " + std::to_string(b));
  std::vector<double> v;
  for (int i = 0; i < n; ++i) {
    const double s = n == 1 ? 0.0 : static_cast<double>(i) / (n - 1);
    v.push_back(r.log ? a * std::pow(b / a, s) : a + s * (b - a));
  }
  return v;
}

std::string pair_text(const std::pair<double, double>& p) {
  std::ostringstream text;
  text << p.first << "," << p.second;
  return text.str();
}

void print_box(const char* what, const std::vector<double>& x) {
  const BoxStats bs = box_stats(x);
  std::printf("%s: median %.4g, 95%% interval of the median [%.4g, %.4g], min %.4g, Q1 %.4g, Q3 %.4g, max %.4g\n", what,
              bs.median, bs.median_low, bs.median_high, bs.min, bs.q1, bs.q3, bs.max);
}

void add_bag_option(CLI::App& app, std::string& bag) {
  app.add_option("--bag", bag,
                 "analyse the run recorded in this bag of gear_simulator (record:=true, or rosbag record of its "
                 "state or state_batch topic) instead of simulating")
      ->type_name("FILE");
}

BagRun load_bag(const std::string& bag, const Common& c) {
  BagRun b;
  b.run = read_live_bag(bag);
  if (b.run.parameters_yaml.empty()) {
    b.config = load_config(c);
    std::printf("# %s has no run_info: the model is config/ with --config and --set, which must be the node's\n",
                bag.c_str());
  } else {
    b.config = parse_config(YAML::Load(b.run.parameters_yaml));
    if (!c.model.files.empty() || !c.model.sets.empty() || c.model.mu)
      std::printf("# --config, --set and --mu are left out: the bag's run_info holds the run's configuration\n");
  }
  b.period = b.run.t[1] - b.run.t[0];
  std::printf("# bag %s: %zu states from %s, t = %g ... %g s, every %g s (%g Hz)\n", bag.c_str(), b.run.t.size(),
              b.run.topic.c_str(), b.run.t.front(), b.run.t.back(), b.period, 1.0 / b.period);
  if (!b.run.note.empty()) std::printf("# %s\n", b.run.note.c_str());
  return b;
}

std::size_t first_after(const BagRun& b, double transient) {
  return static_cast<std::size_t>(std::lower_bound(b.run.t.begin(), b.run.t.end(), transient - 1e-9 * b.period) -
                                  b.run.t.begin());
}

}  // namespace gear_dynamics::tools::analyze
