// gear_run: runs S1 and a few stochastic realizations from the configuration, writes a CSV of the
// decimated series and prints one summary line per run. No ROS master needed.
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "gear_dynamics/config/config.hpp"
#include "gear_dynamics/config/parameters.hpp"
#include "gear_dynamics/config/simulator_settings.hpp"
#include "gear_dynamics/config/sweep.hpp"
#include "gear_dynamics/engine/ensemble.hpp"
#include "gear_dynamics/engine/simulation.hpp"

namespace gd = gear_dynamics;

namespace {

const char* kUsage = R"(usage: gear_run [options]
Runs the deterministic run S1 and stochastic realizations of the spur-gear model.
  --config FILE       YAML file overlaid on the defaults (repeatable)
  --set SEC.KEY=VAL   override one parameter, e.g. --set run.duration=0.1 (repeatable)
  --mu X              friction coefficient (default: gear_pair.friction_coefficient)
  --seed N            seed (default: run.seed)
  --realizations N    stochastic realizations 0..N-1 besides S1 (default 2: S2, S3)
  --no-deterministic  leave out S1
  --rate HZ           CSV sample rate in simulated Hz (default 1000; 0 = no CSV)
  --output FILE       CSV path (default gear_run.csv; '-' = stdout)
  --print-parameters SECTION
                      print the Markdown table of a configuration section (gear_pair, load,
                      run, monte_carlo, simulator, analysis, aggregator) and exit
  --check-simulator   only validate the configuration as gear_simulator would (config/simulator.yaml
                      included): print 'valid' and exit 0, or the problems on stderr and exit 1
                      (simulate.launch runs this while it is parsed, so a bad value ends roslaunch
                      with a non-zero exit code before any node starts)
  --record-dir DIR    with --check-simulator: DIR must be an existing writable folder (record:=true)
  --sweep KEY=V1,V2,...  run every point of a grid (repeatable: the product), e.g.
                      --sweep load.sigma=0,2.5,5 or --sweep load.initial_mean=1:100:3:log
                      (from:to:count[:log]); KEY is any scalar gear_pair/load key (doc/studies.md).
                      Run names get the point, p0001_S1; a summary line per run and point.
The defaults come from the package's config/ folder: $GEAR_DYNAMICS_CONFIG_DIR if set, else the
installed share/gear_dynamics/config, else gear_dynamics/config on $ROS_PACKAGE_PATH.
Snapshot times after run.duration are dropped with a notice (a short --set run.duration run).
CSV columns (SI): run,t,delta,delta_dot,phi,center_distance.
Summary lines use the paper's units: mm, mm/s, mm s^-1/2.
)";

struct Options {
  std::vector<std::string> files;
  std::vector<std::string> sets;
  std::optional<double> mu;      // --mu, else the configuration's
  std::optional<long long> seed;  // --seed, else the configuration's
  int realizations = 2;
  bool deterministic = true;
  double rate = 1000.0;
  std::string output = "gear_run.csv";
  bool check_simulator = false;
  std::string record_dir;
  std::vector<std::string> sweeps;
};

// The Markdown table of one section, as the docs carry it.
void print_parameters(const std::string& name) {
  std::string names;
  for (const gd::SectionSpec& s : gd::parameter_sections()) {
    if (s.name == name) {
      std::cout << gd::parameter_table(s);
      return;
    }
    names += (names.empty() ? "" : ", ") + s.name;
  }
  throw std::runtime_error("--print-parameters: no section '" + name + "'; sections: " + names);
}

