// gear_analyze: the nonlinear-dynamics tools of doc/nonlinear-dynamics.md as one command each —
// spectrum, poincare, bifurcation, lyapunov, safety. Writes CSV (SI units) with a common prefix and
// prints a summary; --png draws the figures with scripts/plot_dynamics.py. No ROS master needed.
#include <tbb/parallel_for.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "gear_dynamics/maths/statistics.hpp"
#include "gear_dynamics/config/config.hpp"
#include "gear_dynamics/dynamics/bifurcation.hpp"
#include "gear_dynamics/dynamics/lyapunov.hpp"
#include "gear_dynamics/dynamics/poincare.hpp"
#include "gear_dynamics/maths/safety.hpp"
#include "gear_dynamics/maths/spectrum.hpp"
#include "gear_dynamics/engine/ensemble.hpp"
#include "gear_dynamics/ros/live_bag.hpp"
#include "cli.hpp"

namespace gd = gear_dynamics;

namespace {

struct Options {
  std::string command;
  gd::tools::ModelOptions model;
  std::string output = "gear_analyze";
  bool png = false;
  std::string bag;  // --bag: a live node's run instead of a simulation
  std::map<std::string, std::string> kv;  // the subcommand's valued options as given (--name value)
  bool log = false;
  double get(const std::string& k, double def) const {
    auto it = kv.find(k);
    return it == kv.end() ? def : std::stod(it->second);
  }
  std::string str(const std::string& k, const std::string& def) const {
    auto it = kv.find(k);
    return it == kv.end() ? def : it->second;
  }
};

// A subcommand's option --name VALUE, kept as text in o.kv (each command reads it with its default).
void add_valued(CLI::App& sub, Options& o, const std::string& name, const std::string& value_name,
                const std::string& description) {
  sub.add_option_function<std::string>("--" + name, [&o, name](const std::string& v) { o.kv[name] = v; },
                                       description)
      ->type_name(value_name);
}

Options parse(int argc, char** argv) {
  Options o;
  CLI::App app("Nonlinear-dynamics tools for the spur-gear model (doc/nonlinear-dynamics.md).", "gear_analyze");
  app.require_subcommand(1);
  app.fallthrough();  // the common options below may follow the subcommand
  add_valued(app, o, "duration", "S",
             "simulated time [s] (spectrum, poincare, safety: run.duration; bifurcation, lyapunov: 2.0 and 1.2)");
  gd::tools::add_model_options(app, o.model);
  app.add_option("--output", o.output, "CSV files PREFIX_<name>.csv")->type_name("PREFIX")->capture_default_str();
  app.add_flag("--png", o.png, "then draw PREFIX_*.png with scripts/plot_dynamics.py");
  app.add_option("--bag", o.bag,
                 "spectrum, poincare, safety: analyse the run recorded in this bag of gear_simulator (record:=true, "
                 "or rosbag record of its state or state_batch topic) instead of simulating")
      ->type_name("FILE");

  CLI::App* spectrum = app.add_subcommand(
      "spectrum", "Welch PSD of delta and of the mesh force of S1 (and of realizations 0..R-1: mean PSD with a "
                  "95 % band); mesh harmonics and sidebands marked");
  add_valued(*spectrum, o, "realizations", "R", "stochastic realizations (default 0)");
  add_valued(*spectrum, o, "transient", "S", "start-up dropped [s] (default 0.1)");
  add_valued(*spectrum, o, "decimate", "K", "sample every K steps (default: the steps of 10 us, f_s = 100 kHz)");
  add_valued(*spectrum, o, "segment", "L", "Welch segment in samples (default 30 mesh periods)");
  add_valued(*spectrum, o, "overlap", "F", "segment overlap (default 0.5)");
  add_valued(*spectrum, o, "harmonics", "N", "mesh harmonics marked (default 6)");
  add_valued(*spectrum, o, "sidebands", "K",
             "sidebands k = 1..K of the faulty gear's rotation frequency marked around each harmonic (default 3)");

  CLI::App* stiffness = app.add_subcommand(
      "stiffness", "the mesh stiffness K over one pinion revolution from theta1 = 0 (PREFIX_stiffness.csv: "
                   "angle[rad],stiffness[N/m]), its levels and jumps");
  add_valued(*stiffness, o, "points", "N", "points per mesh period (default 512)");

  CLI::App* poincare = app.add_subcommand(
      "poincare", "(delta, delta_dot) once per mesh period at mesh phase 0: S1, the phase ensemble phi0 = j phi_n / P, "
                  "and stochastic realizations 0..R-1");
  add_valued(*poincare, o, "phases", "P", "members of the phase ensemble (default 64)");
  add_valued(*poincare, o, "realizations", "R", "stochastic realizations (default 0)");
  add_valued(*poincare, o, "transient", "S", "start-up dropped [s] (default 0.2)");

  const auto add_parameter = [&](CLI::App& sub) {
    add_valued(sub, o, "parameter", "NAME",
               "speed|load|mu|damping (speed [rpm], load = Phi0 [m/s^2], mu, zeta_ref; default speed)");
    add_valued(sub, o, "from", "X", "first value of the parameter");
    add_valued(sub, o, "to", "Y", "last value of the parameter");
    add_valued(sub, o, "values", "N", "number of values (default 400)");
    sub.add_flag("--log", o.log, "values spaced logarithmically");
  };
  CLI::App* bifurcation = app.add_subcommand("bifurcation", "Poincare points of deterministic runs vs one parameter");
  add_parameter(*bifurcation);
  add_valued(*bifurcation, o, "transient", "S", "start-up dropped [s] (default 1.0)");

  CLI::App* lyapunov = app.add_subcommand(
      "lyapunov", "Lyapunov exponents of S1 over the phase ensemble, or along a parameter (--parameter ...), "
                  "averaged over [--transient, --duration]. --method tangent: both exponents from the variational "
                  "equation, orthonormalised every --renormalise steps, with the trace check and per-window values; "
                  "--method pairs: the largest from two trajectories renormalised every --renormalise steps");
  add_valued(*lyapunov, o, "method", "tangent|pairs", "(default tangent)");
  add_valued(*lyapunov, o, "phases", "P", "members of the phase ensemble (default 64)");
  add_valued(*lyapunov, o, "transient", "S", "start-up dropped [s] (default 0.2)");
  add_valued(*lyapunov, o, "renormalise", "N", "steps between renormalisations (default 100)");
  add_valued(*lyapunov, o, "windows", "T0,T1,...", "window edges [s] (default 0,0.1,0.2,0.4; tangent)");
  add_valued(*lyapunov, o, "separation", "D0", "initial separation in units of b and v_ref (default 1e-8; pairs)");
  add_valued(*lyapunov, o, "step-divisor", "M", "time step h/M (default 1; 2 = h/2)");
  add_parameter(*lyapunov);

  CLI::App* safety = app.add_subcommand(
      "safety", "P(delta in I_d and delta_dot in I_v) over time with Wilson bands, first passage out of the safe set "
                "after --settle, Kaplan-Meier survival, PDFs (histogram + KDE)");
  add_valued(*safety, o, "realizations", "R", "stochastic realizations (default 100)");
  add_valued(*safety, o, "record-every", "N", "record every N steps (default 1000)");
  add_valued(*safety, o, "settle", "S", "settling time [s] (default 0.3)");
  add_valued(*safety, o, "delta-interval", "LO,HI", "I_d [mm] (default 0.040,0.055)");
  add_valued(*safety, o, "velocity-interval", "LO,HI", "I_v [mm/s] (default -16,16)");

  gd::tools::parse_or_exit(app, argc, argv);
  o.command = app.get_subcommands().front()->get_name();
  return o;
}

gd::ModelConfig load_config(const Options& o, double duration) {
  YAML::Node root = gd::tools::model_yaml(o.model);
  if (duration > 0) {
    root["run"]["duration"] = duration;
    if (root["run"]["window"] && root["run"]["window"].as<double>() > duration) root["run"]["window"] = duration;
  }
  // Snapshot times are not used here; keep only those inside the run.
  double T = root["run"]["duration"].as<double>();
  YAML::Node kept(YAML::NodeType::Sequence);
  for (const YAML::Node& t : root["run"]["snapshot_times"])
    if (t.as<double>() <= T) kept.push_back(t);
  if (kept.size() == 0) kept.push_back(T);
  root["run"]["snapshot_times"] = kept;
  return gd::parse_config(root);
}

std::ofstream open_csv(const Options& o, const std::string& name) {
  const std::string path = o.output + "_" + name + ".csv";
  std::ofstream f(path);
  if (!f) throw std::runtime_error("cannot write " + path);
  f.precision(17);
  std::cout << "wrote " << path << "\n";
  return f;
}

std::vector<double> value_list(const Options& o) {
  const double a = o.get("from", NAN), b = o.get("to", NAN);
  const int n = static_cast<int>(o.get("values", 400));
  if (!std::isfinite(a) || !std::isfinite(b) || n < 1) throw std::runtime_error("--from, --to and --values are needed");
  std::vector<double> v;
  for (int i = 0; i < n; ++i) {
    const double s = n == 1 ? 0.0 : static_cast<double>(i) / (n - 1);
    v.push_back(o.log ? a * std::pow(b / a, s) : a + s * (b - a));
  }
  return v;
}

double since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

// The sidebands of the gear whose teeth differ (f_r its rotation frequency), printed and written
// as PREFIX_sidebands.csv.
void write_sidebands(const Options& o, const std::vector<double>& f, const std::vector<double>& d, double fm,
                     double fr, int harmonics) {
  const int K = static_cast<int>(o.get("sidebands", 3));
  std::ofstream sb = open_csv(o, "sidebands");
  sb << "harmonic,order,frequency,bin_frequency,density,line\n";
  int found = 0;
  const std::vector<gd::Sideband> lines = gd::sidebands(f, d, fm, fr, harmonics, K);
  for (const gd::Sideband& s : lines) {
    sb << s.harmonic << "," << s.order << "," << s.frequency << "," << s.bin_frequency << "," << s.density << ","
       << (s.line ? 1 : 0) << "\n";
    found += s.line;
  }
  std::printf("sidebands of the mesh force at n f_m + k f_r (f_r = %.6g Hz, |k| <= %d): %d of %zu are lines\n", fr, K,
              found, lines.size());
}

// ---------------------------------------------------------------------------------------------
int stiffness(const Options& o) {
  const gd::ModelConfig c = load_config(o, 0);
  gd::GearInputs in = c.gear;
  in.mesh_phase = 0.0;  // angles from the model's theta1 = 0
  const gd::GearPair g = gd::derive(in);
  const gd::MeshSchedule mesh(g, c.run.time_step);
  const int per = static_cast<int>(o.get("points", 512));
  if (per < 8) throw std::runtime_error("--points = " + std::to_string(per) + " is out of range; allowed >= 8");
  const long N = static_cast<long>(per) * g.in.pinion_teeth;
  std::ofstream f = open_csv(o, "stiffness");
  f << "angle[rad],stiffness[N/m]\n";
  double lo = INFINITY, hi = 0.0, sum = 0.0;
  for (long i = 0; i <= N; ++i) {
    const double a = i * g.mesh_period_angle / per, K = mesh.stiffness_at_angle(a);
    f << a << "," << K << "\n";
    lo = std::min(lo, K), hi = std::max(hi, K);
    if (i < N) sum += K;
  }
  std::printf("# stiffness: %s, one pinion revolution (%d mesh periods, %d points each); contact ratio %.6g: "
              "single contact on [0, %.6g) rad of each mesh period %.6g rad\n",
              g.in.mesh_stiffness == gd::MeshStiffnessModel::kSquareWave ? "square_wave" : "potential_energy",
              g.in.pinion_teeth, per, g.contact_ratio, g.single_pair_angle, g.mesh_period_angle);
  std::printf("K: mean %.6g N/m, min %.6g, max %.6g; ISO 6336 square wave k1 = %.6g, k2 = %.6g, mean %.6g\n", sum / N,
              lo, hi, g.k1, g.k2, g.k_mean);
  if (const gd::MeshTable* t = mesh.table()) {
    std::printf("schedule: %d mesh periods, %d pieces, %d nodes; jumps in the first mesh period at", t->mesh_periods(),
                t->pieces(), t->nodes());
    for (double b : t->breaks())
      if (b > 0.0 && b < g.mesh_period_angle) std::printf(" %.6g", b);
    std::printf(" rad\n");
  }
  return 0;
}

// The PSDs of delta and of the mesh force of run 0 (S1, or a bag's run) and of runs 1..R
// (realizations), with the marks and the sidebands, written as PREFIX_psd.csv, _peaks.csv,
// _spectrum_info.csv (and _sidebands.csv where the teeth differ).
struct SpectrumInput {
  std::vector<std::vector<double>> delta, force;
  double fs = 0, fm = 0, transient = 0, duration = 0, mu = 0, wall = 0;
  int k = 1, periods = 1;
  gd::WelchOptions w;
};
void write_spectra(const Options& o, const SpectrumInput& in) {
  const int L = static_cast<int>(in.delta.size()), R = L - 1, k = in.k, periods = in.periods;
  const double fs = in.fs, fm = in.fm, transient = in.transient;
  const gd::WelchOptions& w = in.w;
  const auto& delta = in.delta;
  const auto& force = in.force;
  std::vector<gd::Psd> pd, pf;
  for (int l = 0; l < L; ++l) {
    pd.push_back(gd::welch_psd(delta[l], fs, w));
    pf.push_back(gd::welch_psd(force[l], fs, w));
  }
  const gd::Psd& s1 = pd[0];
  std::printf("# spectrum: mu %g, T %g s, transient %g s, fs %g Hz (every %d steps), Hann window, segment %zu "
              "(resolution %.4g Hz, ENBW %.4g Hz), overlap %g, %zu segments, %d realizations, %.1f s wall\n",
              in.mu, in.duration, transient, fs, k, s1.segment, s1.resolution, s1.enbw, w.overlap,
              s1.segments, R, in.wall);
  std::printf("# mesh frequency f_m = %.6g Hz\n", fm);
  {
    std::ofstream f = open_csv(o, "psd");
    f << "frequency,delta_S1,force_S1";
    if (R > 0) f << ",delta_mean,delta_mean_low,delta_mean_high,delta_run_low,delta_run_high,force_mean,force_mean_low,force_mean_high,force_run_low,force_run_high";
    f << "\n";
    gd::PsdBand bd, bf;
    if (R > 0) {
      bd = gd::psd_band(std::vector<gd::Psd>(pd.begin() + 1, pd.end()));
      bf = gd::psd_band(std::vector<gd::Psd>(pf.begin() + 1, pf.end()));
    }
    for (std::size_t i = 0; i < s1.frequency.size(); ++i) {
      f << s1.frequency[i] << "," << pd[0].density[i] << "," << pf[0].density[i];
      if (R > 0)
        f << "," << bd.mean[i] << "," << bd.mean_low[i] << "," << bd.mean_high[i] << "," << bd.run_low[i] << ","
          << bd.run_high[i] << "," << bf.mean[i] << "," << bf.mean_low[i] << "," << bf.mean_high[i] << ","
          << bf.run_low[i] << "," << bf.run_high[i];
      f << "\n";
    }
    std::ofstream pk = open_csv(o, "peaks");
    pk << "series,frequency,density,harmonic,offset,is_harmonic,prominence\n";
    const int H = static_cast<int>(o.get("harmonics", 6));
    const auto emit = [&](const std::string& name, const std::vector<double>& fr, const std::vector<double>& d) {
      for (const auto& p : gd::mark_peaks(fr, d, fm, H, 8)) {
        pk << name << "," << p.frequency << "," << p.density << "," << p.harmonic << "," << p.offset << ","
           << (p.is_harmonic ? 1 : 0) << "," << p.prominence << "\n";
        if (p.is_harmonic)
          std::printf("%-12s harmonic %9.2f Hz  (%d f_m)  %.4g, prominence %.3g\n", name.c_str(), p.frequency,
                      p.harmonic, p.density, p.prominence);
        else
          std::printf("%-12s peak     %9.2f Hz  (%d f_m %+8.2f Hz)  %.4g\n", name.c_str(), p.frequency, p.harmonic,
                      p.offset, p.density);
      }
    };
    emit("delta_S1", s1.frequency, pd[0].density);
    emit("force_S1", s1.frequency, pf[0].density);
    if (R > 0) {
      emit("delta_mean", s1.frequency, bd.mean);
      emit("force_mean", s1.frequency, bf.mean);
    }
    if (periods > 1) write_sidebands(o, s1.frequency, pf[0].density, fm, fm / periods, H);
    std::ofstream meta = open_csv(o, "spectrum_info");
    meta << "mesh_frequency,sample_rate,resolution,enbw,segment,overlap,segments,realizations,transient,duration\n"
         << fm << "," << fs << "," << s1.resolution << "," << s1.enbw << "," << s1.segment << "," << w.overlap << ","
         << s1.segments << "," << R << "," << transient << "," << in.duration << "\n";
  }
}

// ---------------------------------------------------------------------------------------------
int spectrum(const Options& o) {
  const gd::ModelConfig c = load_config(o, o.get("duration", 0));
  const gd::GearPair g = gd::derive(c.gear);
  const int R = static_cast<int>(o.get("realizations", 0));
  const double transient = o.get("transient", 0.1);
  const double h = c.run.time_step;
  // 100 kHz by default whatever the step: the mesh force jumps at the switches, so its spectrum
  // folds back from above Nyquist, and a coarser grid would fold more.
  const int k = static_cast<int>(o.get("decimate", std::max(1.0, std::round(1e-5 / h))));
  const double fs = 1.0 / (k * h), fm = 1.0 / gd::mesh_period(g);
  // Default segment: 30 mesh periods, so that every mesh harmonic falls on a bin centre. With a
  // gear whose teeth differ, whole schedule periods (revolutions), up to 4 while the run holds two
  // segments: its sidebands then fall on bin centres too, 4 bins from the harmonics, clear of the
  // Hann window's leakage of a harmonic into its neighbouring bins.
  const gd::MeshSchedule schedule(g, h);
  const int periods = schedule.table() ? schedule.table()->mesh_periods() : 1;
  const double available = (c.run.duration - transient) / gd::mesh_period(g);
  const int revolutions = std::max(1, std::min(4, static_cast<int>(available / (2.0 * periods))));
  const double seg_default =
      std::round((periods > 1 ? revolutions * periods : 30.0) * gd::mesh_period(g) * fs);
  gd::WelchOptions w{static_cast<std::size_t>(o.get("segment", seg_default)), o.get("overlap", 0.5)};
  std::vector<gd::LaneSpec> lanes{gd::deterministic_lane(c, c.friction_coefficient)};
  for (int r = 0; r < R; ++r) lanes.push_back(gd::stochastic_lane(c, c.friction_coefficient, r));
  const int L = static_cast<int>(lanes.size());
  std::vector<std::vector<double>> delta(L), force(L);
  const auto t0 = std::chrono::steady_clock::now();
  // Blocks of 16 lanes in parallel; S1 is lane 0 of block 0.
  const int per = 16, blocks = (L + per - 1) / per;
  tbb::parallel_for(0, blocks, [&](int blk) {
    const int first = blk * per, last = std::min(L, first + per);
    gd::Ensemble e(g, h, c.initial, std::vector<gd::LaneSpec>(lanes.begin() + first, lanes.begin() + last), c.seed);
    const std::int64_t N = c.run.steps(), n0 = std::llround(transient / h);
    for (std::int64_t n = 0; n <= N; ++n) {
      if (n >= n0 && (n - n0) % k == 0) {
        const double t = e.time(), K = e.mesh().stiffness(t), err = e.mesh().transmission_error(t),
                     rate = e.mesh().transmission_error_rate(t);
        for (int l = 0; l < last - first; ++l) {
          delta[first + l].push_back(e.delta()[l]);
          force[first + l].push_back(gd::mesh_force(g, K, e.delta()[l], e.velocity()[l], err, rate));
        }
      }
      if (n < N) e.step();
    }
  });
  SpectrumInput in;
  in.delta = std::move(delta);
  in.force = std::move(force);
  in.fs = fs, in.fm = fm, in.transient = transient, in.duration = c.run.duration, in.mu = c.friction_coefficient;
  in.wall = since(t0), in.k = k, in.periods = periods, in.w = w;
  write_spectra(o, in);
  return 0;
}

// ---------------------------------------------------------------------------------------------
int poincare(const Options& o) {
  const gd::ModelConfig c = load_config(o, o.get("duration", 0));
  const gd::GearPair g = gd::derive(c.gear);
  const int P = static_cast<int>(o.get("phases", 64)), R = static_cast<int>(o.get("realizations", 0));
  const double transient = o.get("transient", 0.2), h = c.run.time_step, Tm = gd::mesh_period(g);
  const auto t0 = std::chrono::steady_clock::now();
  // Phase ensemble (member 0 = S1 when phi0 = 0): GearLanes, one per phase, sampled at mesh phase 0,
  // i.e. at t = (phi_n - phi0)/Omega mod T_m + k T_m (interpolated unless on the grid).
  std::vector<std::vector<gd::SectionState>> ph(P);
  tbb::parallel_for(0, P, [&](int j) {
    gd::GearInputs gi = c.gear;
    gi.mesh_phase = j * g.mesh_period_angle / P;
    gd::GearLanes sys({gd::GearLaneSpec{gi, c.friction_coefficient, c.load.initial_mean, c.initial}}, h);
    const double offset = gd::first_mesh_period_start(gd::derive(gi));  // as the batch's /gear/poincare
    ph[j] = gd::poincare_section(sys, {Tm, offset, transient, c.run.duration, {}});
  });
  std::vector<gd::SectionState> st;
  if (R > 0) {
    std::vector<gd::LaneSpec> lanes;
    for (int r = 0; r < R; ++r) lanes.push_back(gd::stochastic_lane(c, c.friction_coefficient, r));
    gd::Ensemble e(g, h, c.initial, lanes, c.seed);
    gd::EnsembleLanes sys(e);
    st = gd::poincare_section(sys, {Tm, 0.0, transient, c.run.duration, {}});
  }
  std::ofstream f = open_csv(o, "poincare");
  f << "set,run,phase0,k,t,delta,delta_dot,on_grid\n";
  for (int j = 0; j < P; ++j)
    for (const auto& p : ph[j])
      f << (j == 0 ? "S1" : "phase") << "," << j << "," << j * g.mesh_period_angle / P << "," << p.k << "," << p.time
        << "," << p.x[0] << "," << p.x[1] << "," << p.on_grid << "\n";
  for (const auto& p : st)
    f << "stochastic,r" << p.lane << ",0," << p.k << "," << p.time << "," << p.x[0] << "," << p.x[1] << "," << p.on_grid << "\n";
  std::printf("# poincare: mesh period %.6g s (%s), transient %g s, T %g s, %d phases, %d realizations, %.1f s wall\n",
              Tm, gd::on_step_grid(Tm, h) ? "a whole number of steps: grid states" : "interpolated", transient,
              c.run.duration, P, R, since(t0));
  const int period = gd::detect_period(ph[0], 16, {1e-3 * g.in.backlash, 1e-3 * std::sqrt(2 * c.load.initial_mean * g.in.backlash)});
  std::printf("S1: %zu points, %s\n", ph[0].size(), period > 0 ? ("period " + std::to_string(period)).c_str() : "no period <= 16 (aperiodic)");
  return 0;
}

// ---------------------------------------------------------------------------------------------
int bifurcation(const Options& o) {
  const gd::ModelConfig c = load_config(o, 0);
  const gd::ScanParameter p = gd::parse_scan_parameter(o.str("parameter", "speed"));
  const std::vector<double> values = value_list(o);
  gd::ScanOptions so;
  so.duration = o.get("duration", 2.0);
  so.transient = o.get("transient", 1.0);
  const auto t0 = std::chrono::steady_clock::now();
  const auto r = gd::bifurcation_scan(c, p, values, so);
  const double wall = since(t0);
  std::ofstream f = open_csv(o, "bifurcation");
  f << "value,k,t,delta,delta_dot\n";
  for (const auto& v : r)
    for (const auto& q : v.points) f << v.value << "," << q.k << "," << q.time << "," << q.x[0] << "," << q.x[1] << "\n";
  std::ofstream s = open_csv(o, "bifurcation_summary");
  s << "parameter,value,period,regime,min_gap,min_delta,points\n";
  std::map<std::string, int> count;
  for (const auto& v : r) {
    s << gd::scan_parameter_name(p) << "," << v.value << "," << v.period << ",\"" << v.regime << "\"," << v.min_gap << ","
      << v.min_delta << "," << v.points.size() << "\n";
    ++count[v.regime];
  }
  std::printf("# bifurcation over %s: %zu values %g..%g%s, %g s each (transient %g s), mu %g, %.1f s wall\n",
              gd::scan_parameter_name(p).c_str(), values.size(), values.front(), values.back(), o.log ? " (log)" : "",
              so.duration, so.transient, c.friction_coefficient, wall);
  // Ranges of equal regime.
  std::size_t i = 0;
  while (i < r.size()) {
    std::size_t j = i;
    while (j + 1 < r.size() && r[j + 1].regime == r[i].regime) ++j;
    std::printf("  %-10g .. %-10g %s (%zu values)\n", r[i].value, r[j].value, r[i].regime.c_str(), j - i + 1);
    i = j + 1;
  }
  return 0;
}

// ---------------------------------------------------------------------------------------------
struct LyapunovRuns {
  std::vector<gd::GearLaneSpec> specs;
  std::vector<double> values;
  std::string column;  // the CSV column of `values`
  std::string what;    // "phases" or "values"
};

LyapunovRuns lyapunov_runs(const Options& o, const gd::ModelConfig& c) {
  LyapunovRuns r;
  if (o.kv.count("parameter") > 0) {
    const gd::ScanParameter p = gd::parse_scan_parameter(o.str("parameter", "speed"));
    r.values = value_list(o);
    for (double v : r.values) {
      const gd::ModelConfig cv = gd::with_parameter(c, p, v);
      r.specs.push_back({cv.gear, cv.friction_coefficient, cv.load.initial_mean, cv.initial});
    }
    r.column = gd::scan_parameter_name(p);
    r.what = "values";
    return r;
  }
  const int P = static_cast<int>(o.get("phases", 64));
  const gd::GearPair g = gd::derive(c.gear);
  for (int j = 0; j < P; ++j) {
    gd::GearInputs gi = c.gear;
    gi.mesh_phase = j * g.mesh_period_angle / P;
    r.values.push_back(gi.mesh_phase);
    r.specs.push_back({gi, c.friction_coefficient, c.load.initial_mean, c.initial});
  }
  r.column = "phase0";
  r.what = "phases";
  return r;
}

void print_box(const char* what, const std::vector<double>& x) {
  const gd::BoxStats bs = gd::box_stats(x);
  std::printf("%s: median %.4g, 95%% interval of the median [%.4g, %.4g], min %.4g, Q1 %.4g, Q3 %.4g, max %.4g\n", what,
              bs.median, bs.median_low, bs.median_high, bs.min, bs.q1, bs.q3, bs.max);
}

std::vector<double> number_list(const std::string& s) {
  std::vector<double> out;
  std::stringstream in(s);
  for (std::string item; std::getline(in, item, ',');) out.push_back(std::stod(item));
  return out;
}

// Both exponents from the tangent flow, per run; the main window is [transient, duration].
int lyapunov_tangent(const Options& o, const gd::ModelConfig& c, double h, const LyapunovRuns& runs) {
  gd::SpectrumOptions so;
  so.duration = o.get("duration", 1.2);
  const double transient = o.get("transient", 0.2);
  so.orthonormalise_every = static_cast<std::int64_t>(o.get("renormalise", 100)) * static_cast<std::int64_t>(o.get("step-divisor", 1));
  std::vector<double> edges = number_list(o.str("windows", "0,0.1,0.2,0.4"));
  edges.push_back(transient);
  edges.push_back(so.duration);
  std::sort(edges.begin(), edges.end());
  edges.erase(std::unique(edges.begin(), edges.end(), [](double a, double b) { return std::fabs(a - b) < 1e-12; }),
              edges.end());
  edges.erase(std::remove_if(edges.begin(), edges.end(), [&](double e) { return e < 0 || e > so.duration + 1e-12; }),
              edges.end());
  so.windows = edges;
  const int n = static_cast<int>(runs.specs.size());
  std::vector<gd::LyapunovSpectrum> res(n);
  const auto t0 = std::chrono::steady_clock::now();
  tbb::parallel_for(0, n, [&](int i) {
    gd::SpectrumOptions si = so;
    si.scale = {c.gear.backlash, std::sqrt(2.0 * std::abs(c.load.initial_mean) * c.gear.backlash)};
    res[i] = gd::lyapunov_spectrum(runs.specs[i], h, si);
  });
  const double wall = since(t0);
  const auto main_window = [&](const gd::LyapunovSpectrum& r) {
    const auto at = [&](double t) {
      for (const auto& e : r.edges)
        if (std::fabs(e.time - t) < 1e-9) return e;
      throw std::logic_error("lyapunov: no window edge at " + std::to_string(t) + " s");
    };
    return gd::window_between(at(transient), at(so.duration));
  };
  std::ofstream f = open_csv(o, "lyapunov");
  f << runs.column << ",exponent,exponent2,trace,liouville_error\n";
  std::vector<double> l1, l2, liouville;
  for (int i = 0; i < n; ++i) {
    const gd::SpectrumWindow w = main_window(res[i]);
    const double err = res[i].exponent[0] + res[i].exponent[1] - res[i].trace;  // over [0, duration]
    f << runs.values[i] << "," << w.exponent[0] << "," << w.exponent[1] << "," << w.trace << "," << err << "\n";
    l1.push_back(w.exponent[0]);
    l2.push_back(w.exponent[1]);
    liouville.push_back(std::fabs(err));
  }
  std::ofstream fw = open_csv(o, "lyapunov_windows");
  fw << "id,value,start,end,exponent,exponent2,trace\n";
  for (int i = 0; i < n; ++i)
    for (const auto& w : res[i].windows)
      fw << i << "," << runs.values[i] << "," << w.start << "," << w.end << "," << w.exponent[0] << "," << w.exponent[1]
         << "," << w.trace << "\n";
  std::ofstream fr = open_csv(o, "lyapunov_running");
  fr << "id,value,t,running\n";
  for (int i = 0; i < n; ++i)
    for (std::size_t k = 0; k < res[i].time.size(); ++k)
      fr << i << "," << runs.values[i] << "," << res[i].time[k] << "," << res[i].running[k] << "\n";
  std::printf("# lyapunov (tangent): h %g s, averaged over [%g, %g] s, orthonormalised every %lld steps (%g s), mu %g, "
              "%d %s, %.1f s wall\n",
              h, transient, so.duration, static_cast<long long>(so.orthonormalise_every), so.orthonormalise_every * h,
              c.friction_coefficient, n, runs.what.c_str(), wall);
  print_box("largest exponent [1/s]", l1);
  print_box("second exponent [1/s]", l2);
  std::printf("|lambda1 + lambda2 - mean trace| over [0, %g] s: max %.3g 1/s\n", so.duration,
              *std::max_element(liouville.begin(), liouville.end()));
  for (std::size_t k = 0; k + 1 < edges.size(); ++k) {
    std::vector<double> wk;
    for (const auto& r : res) wk.push_back(r.windows[k].exponent[0]);
    char label[80];
    std::snprintf(label, sizeof label, "lambda1 over [%g, %g] s", edges[k], edges[k + 1]);
    print_box(label, wk);
  }
  return 0;
}

// The largest exponent from two trajectories per run (the cross-check of the tangent method).
int lyapunov_pairs(const Options& o, const gd::ModelConfig& c, double h, const LyapunovRuns& runs) {
  const int M = static_cast<int>(o.get("step-divisor", 1));
  const double b = c.gear.backlash;
  gd::LyapunovOptions lo;
  lo.transient = o.get("transient", 0.2);
  lo.duration = o.get("duration", 1.2) - lo.transient;
  lo.renormalise_every = static_cast<std::int64_t>(o.get("renormalise", 100)) * M;
  lo.separation = o.get("separation", 1e-8);
  lo.record_every = 10;
  const int n = static_cast<int>(runs.specs.size());
  std::vector<gd::LyapunovResult> res(n);
  const auto t0 = std::chrono::steady_clock::now();
  const int per = 4;
  tbb::parallel_for(0, (n + per - 1) / per, [&](int blk) {
    std::vector<gd::GearLaneSpec> lanes;
    for (int i = blk * per; i < std::min(n, blk * per + per); ++i) {
      lanes.push_back(runs.specs[i]);
      lanes.push_back(runs.specs[i]);
    }
    gd::GearLanes sys(lanes, h);
    gd::LyapunovOptions l = lo;
    l.scale = {b, std::sqrt(2.0 * std::abs(c.load.initial_mean) * b)};
    const auto r = gd::largest_lyapunov(sys, l);
    for (std::size_t k = 0; k < r.size(); ++k) res[blk * per + k] = r[k];
  });
  const double wall = since(t0);
  std::ofstream f = open_csv(o, "lyapunov");
  f << runs.column << ",exponent,max_log_growth,min_log_growth,intervals\n";
  std::vector<double> ex;
  for (int i = 0; i < n; ++i) {
    f << runs.values[i] << "," << res[i].exponent << "," << res[i].max_log_growth << "," << res[i].min_log_growth << ","
      << res[i].intervals << "\n";
    ex.push_back(res[i].exponent);
  }
  std::ofstream fr = open_csv(o, "lyapunov_running");
  fr << "id,value,t,running\n";
  for (int i = 0; i < n; ++i)
    for (std::size_t k = 0; k < res[i].time.size(); ++k)
      fr << i << "," << runs.values[i] << "," << res[i].time[k] << "," << res[i].running[k] << "\n";
  double gmax = -1e300, gmin = 1e300;
  for (const auto& r : res) { gmax = std::max(gmax, r.max_log_growth); gmin = std::min(gmin, r.min_log_growth); }
  std::printf("# lyapunov (pairs): h %g s, transient %g s, averaged over %g s, renormalised every %lld steps (%g s), d0 %g "
              "(units b = %g m, v_ref = %g m/s), mu %g, %d %s, %.1f s wall\n",
              h, lo.transient, lo.duration, static_cast<long long>(lo.renormalise_every), lo.renormalise_every * h,
              lo.separation, b, std::sqrt(2.0 * c.load.initial_mean * b), c.friction_coefficient, n, runs.what.c_str(), wall);
  print_box("largest exponent [1/s]", ex);
  std::printf("ln(d/d0) per renormalisation interval: min %.3g, max %.3g\n", gmin, gmax);
  return 0;
}

int lyapunov(const Options& o) {
  const gd::ModelConfig c = load_config(o, 0);
  const double h = c.run.time_step / o.get("step-divisor", 1);
  const LyapunovRuns runs = lyapunov_runs(o, c);
  const std::string method = o.str("method", "tangent");
  if (method == "tangent") return lyapunov_tangent(o, c, h, runs);
  if (method == "pairs") return lyapunov_pairs(o, c, h, runs);
  throw std::runtime_error("--method = '" + method + "' is not a method; allowed: tangent, pairs");
}

// ---------------------------------------------------------------------------------------------
gd::Interval interval_mm(const std::string& s, double scale) {
  const auto comma = s.find(',');
  if (comma == std::string::npos) throw std::runtime_error("an interval is LO,HI, got '" + s + "'");
  return {std::stod(s.substr(0, comma)) * scale, std::stod(s.substr(comma + 1)) * scale};
}

int safety(const Options& o) {
  const gd::ModelConfig c = load_config(o, o.get("duration", 0));
  const gd::GearPair g = gd::derive(c.gear);
  const int R = static_cast<int>(o.get("realizations", 100));
  const std::int64_t every = static_cast<std::int64_t>(o.get("record-every", 1000));
  const double settle = o.get("settle", 0.3), h = c.run.time_step;
  const gd::Interval di = interval_mm(o.str("delta-interval", "0.040,0.055"), 1e-3);
  const gd::Interval vi = interval_mm(o.str("velocity-interval", "-16,16"), 1e-3);
  if (R < 2) throw std::runtime_error("--realizations must be >= 2");
  gd::RecordedRuns runs;
  runs.delta.assign(R, {});
  runs.velocity.assign(R, {});
  const std::int64_t N = c.run.steps();
  for (std::int64_t n = 0; n <= N; n += every) runs.time.push_back(n * h);
  const auto t0 = std::chrono::steady_clock::now();
  const int per = 16;
  tbb::parallel_for(0, (R + per - 1) / per, [&](int blk) {
    std::vector<gd::LaneSpec> lanes;
    for (int r = blk * per; r < std::min(R, blk * per + per); ++r)
      lanes.push_back(gd::stochastic_lane(c, c.friction_coefficient, r));
    gd::Ensemble e(g, h, c.initial, lanes, c.seed);
    for (std::int64_t n = 0; n <= N; ++n) {
      if (n % every == 0)
        for (int l = 0; l < e.lanes(); ++l) {
          runs.delta[blk * per + l].push_back(e.delta()[l]);
          runs.velocity[blk * per + l].push_back(e.velocity()[l]);
        }
      if (n < N) e.step();
    }
  });
  const double wall = since(t0);
  const auto s = gd::safety_over_time(runs, di, vi);
  std::ofstream f = open_csv(o, "safety");
  f << "t,joint,joint_low,joint_high,delta,delta_low,delta_high,velocity,velocity_low,velocity_high\n";
  for (std::size_t j = 0; j < s.time.size(); ++j)
    f << s.time[j] << "," << s.joint[j].estimate << "," << s.joint[j].low << "," << s.joint[j].high << ","
      << s.delta_only[j].estimate << "," << s.delta_only[j].low << "," << s.delta_only[j].high << ","
      << s.velocity_only[j].estimate << "," << s.velocity_only[j].low << "," << s.velocity_only[j].high << "\n";
  const auto fp = gd::first_passage(runs, di, vi, settle);
  std::ofstream fpf = open_csv(o, "first_passage");
  fpf << "run,time,event\n";
  std::size_t events = 0;
  for (int r = 0; r < R; ++r) {
    fpf << r << "," << fp.time[r] << "," << fp.event[r] << "\n";
    events += fp.event[r];
  }
  const auto km = gd::kaplan_meier(fp.time, fp.event);
  std::ofstream kf = open_csv(o, "survival");
  kf << "t,survival,low,high,at_risk,events\n";
  kf << settle << ",1,1,1," << R << ",0\n";
  for (std::size_t i = 0; i < km.time.size(); ++i)
    kf << km.time[i] << "," << km.survival[i] << "," << km.low[i] << "," << km.high[i] << "," << km.at_risk[i] << ","
       << km.events[i] << "\n";
  // The curve ends at the last recorded time (censoring), with the last values.
  if (!km.time.empty() && km.time.back() < runs.time.back())
    kf << runs.time.back() << "," << km.survival.back() << "," << km.low.back() << "," << km.high.back() << ",0,0\n";
  // PDFs at T: histogram (doc/model.md §8 edges) and KDE with Silverman's bandwidth.
  std::ofstream pf = open_csv(o, "pdf");
  pf << "variable,x,histogram,kde,bandwidth\n";
  const auto pdf = [&](const std::string& name, const std::vector<double>& x, double lo, double hi, double width) {
    const double bw = gd::silverman_bandwidth(x);
    std::vector<double> grid;
    for (double v = lo; v <= hi + 1e-12 * std::abs(hi); v += width / 8) grid.push_back(v);
    const auto kde = gd::gaussian_kde(x, grid, bw);
    const gd::BinSpec spec{lo, hi, width};
    const gd::Histogram hist = gd::histogram(x, spec);
    for (std::size_t i = 0; i < grid.size(); ++i) {
      const std::size_t bin = std::min<std::size_t>(hist.counts.size() - 1, static_cast<std::size_t>((grid[i] - lo) / width));
      pf << name << "," << grid[i] << "," << hist.density(bin) << "," << kde[i] << "," << bw << "\n";
    }
    return bw;
  };
  std::vector<double> dT, vT;
  for (int r = 0; r < R; ++r) { dT.push_back(runs.delta[r].back()); vT.push_back(runs.velocity[r].back()); }
  const double bwd = pdf("delta", dT, 0.030e-3, 0.060e-3, 0.0005e-3), bwv = pdf("delta_dot", vT, -0.040, 0.040, 0.002);
  std::printf("# safety: %d realizations, mu %g, T %g s, recorded every %lld steps, delta in [%g, %g] m, delta_dot in [%g, %g] m/s, %.1f s wall\n",
              R, c.friction_coefficient, c.run.duration, static_cast<long long>(every), di.lo, di.hi, vi.lo, vi.hi, wall);
  std::printf("P(safe at T) = %.3f [%.3f, %.3f]; first passage after %g s: %zu of %d runs left the safe set; "
              "KM S(T) = %.3f; KDE bandwidths (Silverman) %.3g m, %.3g m/s\n",
              s.joint.back().estimate, s.joint.back().low, s.joint.back().high, settle, events, R,
              km.survival.empty() ? 1.0 : km.survival.back(), bwd, bwv);
  return 0;
}

// ---------------------------------------------------------------------------------------------
// A live node's run read from its bag (--bag): its configuration from the bag's run_info.
struct BagRun {
  gd::ModelConfig config;
  gd::LiveBagRun run;
  double period = 0;  // the recording period [s]
};

BagRun load_bag(const Options& o) {
  BagRun b;
  b.run = gd::read_live_bag(o.bag);
  if (b.run.parameters_yaml.empty()) {
    b.config = load_config(o, 0);
    std::printf("# %s has no run_info: the model is config/ with --config and --set, which must be the node's\n",
                o.bag.c_str());
  } else {
    b.config = gd::parse_config(YAML::Load(b.run.parameters_yaml));
    if (!o.model.files.empty() || !o.model.sets.empty() || o.model.mu)
      std::printf("# --config, --set and --mu are left out: the bag's run_info holds the run's configuration\n");
  }
  b.period = b.run.t[1] - b.run.t[0];
  std::printf("# bag %s: %zu states from %s, t = %g ... %g s, every %g s (%g Hz)\n", o.bag.c_str(), b.run.t.size(),
              b.run.topic.c_str(), b.run.t.front(), b.run.t.back(), b.period, 1.0 / b.period);
  if (!b.run.note.empty()) std::printf("# %s\n", b.run.note.c_str());
  return b;
}

// The first recorded state at or after `transient`.
std::size_t first_after(const BagRun& b, double transient) {
  return static_cast<std::size_t>(std::lower_bound(b.run.t.begin(), b.run.t.end(), transient - 1e-9 * b.period) -
                                  b.run.t.begin());
}

int spectrum_of_bag(const Options& o) {
  const BagRun b = load_bag(o);
  const gd::ModelConfig& c = b.config;
  const gd::GearPair g = gd::derive(c.gear);
  const gd::MeshSchedule schedule(g, c.run.time_step);
  const double transient = o.get("transient", 0.1), fm = 1.0 / gd::mesh_period(g);
  SpectrumInput in;
  in.delta.assign(1, {});
  in.force.assign(1, {});
  for (std::size_t i = first_after(b, transient); i < b.run.t.size(); ++i) {
    const double t = b.run.t[i];
    in.delta[0].push_back(b.run.delta[i]);
    in.force[0].push_back(gd::mesh_force(g, b.run.stiffness[i], b.run.delta[i], b.run.delta_dot[i],
                                         schedule.transmission_error(t), schedule.transmission_error_rate(t)));
  }
  in.fs = 1.0 / b.period, in.fm = fm, in.transient = transient, in.duration = b.run.t.back();
  in.mu = c.friction_coefficient, in.k = static_cast<int>(std::lround(b.period / c.run.time_step));
  in.periods = schedule.table() ? schedule.table()->mesh_periods() : 1;
  const double available = (b.run.t.back() - transient) / gd::mesh_period(g);
  const int revolutions = std::max(1, std::min(4, static_cast<int>(available / (2.0 * in.periods))));
  const double seg_default =
      std::round((in.periods > 1 ? revolutions * in.periods : 30.0) * gd::mesh_period(g) * in.fs);
  in.w = gd::WelchOptions{static_cast<std::size_t>(o.get("segment", seg_default)), o.get("overlap", 0.5)};
  if (in.delta[0].size() < in.w.segment)
    throw std::runtime_error("the bag's run holds " + std::to_string(in.delta[0].size()) + " states after --transient " +
                             std::to_string(transient) + " s, fewer than one Welch segment of " +
                             std::to_string(in.w.segment) + ": record longer, or give --segment");
  if (in.fs < 2.5 * fm)
    std::printf("# the recording's Nyquist frequency %g Hz is below the mesh frequency's harmonics: record at a higher "
                "publish_rate for a spectrum\n", 0.5 * in.fs);
  write_spectra(o, in);
  return 0;
}

int poincare_of_bag(const Options& o) {
  const BagRun b = load_bag(o);
  const gd::GearPair g = gd::derive(b.config.gear);
  const double transient = o.get("transient", 0.2), Tm = gd::mesh_period(g), dt = b.period;
  const auto& r = b.run;
  std::ofstream f = open_csv(o, "poincare");
  f << "set,run,phase0,k,t,delta,delta_dot,on_grid\n";
  // Mesh phase 0 at t = first_mesh_period_start + k T_m: a recorded state where that is a recording
  // time, else the cubic Hermite through the two recorded states around it.
  std::vector<gd::SectionState> points;
  const double offset = gd::first_mesh_period_start(g);
  for (std::int64_t k = 0;; ++k) {
    const double t = offset + static_cast<double>(k) * Tm;
    if (t > r.t.back() + 1e-9 * dt) break;
    if (t < transient - 1e-9 * dt) continue;
    const double u = (t - r.t.front()) / dt;
    const auto i = static_cast<std::size_t>(std::max(0.0, std::floor(u + 1e-9)));
    const double s = t - r.t[i];
    gd::SectionState p;
    p.k = k, p.time = t;
    p.on_grid = std::abs(s) <= 1e-9 * dt || i + 1 >= r.t.size();
    p.x = p.on_grid ? std::vector<double>{r.delta[i], r.delta_dot[i]}
                    : std::vector<double>{gd::hermite_in_step(r.delta[i], r.delta_dot[i], r.delta[i + 1],
                                                               r.delta_dot[i + 1], s, dt),
                                          gd::hermite_slope_in_step(r.delta[i], r.delta_dot[i], r.delta[i + 1],
                                                                    r.delta_dot[i + 1], s, dt)};
    f << "bag,0," << g.in.mesh_phase << "," << p.k << "," << p.time << "," << p.x[0] << "," << p.x[1] << ","
      << p.on_grid << "\n";
    points.push_back(p);
  }
  const int period = gd::detect_period(points, 16, {1e-3 * g.in.backlash, 1e-3 * std::sqrt(2 * b.config.load.initial_mean * g.in.backlash)});
  std::printf("# poincare of the bag: mesh period %.6g s (%s), transient %g s; %zu points, %s\n", Tm,
              gd::on_step_grid(Tm, dt) ? "a whole number of recording periods: recorded states"
                                       : "interpolated between recorded states",
              transient, points.size(), period > 0 ? ("period " + std::to_string(period)).c_str() : "no period <= 16");
  return 0;
}

int safety_of_bag(const Options& o) {
  const BagRun b = load_bag(o);
  const double settle = o.get("settle", 0.3);
  const gd::Interval di = interval_mm(o.str("delta-interval", "0.040,0.055"), 1e-3);
  const gd::Interval vi = interval_mm(o.str("velocity-interval", "-16,16"), 1e-3);
  gd::RecordedRuns runs;
  runs.time = b.run.t;
  runs.delta = {b.run.delta};
  runs.velocity = {b.run.delta_dot};
  const auto s = gd::safety_over_time(runs, di, vi);
  std::ofstream f = open_csv(o, "safety");
  f << "t,joint,delta,velocity\n";
  std::size_t after = 0, inside = 0;
  for (std::size_t j = 0; j < s.time.size(); ++j) {
    f << s.time[j] << "," << s.joint[j].estimate << "," << s.delta_only[j].estimate << ","
      << s.velocity_only[j].estimate << "\n";
    if (s.time[j] >= settle) ++after, inside += s.joint[j].estimate > 0.5;
  }
  const auto fp = gd::first_passage(runs, di, vi, settle);
  std::ofstream fpf = open_csv(o, "first_passage");
  fpf << "run,time,event\n" << 0 << "," << fp.time[0] << "," << fp.event[0] << "\n";
  std::printf("# safety of the bag's run: delta in [%g, %g] m, delta_dot in [%g, %g] m/s; after %g s %zu of %zu "
              "recorded states inside (%.1f %%); %s\n",
              di.lo, di.hi, vi.lo, vi.hi, settle, inside, after, after ? 100.0 * inside / after : 0.0,
              fp.event[0] ? ("first left the safe set at t = " + std::to_string(fp.time[0]) + " s").c_str()
                          : "never left it (censored at the last state)");
  return 0;
}

void draw(const Options& o) {
  namespace fs = std::filesystem;
  std::cout.flush();
  std::fflush(stdout);  // the summary before the plot script's lines
  const fs::path script = fs::path(gd::tools::config_dir()).parent_path() / "scripts" / "plot_dynamics.py";
  if (!fs::exists(script)) throw std::runtime_error("--png: cannot find " + script.string());
  const std::string cmd = "/usr/bin/python3 '" + script.string() + "' " + o.command + " '" + o.output + "'";
  if (std::system(cmd.c_str()) != 0) throw std::runtime_error("--png: '" + cmd + "' failed");
}

}  // namespace

int main(int argc, char** argv) try {
  const Options o = parse(argc, argv);
  int rc = 0;
  if (!o.bag.empty() && o.command != "spectrum" && o.command != "poincare" && o.command != "safety")
    throw std::runtime_error("--bag works with spectrum, poincare and safety, not " + o.command);
  if (!o.bag.empty() && o.command == "spectrum") rc = spectrum_of_bag(o);
  else if (!o.bag.empty() && o.command == "poincare") rc = poincare_of_bag(o);
  else if (!o.bag.empty()) rc = safety_of_bag(o);
  else if (o.command == "spectrum") rc = spectrum(o);
  else if (o.command == "poincare") rc = poincare(o);
  else if (o.command == "bifurcation") rc = bifurcation(o);
  else if (o.command == "lyapunov") rc = lyapunov(o);
  else if (o.command == "safety") rc = safety(o);
  else if (o.command == "stiffness") rc = stiffness(o);
  else throw std::runtime_error("unknown subcommand '" + o.command + "' (gear_analyze --help)");
  if (rc == 0 && o.png) draw(o);
  return rc;
} catch (const std::exception& e) {
  std::cerr << "gear_analyze: " << e.what() << "\n";
  return 1;
}
