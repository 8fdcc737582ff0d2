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
#include "gear_dynamics/engine/instruction_set.hpp"
#include "gear_dynamics/config/parameters.hpp"
#include "gear_dynamics/config/simulator_settings.hpp"
#include "gear_dynamics/config/sweep.hpp"
#include "gear_dynamics/engine/bearings.hpp"
#include "gear_dynamics/engine/ensemble.hpp"
#include "gear_dynamics/engine/observers.hpp"
#include "gear_dynamics/engine/simulation.hpp"
#include "gear_dynamics/model/gear_urdf.hpp"
#include "cli.hpp"

namespace gd = gear_dynamics;

namespace {

const char* kDescription = R"(Runs the deterministic run S1 and stochastic realizations of the spur-gear model.
The defaults come from the package's config/ folder: $GEAR_DYNAMICS_CONFIG_DIR if set, else the
installed share/gear_dynamics/config, else gear_dynamics/config on $ROS_PACKAGE_PATH.
Snapshot times after run.duration are dropped with a notice (a short --set run.duration run).
CSV columns (SI): run,t,delta,delta_dot,phi,center_distance; with gear_pair.model = bearings delta is
the mesh deflection delta_m, followed by delta_t,mesh_force,pinion_fx,pinion_fy,wheel_fx,wheel_fy,
and each run's summary by the window's mean and RMS of the forces [N].
Summary lines use the paper's units: mm, mm/s, mm s^-1/2.)";

struct Options {
  gd::tools::ModelOptions model;
  std::optional<long long> seed;  // --seed, else the configuration's
  int realizations = 2;
  bool deterministic = true;
  double rate = 1000.0;
  std::string output = "gear_run.csv";
  std::optional<std::string> print_parameters;
  bool check_simulator = false;
  bool print_urdf = false;
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
  CLI::App app(kDescription, "gear_run");
  gd::tools::add_model_options(app, o.model);
  app.add_option("--seed", o.seed, "seed (default: run.seed)")->type_name("N");
  app.add_option("--realizations", o.realizations, "stochastic realizations 0..N-1 besides S1 (S2, S3)")
      ->type_name("N")->capture_default_str();
  app.add_flag("!--no-deterministic", o.deterministic, "leave out S1");
  app.add_option("--rate", o.rate, "CSV sample rate in simulated Hz (0 = no CSV)")
      ->type_name("HZ")->capture_default_str();
  app.add_option("--output", o.output, "CSV path ('-' = stdout)")->type_name("FILE")->capture_default_str();
  app.add_option("--print-parameters", o.print_parameters,
                 "print the Markdown table of a configuration section and exit")
      ->type_name("SECTION");
  app.add_flag("--check-simulator", o.check_simulator, "only validate the configuration as gear_simulator would");
  app.add_flag("--print-urdf", o.print_urdf, "print the URDF of the configured gear pair and exit");
  app.add_option("--record-dir", o.record_dir, "with --check-simulator: DIR must be a writable folder")
      ->type_name("DIR");
  gd::tools::add_repeatable(app, "--sweep", o.sweeps, "run every point of a grid (repeatable: the product)")
      ->type_name("KEY=V1,V2,...");
  app.footer(R"(--print-parameters SECTION: gear_pair, load, run, monte_carlo, simulator, analysis or aggregator.
--check-simulator: config/simulator.yaml included; prints 'valid' and exits 0, or the problems on
  stderr and exits 1 (simulate.launch runs this while it is parsed, so a bad value ends roslaunch
  with a non-zero exit code before any node starts); --record-dir for record:=true.
--print-urdf: config/simulator.yaml included, validated as --check-simulator does; prints the
  gear pair's URDF at the configured gear (simulate.launch tf:=true loads it as robot_description).
--sweep KEY=V1,V2,... or KEY=from:to:count[:log], e.g. --sweep load.sigma=0,2.5,5 or
  --sweep load.initial_mean=1:100:3:log; KEY is any scalar gear_pair/load key (doc/studies.md).
  Run names get the point, p0001_S1; a summary line per run and point.)");
  gd::tools::parse_or_exit(app, argc, argv);
  if (o.realizations < 0) throw std::runtime_error("--realizations must be >= 0");
  if (o.rate < 0) throw std::runtime_error("--rate must be >= 0 Hz");
  return o;
}

// The bearings model's window forces of a run (/gear/bearing_summary's), each mean and RMS [N].
void print_bearing_forces(const gd::BearingForces& f) {
  std::printf("  over the window, mean / RMS [N]:");
  const char* separator = " ";
  for (const gd::BearingsOutputSpec& s : gd::kBearingsOutputs) {
    if (!s.window) continue;
    const gd::ForceStatistics& w = f.*s.window;
    std::printf("%s%s %.6g / %.6g", separator, s.name, w.mean, w.rms);
    separator = ", ";
  }
  std::printf("\n");
}

}  // namespace