Options parse(int argc, char** argv) {
  Options o;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto value = [&]() -> std::string {
      if (i + 1 >= argc) throw std::runtime_error("option " + a + " needs a value");
      return argv[++i];
    };
    if (a == "--config") o.files.push_back(value());
    else if (a == "--set") o.sets.push_back(value());
    else if (a == "--mu") o.mu = std::stod(value());
    else if (a == "--seed") o.seed = std::stoll(value());
    else if (a == "--realizations") o.realizations = std::stoi(value());
    else if (a == "--no-deterministic") o.deterministic = false;
    else if (a == "--rate") o.rate = std::stod(value());
    else if (a == "--output") o.output = value();
    else if (a == "--print-parameters") { print_parameters(value()); std::exit(0); }
    else if (a == "--check-simulator") o.check_simulator = true;
    else if (a == "--record-dir") o.record_dir = value();
    else if (a == "--sweep") o.sweeps.push_back(value());
    else if (a == "-h" || a == "--help") { std::cout << kUsage; std::exit(0); }
    else throw std::runtime_error("unknown option '" + a + "'\n" + kUsage);
  }
  if (o.realizations < 0) throw std::runtime_error("--realizations must be >= 0");
  if (o.rate < 0) throw std::runtime_error("--rate must be >= 0 Hz");
  return o;
}

// "--set run.duration=0.1" as a YAML overlay.
void apply_set(YAML::Node& root, const std::string& assignment) {
  const auto eq = assignment.find('='), dot = assignment.find('.');
  if (eq == std::string::npos || dot == std::string::npos || dot > eq)
    throw std::runtime_error("--set expects SECTION.KEY=VALUE, got '" + assignment + "'");
  YAML::Node overlay;
  overlay[assignment.substr(0, dot)][assignment.substr(dot + 1, eq - dot - 1)] =
      YAML::Load(assignment.substr(eq + 1));
  gd::merge_yaml(root, overlay);
}

// The folder holding gear_pair.yaml, load.yaml and run.yaml (see kUsage); never a path fixed at
// build time, so an installed gear_run finds its installed defaults.
std::string config_dir() {
  namespace fs = std::filesystem;
  std::vector<fs::path> tried;
  if (const char* env = std::getenv("GEAR_DYNAMICS_CONFIG_DIR")) tried.emplace_back(env);
  std::error_code ec;
  const fs::path exe = fs::read_symlink("/proc/self/exe", ec);  // <prefix>/lib/gear_dynamics/gear_run
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

// Drops run.snapshot_times that lie after run.duration, with one notice, so that a short run set
// with --set run.duration=... works without restating the snapshot list.
void drop_late_snapshots(YAML::Node& root) {
  YAML::Node run = root["run"];
  double duration = 0.0;
  if (!run || !run["snapshot_times"] || !run["snapshot_times"].IsSequence() ||
      !gd::detail::as_number(run["duration"], duration))
    return;
  YAML::Node kept(YAML::NodeType::Sequence);
  std::string dropped;
  for (const YAML::Node& t : run["snapshot_times"]) {
    double v = 0.0;
    if (gd::detail::as_number(t, v) && v > duration) dropped += (dropped.empty() ? "" : ", ") + gd::detail::show(t);
    else kept.push_back(t);
  }
  if (dropped.empty()) return;
  std::cerr << "gear_run: snapshot times " << dropped << " s lie after run.duration = " << duration
            << " s: dropped\n";
  run["snapshot_times"] = kept;
}

}  // namespace

