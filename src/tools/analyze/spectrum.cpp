// gear_analyze spectrum: the Welch PSDs of delta and of the mesh force (or, for the bearings model,
// another output: --signal) of S1 (or of a bag's run) and of stochastic realizations, with the mesh
// harmonics and the sidebands marked.
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "common.hpp"
#include "gear_dynamics/engine/bearings.hpp"
#include "gear_dynamics/engine/ensemble.hpp"
#include "gear_dynamics/maths/spectrum.hpp"

namespace gear_dynamics::tools::analyze {
namespace {

// The sampled series of run 0 (S1, or a bag's run) and of runs 1..R (realizations): delta, and the
// second signal (the mesh force unless --signal) whose columns and peaks are named `label`.
struct SpectrumInput {
  std::vector<std::vector<double>> delta, force;
  std::string label = "force";
  double fs = 0, fm = 0, transient = 0, duration = 0, mu = 0, wall = 0;
  int k = 1, periods = 1;
  WelchOptions w;
};

class Spectrum : public Subcommand {
 public:
  std::string name() const override { return "spectrum"; }
  std::string description() const override {
    return "Welch PSD of delta and of the mesh force of S1 (and of realizations 0..R-1: mean PSD with a 95 % band); "
           "mesh harmonics and sidebands marked";
  }
  void add_options(CLI::App& app) override {
    app.add_option("--duration", duration_, "simulated time [s] (default: run.duration)")->type_name("S")->check(positive());
    app.add_option("--realizations", realizations_, "stochastic realizations")->type_name("R")->check(in_range(0))
        ->capture_default_str();
    app.add_option("--transient", transient_, "start-up dropped [s]")->type_name("S")->check(in_range(0))
        ->capture_default_str();
    app.add_option("--decimate", decimate_, "sample every K steps (default: the steps of 10 us, f_s = 100 kHz)")
        ->type_name("K")->check(in_range(1));
    app.add_option("--segment", segment_,
                   "Welch segment in samples (default 30 mesh periods; whole revolutions where the teeth differ)")
        ->type_name("L")->check(in_range(2));
    app.add_option("--overlap", overlap_, "segment overlap")->type_name("F")->check(in_range(0, 0.99))
        ->capture_default_str();
    app.add_option("--harmonics", harmonics_, "mesh harmonics marked")->type_name("N")->check(in_range(1))
        ->capture_default_str();
    app.add_option("--sidebands", sidebands_,
                   "sidebands k = 1..K of the faulty gear's rotation frequency marked around each harmonic")
        ->type_name("K")->check(in_range(0))->capture_default_str();
    app.add_option("--signal", signal_,
                   "the second series: mesh_force, or with gear_pair.model = bearings any output of gear_run's "
                   "CSV (delta_t, pinion_fx, pinion_fy, wheel_fx, wheel_fy)")
        ->type_name("NAME")->capture_default_str();
    add_bag_option(app, bag_);
  }
  int run(const Common& c) override {
    write_spectra(c, bag_.empty() ? simulate(c) : from_bag(c));
    return 0;
  }

 private:
  SpectrumInput simulate(const Common& c) const;
  SpectrumInput from_bag(const Common& c) const;
  // Default segment: 30 mesh periods, so that every mesh harmonic falls on a bin centre. With a
  // gear whose teeth differ, whole schedule periods (revolutions), up to 4 while the run holds two
  // segments: its sidebands then fall on bin centres too, 4 bins from the harmonics, clear of the
  // Hann window's leakage of a harmonic into its neighbouring bins.
  WelchOptions welch(double Tm, double fs, int periods, double available_time) const {
    const double available = available_time / Tm;
    const int revolutions = std::max(1, std::min(4, static_cast<int>(available / (2.0 * periods))));
    const double seg_default = std::round((periods > 1 ? revolutions * periods : 30.0) * Tm * fs);
    return WelchOptions{segment_ ? static_cast<std::size_t>(*segment_) : static_cast<std::size_t>(seg_default),
                        overlap_};
  }
  void write_spectra(const Common& c, const SpectrumInput& in) const;
  void write_sidebands(const Common& c, const std::vector<double>& f, const std::vector<double>& d, double fm,
                       double fr, const std::string& label) const;