int main(int argc, char** argv) try {
  const Options opt = parse(argc, argv);
  if (opt.print_parameters) {
    print_parameters(*opt.print_parameters);
    return 0;
  }
  // The simulator's commands take simulate.launch's overlays, simulator keys included.
  const bool simulator = opt.check_simulator || opt.print_urdf;
  YAML::Node root = gd::tools::model_yaml(opt.model, simulator ? std::vector<std::string>{"simulator.yaml"}
                                                               : std::vector<std::string>{});
  // Validated with the rest: a negative value is refused by name, not ignored.
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
  if (opt.print_urdf) {
    const gd::ModelConfig model = gd::parse_config(root);
    gd::parse_simulator_settings(root, model.run.time_step);
    std::fputs(gd::gear_pair_urdf(gd::derive(model.gear)).c_str(), stdout);
    return 0;
  }
  if (const std::string notice = gd::tools::drop_late_snapshots(root); !notice.empty())
    std::cerr << "gear_run: " << notice << "\n";
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
    *csv << "run,t,delta,delta_dot,phi,center_distance";
    if (cfg.gear.model == gd::GearModel::kBearings)
      for (const gd::BearingsOutputSpec& s : gd::kBearingsOutputs) *csv << ',' << s.name;
    *csv << '\n';
  }
  for (const gd::StudyPoint& point : study.points) {
    const gd::ModelConfig& pc = point.config;
    std::string prefix;
    if (!opt.sweeps.empty()) {
      char buf[16];
      std::snprintf(buf, sizeof buf, "p%04zu_", point.index);
      prefix = buf;
      std::printf("# point %zu: %s\n", point.index, gd::point_text(study.axes, point.values).c_str());
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
    const bool bearings = pc.gear.model == gd::GearModel::kBearings;
    gd::Ensemble ensemble(gd::derive(pc.gear), pc.run.time_step, pc.initial, lanes, pc.seed);
    gd::Recorder recorder;
    if (csv) {
      recorder.every = std::max<std::int64_t>(1, std::llround(1.0 / (opt.rate * pc.run.time_step)));
      recorder.record = [&](const gd::Ensemble& e, const Eigen::ArrayXd& d) {
        const gd::model_step::MeshPoint mesh =
            bearings ? gd::output_mesh_point(e.mesh(), e.time()) : gd::model_step::MeshPoint{};
        for (int i = 0; i < e.lanes(); ++i) {
          *csv << names[i] << ',' << gd::grid_time(e.step_index(), e.time_step()) << ',' << e.delta()[i] << ','
               << e.velocity()[i] << ',' << e.load()[i] << ',' << d[i];
          if (bearings) {
            const gd::BearingsOutputs o = gd::bearings_outputs(e, mesh, i);
            for (const gd::BearingsOutputSpec& s : gd::kBearingsOutputs) *csv << ',' << o.*s.value;
          }
          *csv << '\n';
        }
      };
    }

    const auto start = std::chrono::steady_clock::now();
    const auto results = gd::simulate(ensemble, pc.run, recorder);
    const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();

    std::printf("# mu %.4g, seed %llu, h %g s, T %g s, window %g s, %zu runs in %.3f s wall, %s\n",
                pc.friction_coefficient, static_cast<unsigned long long>(pc.seed), pc.run.time_step,
                pc.run.duration, pc.run.window, results.size(), wall, gd::instruction_set_description().c_str());
    for (std::size_t i = 0; i < results.size(); ++i) {
      const auto& r = results[i];
      std::printf("%s: d = %.6f mm s^-1/2, t_ss = %.6f s (%s), delta(T) = %.6f mm, delta_dot(T) = %.4f mm/s, Phi(T) = %.3f mm/s^2\n",
                  names[i].c_str(), 1e3 * r.center_distance, r.steady_state_time,
                  r.reached_steady_state ? "steady" : "not steady", 1e3 * r.final_delta,
                  1e3 * r.final_delta_dot, 1e3 * r.final_load);
      if (r.bearings) print_bearing_forces(*r.bearings);
    }
  }
  return 0;
} catch (const std::exception& e) {
  std::fprintf(stderr, "gear_run: %s\n", e.what());
  return 1;
}