int main(int argc, char** argv) try {
  const Options opt = parse(argc, argv);
  const std::string dir = config_dir();
  std::vector<std::string> files = {dir + "/gear_pair.yaml", dir + "/load.yaml", dir + "/run.yaml"};
  if (opt.check_simulator) files.push_back(dir + "/simulator.yaml");
  files.insert(files.end(), opt.files.begin(), opt.files.end());
  YAML::Node root = gd::read_yaml_files(files);
  for (const auto& s : opt.sets) apply_set(root, s);
  // Validated with the rest: a negative value is refused by name, not ignored.
  if (opt.mu) root["gear_pair"]["friction_coefficient"] = *opt.mu;
  if (opt.seed) root["run"]["seed"] = *opt.seed;
  if (opt.check_simulator) {
    try {
      const gd::ModelConfig model = gd::parse_config(root);
      gd::parse_simulator_settings(root, model.run.time_step);
    } catch (const gd::ConfigError& e) {
      std::fprintf(stderr, "gear_simulator would refuse to start: %s\n", e.what());
      return 1;
    }
    if (!opt.record_dir.empty() && ::access(opt.record_dir.c_str(), W_OK | X_OK) != 0) {
      std::fprintf(stderr, "gear_simulator would refuse to start: record_dir '%s' is not a writable folder\n",
                   opt.record_dir.c_str());
      return 1;
    }
    std::printf("valid\n");
    return 0;
  }
  drop_late_snapshots(root);
  const gd::ModelConfig cfg = gd::parse_config(root);

  // The grid of --sweep (one point without it): every point validated before anything runs.
  std::vector<gd::SweepAxis> axes;
  for (const auto& text : opt.sweeps) axes.push_back(gd::parse_sweep_argument(text));
  const gd::Study study = gd::make_study(cfg, {cfg.friction_coefficient}, axes);

  std::ofstream file;
  std::ostream* csv = nullptr;
  if (opt.rate > 0) {
    if (opt.output == "-") {
      csv = &std::cout;
    } else {
      file.open(opt.output);
      if (!file) throw std::runtime_error("cannot write '" + opt.output + "'");
      csv = &file;
    }
    csv->precision(17);
    *csv << "run,t,delta,delta_dot,phi,center_distance\n";
  }
  for (const gd::StudyPoint& point : study.points) {
    const gd::ModelConfig& pc = point.config;
    std::string prefix;
    if (!opt.sweeps.empty()) {
      char buf[16];
      std::snprintf(buf, sizeof buf, "p%04zu_", point.index);
      prefix = buf;
      std::printf("# point %zu: %s\n", point.index, gd::point_text(study.keys(), point.values).c_str());
    }
    std::vector<gd::LaneSpec> lanes;
    std::vector<std::string> names;
    if (opt.deterministic) {
      lanes.push_back(gd::deterministic_lane(pc, pc.friction_coefficient));
      names.push_back(prefix + "S1");
    }
    for (int r = 0; r < opt.realizations; ++r) {
      lanes.push_back(gd::stochastic_lane(pc, pc.friction_coefficient, static_cast<std::uint64_t>(r)));
      names.push_back(prefix + "r" + std::to_string(r));
    }
    if (lanes.empty()) throw std::runtime_error("nothing to run: --no-deterministic with --realizations 0");

    gd::Ensemble ensemble(gd::derive(pc.gear), pc.run.time_step, pc.initial, lanes, pc.seed);
    gd::Recorder recorder;
    if (csv) {
      recorder.every = std::max<std::int64_t>(1, std::llround(1.0 / (opt.rate * pc.run.time_step)));
      recorder.record = [&](const gd::Ensemble& e, const Eigen::ArrayXd& d) {
        for (int i = 0; i < e.lanes(); ++i)
          *csv << names[i] << ',' << gd::grid_time(e.step_index(), e.time_step()) << ',' << e.delta()[i] << ',' << e.velocity()[i] << ','
               << e.load()[i] << ',' << d[i] << '\n';
      };
    }

    const auto start = std::chrono::steady_clock::now();
    const auto results = gd::simulate(ensemble, pc.run, recorder);
    const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();

    std::printf("# mu %.4g, seed %llu, h %g s, T %g s, window %g s, %zu runs in %.3f s wall\n",
                pc.friction_coefficient, static_cast<unsigned long long>(pc.seed), pc.run.time_step,
                pc.run.duration, pc.run.window, results.size(), wall);
    for (std::size_t i = 0; i < results.size(); ++i) {
      const auto& r = results[i];
      std::printf("%s: d = %.6f mm s^-1/2, t_ss = %.6f s (%s), delta(T) = %.6f mm, delta_dot(T) = %.4f mm/s, Phi(T) = %.3f mm/s^2\n",
                  names[i].c_str(), 1e3 * r.center_distance, r.steady_state_time,
                  r.reached_steady_state ? "steady" : "not steady", 1e3 * r.final_delta,
                  1e3 * r.final_delta_dot, 1e3 * r.final_load);
    }
  }
  return 0;
} catch (const std::exception& e) {
  std::fprintf(stderr, "gear_run: %s\n", e.what());
  return 1;
}