  std::optional<double> duration_;
  int realizations_ = 0;
  double transient_ = 0.1;
  std::optional<int> decimate_;
  std::optional<long> segment_;
  double overlap_ = 0.5;
  int harmonics_ = 6;
  int sidebands_ = 3;
  std::string signal_ = "mesh_force";
  std::string bag_;
};

SpectrumInput Spectrum::simulate(const Common& c) const {
  const ModelConfig cfg = load_config(c, duration_);
  const BearingsOutputSpec* output = signal_output(signal_, cfg.gear.model);
  const GearPair g = derive(cfg.gear);
  const int R = realizations_;
  const double transient = transient_, h = cfg.run.time_step;
  // 100 kHz by default whatever the step: the mesh force jumps at the switches, so its spectrum
  // folds back from above Nyquist, and a coarser grid would fold more.
  const int k = decimate_ ? *decimate_ : static_cast<int>(std::max(1.0, std::round(1e-5 / h)));
  const double fs = 1.0 / (k * h), fm = 1.0 / mesh_period(g);
  const MeshSchedule schedule(g, h);
  const int periods = schedule.table() ? schedule.table()->mesh_periods() : 1;
  const WelchOptions w = welch(mesh_period(g), fs, periods, cfg.run.duration - transient);
  std::vector<LaneSpec> lanes{deterministic_lane(cfg, cfg.friction_coefficient)};
  for (int r = 0; r < R; ++r) lanes.push_back(stochastic_lane(cfg, cfg.friction_coefficient, r));
  const int L = static_cast<int>(lanes.size());
  std::vector<std::vector<double>> delta(L), force(L);
  const auto t0 = std::chrono::steady_clock::now();
  // Blocks of 16 lanes in parallel; S1 is lane 0 of block 0.
  const int per = 16, blocks = (L + per - 1) / per;
  tbb::parallel_for(0, blocks, [&](int blk) {
    const int first = blk * per, last = std::min(L, first + per);
    Ensemble e(g, h, cfg.initial, std::vector<LaneSpec>(lanes.begin() + first, lanes.begin() + last), cfg.seed);
    const std::int64_t N = cfg.run.steps(), n0 = std::llround(transient / h);
    for (std::int64_t n = 0; n <= N; ++n) {
      if (n >= n0 && (n - n0) % k == 0) {
        const model_step::MeshPoint mesh = output_mesh_point(e.mesh(), e.time());
        for (int l = 0; l < last - first; ++l) {
          delta[first + l].push_back(e.delta()[l]);
          force[first + l].push_back(output ? bearings_outputs(e, mesh, l).*output->value
                                            : mesh_force(g, mesh.stiffness, e.delta()[l], e.velocity()[l], mesh.error,
                                                         mesh.error_rate));
        }
      }
      if (n < N) e.step();
    }
  });
  SpectrumInput in;
  in.delta = std::move(delta);
  in.force = std::move(force);
  if (output) in.label = output->name;
  in.fs = fs, in.fm = fm, in.transient = transient, in.duration = cfg.run.duration, in.mu = cfg.friction_coefficient;
  in.wall = seconds_since(t0), in.k = k, in.periods = periods, in.w = w;
  return in;
}

SpectrumInput Spectrum::from_bag(const Common& c) const {
  if (signal_ != "mesh_force")
    throw std::runtime_error("--signal " + signal_ + " with --bag: a bag's run gives delta and the mesh force; "
                             "allowed with --bag: mesh_force");
  const BagRun b = load_bag(bag_, c);
  const ModelConfig& cfg = b.config;
  const GearPair g = derive(cfg.gear);
  const MeshSchedule schedule(g, cfg.run.time_step);
  const double transient = transient_, fm = 1.0 / mesh_period(g);
  SpectrumInput in;
  in.delta.assign(1, {});
  in.force.assign(1, {});
  for (std::size_t i = first_after(b, transient); i < b.run.t.size(); ++i) {
    const double t = b.run.t[i];
    in.delta[0].push_back(b.run.delta[i]);
    in.force[0].push_back(mesh_force(g, b.run.stiffness[i], b.run.delta[i], b.run.delta_dot[i],
                                     schedule.transmission_error(t), schedule.transmission_error_rate(t)));
  }
  in.fs = 1.0 / b.period, in.fm = fm, in.transient = transient, in.duration = b.run.t.back();
  in.mu = cfg.friction_coefficient, in.k = static_cast<int>(std::lround(b.period / cfg.run.time_step));
  in.periods = schedule.table() ? schedule.table()->mesh_periods() : 1;
  in.w = welch(mesh_period(g), in.fs, in.periods, b.run.t.back() - transient);
  if (in.delta[0].size() < in.w.segment)
    throw std::runtime_error("the bag's run holds " + std::to_string(in.delta[0].size()) + " states after --transient " +
                             std::to_string(transient) + " s, fewer than one Welch segment of " +
                             std::to_string(in.w.segment) + ": record longer, or give --segment");
  if (in.fs < 2.5 * fm)
    std::printf("# the recording's Nyquist frequency %g Hz is below the mesh frequency's harmonics: record at a higher "
                "publish_rate for a spectrum\n", 0.5 * in.fs);
  return in;
}

// The sidebands of the gear whose teeth differ (f_r its rotation frequency), printed and written
// as PREFIX_sidebands.csv.
void Spectrum::write_sidebands(const Common& c, const std::vector<double>& f, const std::vector<double>& d, double fm,
                               double fr, const std::string& label) const {
  const int K = sidebands_;
  const auto sb_file = open_csv(c, "sidebands");
  std::ostream& sb = sb_file->out();
  sb << "harmonic,order,frequency,bin_frequency,density,line\n";
  int found = 0;
  const std::vector<Sideband> lines = sidebands(f, d, fm, fr, harmonics_, K);
  for (const Sideband& s : lines) {
    sb << s.harmonic << "," << s.order << "," << s.frequency << "," << s.bin_frequency << "," << s.density << ","
       << (s.line ? 1 : 0) << "\n";
    found += s.line;
  }
  std::printf("sidebands of the %s at n f_m + k f_r (f_r = %.6g Hz, |k| <= %d): %d of %zu are lines\n",
              label == "force" ? "mesh force" : label.c_str(), fr, K, found, lines.size());
}

// PREFIX_psd.csv, _peaks.csv, _spectrum_info.csv (and _sidebands.csv where the teeth differ).
void Spectrum::write_spectra(const Common& c, const SpectrumInput& in) const {
  const int L = static_cast<int>(in.delta.size()), R = L - 1, k = in.k, periods = in.periods;
  const double fs = in.fs, fm = in.fm, transient = in.transient;
  const WelchOptions& w = in.w;
  const auto& delta = in.delta;
  const auto& force = in.force;
  std::vector<Psd> pd, pf;
  for (int l = 0; l < L; ++l) {
    pd.push_back(welch_psd(delta[l], fs, w));
    pf.push_back(welch_psd(force[l], fs, w));
  }
  const Psd& s1 = pd[0];
  std::printf("# spectrum: mu %g, T %g s, transient %g s, fs %g Hz (every %d steps), Hann window, segment %zu "
              "(resolution %.4g Hz, ENBW %.4g Hz), overlap %g, %zu segments, %d realizations, %.1f s wall\n",
              in.mu, in.duration, transient, fs, k, s1.segment, s1.resolution, s1.enbw, w.overlap,
              s1.segments, R, in.wall);
  std::printf("# mesh frequency f_m = %.6g Hz\n", fm);
  {
    const auto f_file = open_csv(c, "psd");
  std::ostream& f = f_file->out();
    const std::string& x = in.label;
    f << "frequency,delta_S1," << x << "_S1";
    if (R > 0)
      f << ",delta_mean,delta_mean_low,delta_mean_high,delta_run_low,delta_run_high," << x << "_mean," << x << "_mean_low,"
        << x << "_mean_high," << x << "_run_low," << x << "_run_high";
    f << "\n";
    PsdBand bd, bf;
    if (R > 0) {
      bd = psd_band(std::vector<Psd>(pd.begin() + 1, pd.end()));
      bf = psd_band(std::vector<Psd>(pf.begin() + 1, pf.end()));
    }
    for (std::size_t i = 0; i < s1.frequency.size(); ++i) {
      f << s1.frequency[i] << "," << pd[0].density[i] << "," << pf[0].density[i];
      if (R > 0)
        f << "," << bd.mean[i] << "," << bd.mean_low[i] << "," << bd.mean_high[i] << "," << bd.run_low[i] << ","
          << bd.run_high[i] << "," << bf.mean[i] << "," << bf.mean_low[i] << "," << bf.mean_high[i] << ","
          << bf.run_low[i] << "," << bf.run_high[i];
      f << "\n";
    }
    const auto pk_file = open_csv(c, "peaks");
  std::ostream& pk = pk_file->out();
    pk << "series,frequency,density,harmonic,offset,is_harmonic,prominence\n";
    const int H = harmonics_;
    const auto emit = [&](const std::string& name, const std::vector<double>& fr, const std::vector<double>& d) {
      for (const auto& p : mark_peaks(fr, d, fm, H, 8)) {
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
    emit(in.label + "_S1", s1.frequency, pf[0].density);
    if (R > 0) {
      emit("delta_mean", s1.frequency, bd.mean);
      emit(in.label + "_mean", s1.frequency, bf.mean);
    }
    if (periods > 1) write_sidebands(c, s1.frequency, pf[0].density, fm, fm / periods, in.label);
    const auto meta_file = open_csv(c, "spectrum_info");
  std::ostream& meta = meta_file->out();
    meta << "mesh_frequency,sample_rate,resolution,enbw,segment,overlap,segments,realizations,transient,duration\n"
         << fm << "," << fs << "," << s1.resolution << "," << s1.enbw << "," << s1.segment << "," << w.overlap << ","
         << s1.segments << "," << R << "," << transient << "," << in.duration << "\n";
  }
}

}  // namespace

std::unique_ptr<Subcommand> make_spectrum() { return std::make_unique<Spectrum>(); }

}  // namespace gear_dynamics::tools::analyze
