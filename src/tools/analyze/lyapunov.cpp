// gear_analyze lyapunov: the Lyapunov exponents of S1 over the phase ensemble, or along a
// parameter, from the tangent flow (every exponent) or from pairs of trajectories (the largest).
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "common.hpp"
#include "gear_dynamics/dynamics/bifurcation.hpp"
#include "gear_dynamics/dynamics/lyapunov.hpp"

namespace gear_dynamics::tools::analyze {
namespace {

// The runs whose exponents are wanted: one per phase, or one per parameter value.
struct LyapunovRuns {
  std::vector<GearLaneSpec> specs;
  std::vector<double> values;
  std::string column;  // the CSV column of `values`
  std::string what;    // "phases" or "values"
};

// PREFIX_lyapunov_running.csv: each run's running estimate over time (either method's results).
template <class Result>
void write_running(const Common& common, const LyapunovRuns& runs, const std::vector<Result>& res) {
  const auto file = open_csv(common, "lyapunov_running");
  std::ostream& out = file->out();
  out << "id,value,t,running\n";
  for (std::size_t i = 0; i < res.size(); ++i)
    for (std::size_t k = 0; k < res[i].time.size(); ++k)
      out << i << "," << runs.values[i] << "," << res[i].time[k] << "," << res[i].running[k] << "\n";
}


class Lyapunov : public Subcommand {
 public:
  std::string name() const override { return "lyapunov"; }
  std::string description() const override {
    return "Lyapunov exponents of S1 over the phase ensemble, or along a parameter (--parameter ...), averaged over "
           "[--transient, --duration]. --method tangent: both exponents from the variational equation, "
           "orthonormalised every --renormalise steps, with the trace check and per-window values; --method pairs: "
           "the largest from two trajectories renormalised every --renormalise steps";
  }
  void add_options(CLI::App& app) override {
    app.add_option("--method", method_, "tangent|pairs")->check(CLI::IsMember({"tangent", "pairs"}))
        ->capture_default_str();
    app.add_option("--phases", phases_, "members of the phase ensemble")->type_name("P")->check(in_range(1))
        ->capture_default_str();
    app.add_option("--duration", duration_, "simulated time [s]")->type_name("S")->check(positive())
        ->capture_default_str();
    app.add_option("--transient", transient_, "start-up dropped [s]")->type_name("S")->check(in_range(0))
        ->capture_default_str();
    app.add_option("--renormalise", renormalise_, "steps between renormalisations")->type_name("N")
        ->check(in_range(1))->capture_default_str();
    app.add_option("--windows", windows_, "window edges [s] (tangent)")->type_name("T0,T1,...")->delimiter(',')
        ->check(in_range(0))->capture_default_str();
    app.add_option("--separation", separation_, "initial separation in units of b and v_ref (pairs)")
        ->type_name("D0")->check(positive())->capture_default_str();
    app.add_option("--step-divisor", step_divisor_, "time step h/M (2 = h/2)")->type_name("M")->check(in_range(1))
        ->capture_default_str();
    app.add_option("--absorbed-periods", absorbed_periods_,
                   "a run without separation (delta - e > b) over its last N mesh periods counts as absorbed into "
                   "permanent contact (tangent)")
        ->type_name("N")->check(in_range(1))->capture_default_str();
    add_parameter_options(app, range_);
  }
  int run(const Common& common) override;

 private:
  LyapunovRuns runs(const ModelConfig& c) const;
  int tangent(const Common& common, const ModelConfig& c, double h, const LyapunovRuns& runs) const;
  int pairs(const Common& common, const ModelConfig& c, double h, const LyapunovRuns& runs) const;

  std::string method_ = "tangent";
  int phases_ = 64;
  double duration_ = 1.2;
  double transient_ = 0.2;
  std::int64_t renormalise_ = 100;
  std::vector<double> windows_ = {0, 0.1, 0.2, 0.4};
  double separation_ = 1e-8;
  int step_divisor_ = 1;
  int absorbed_periods_ = 100;
  ParameterRange range_;
};

int Lyapunov::run(const Common& common) {
  const ModelConfig c = load_config(common);
  const double h = c.run.time_step / step_divisor_;
  const LyapunovRuns r = runs(c);
  return method_ == "tangent" ? tangent(common, c, h, r) : pairs(common, c, h, r);
}

LyapunovRuns Lyapunov::runs(const ModelConfig& c) const {
  LyapunovRuns r;
  if (range_.parameter_option->count() > 0) {
    const ScanParameter p = parse_scan_parameter(range_.parameter);
    r.values = parameter_values(range_);
    for (double v : r.values) {
      const ModelConfig cv = with_parameter(c, p, v);
      r.specs.push_back({cv.gear, cv.friction_coefficient, cv.load.initial_mean, cv.initial});
    }
    r.column = scan_parameter_name(p);
    r.what = "values";
    return r;
  }
  const int P = phases_;
  const GearPair g = derive(c.gear);
  for (int j = 0; j < P; ++j) {
    GearInputs gi = c.gear;
    gi.mesh_phase = j * g.mesh_period_angle / P;
    r.values.push_back(gi.mesh_phase);
    r.specs.push_back({gi, c.friction_coefficient, c.load.initial_mean, c.initial});
  }
  r.column = "phase0";
  r.what = "phases";
  return r;
}

// The exponents from the tangent flow, per run (the CSV's the two largest, the Liouville check of
// all); the main window is [transient, duration].
int Lyapunov::tangent(const Common& common, const ModelConfig& c, double h, const LyapunovRuns& runs) const {
  SpectrumOptions so;
  so.duration = duration_;
  const double transient = transient_;
  so.orthonormalise_every = renormalise_ * step_divisor_;
  std::vector<double> edges = windows_;
  edges.push_back(transient);
  edges.push_back(so.duration);
  std::sort(edges.begin(), edges.end());
  edges.erase(std::unique(edges.begin(), edges.end(), [](double a, double b) { return std::fabs(a - b) < 1e-12; }),
              edges.end());
  edges.erase(std::remove_if(edges.begin(), edges.end(), [&](double e) { return e < 0 || e > so.duration + 1e-12; }),
              edges.end());
  so.windows = edges;
  const int n = static_cast<int>(runs.specs.size());
  std::vector<LyapunovSpectrum> res(n);
  const auto t0 = std::chrono::steady_clock::now();
  tbb::parallel_for(0, n, [&](int i) {
    res[i] = lyapunov_spectrum(runs.specs[i], h, so);  // scaled by b and sqrt(2 Phi b)
  });
  const double wall = seconds_since(t0);
  const auto main_window = [&](const LyapunovSpectrum& r) {
    const auto at = [&](double t) {
      for (const auto& e : r.edges)
        if (std::fabs(e.time - t) < 1e-9) return e;
      throw std::logic_error("lyapunov: no window edge at " + std::to_string(t) + " s");
    };
    return window_between(at(transient), at(so.duration));
  };
  const auto f_file = open_csv(common, "lyapunov");
  std::ostream& f = f_file->out();
  f << runs.column << ",exponent,exponent2,trace,liouville_error,last_separation,absorbed\n";
  std::vector<double> l1, l2, liouville;
  // Absorbed: left the rattle for permanent contact, delta - e > b at every step of the last
  // --absorbed-periods mesh periods (each run's own mesh period along a speed scan).
  std::vector<int> absorbed;
  for (int i = 0; i < n; ++i) {
    const double quiet = absorbed_periods_ * mesh_period(derive(runs.specs[i].gear));
    if (res[i].last_separation <= so.duration - quiet) absorbed.push_back(i);
  }
  for (int i = 0; i < n; ++i) {
    const SpectrumWindow w = main_window(res[i]);
    double err = -res[i].trace;  // the exponents' sum against the mean trace over [0, duration]
    for (double e : res[i].exponent) err += e;
    const bool in_contact = std::find(absorbed.begin(), absorbed.end(), i) != absorbed.end();
    f << runs.values[i] << "," << w.exponent[0] << "," << w.exponent[1] << "," << w.trace << "," << err << ","
      << res[i].last_separation << "," << (in_contact ? 1 : 0) << "\n";
    l1.push_back(w.exponent[0]);
    l2.push_back(w.exponent[1]);
    liouville.push_back(std::fabs(err));
  }
  const auto fw_file = open_csv(common, "lyapunov_windows");
  std::ostream& fw = fw_file->out();
  fw << "id,value,start,end,exponent,exponent2,trace\n";
  for (int i = 0; i < n; ++i)
    for (const auto& w : res[i].windows)
      fw << i << "," << runs.values[i] << "," << w.start << "," << w.end << "," << w.exponent[0] << "," << w.exponent[1]
         << "," << w.trace << "\n";
  write_running(common, runs, res);
  std::printf("# lyapunov (tangent): h %g s, averaged over [%g, %g] s, orthonormalised every %lld steps (%g s), mu %g, "
              "%d %s, %.1f s wall\n",
              h, transient, so.duration, static_cast<long long>(so.orthonormalise_every), so.orthonormalise_every * h,
              c.friction_coefficient, n, runs.what.c_str(), wall);
  print_box("largest exponent [1/s]", l1);
  print_box("second exponent [1/s]", l2);
  std::printf("absorbed into permanent contact (delta - e > b over the last %d mesh periods): %zu of %d %s",
              absorbed_periods_, absorbed.size(), n, runs.what.c_str());
  for (std::size_t k = 0; k < absorbed.size(); ++k)
    std::printf("%s%d (last separation %.4g s)", k ? ", " : ": ", absorbed[k], res[absorbed[k]].last_separation);
  std::printf("\n");
  std::printf("|sum of the %zu exponents - mean trace| over [0, %g] s: max %.3g 1/s\n", res.front().exponent.size(),
              so.duration,
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
int Lyapunov::pairs(const Common& common, const ModelConfig& c, double h, const LyapunovRuns& runs) const {
  const int M = step_divisor_;
  const double b = c.gear.backlash, v_ref = std::sqrt(2.0 * std::abs(c.load.initial_mean) * b);
  const bool bearings = c.gear.model == GearModel::kBearings;
  LyapunovOptions lo;
  lo.transient = transient_;
  lo.duration = duration_ - lo.transient;
  lo.renormalise_every = renormalise_ * M;
  lo.separation = separation_;
  lo.record_every = 10;
  const int n = static_cast<int>(runs.specs.size());
  std::vector<LyapunovResult> res(n);
  const auto t0 = std::chrono::steady_clock::now();
  const int per = 4;
  tbb::parallel_for(0, (n + per - 1) / per, [&](int blk) {
    std::vector<GearLaneSpec> lanes;
    for (int i = blk * per; i < std::min(n, blk * per + per); ++i) {
      lanes.push_back(runs.specs[i]);
      lanes.push_back(runs.specs[i]);
    }
    LyapunovOptions l = lo;
    l.scale = {b, v_ref};
    if (bearings) {  // one ensemble per run (its gear), a pair of lanes, the whole ten-state state
      for (int i = blk * per; i < std::min(n, blk * per + per); ++i) {
        const GearLaneSpec& s = runs.specs[i];
        LaneSpec lane;
        lane.mu = s.mu, lane.load_mean = s.load, lane.stochastic = false;
        Ensemble e(derive(s.gear), h, s.initial, {lane, lane}, c.seed);
        BearingsLanes sys(e);
        l.scale.clear();  // displacements in b, their rates in v_ref
        for (int k = 0; k < sys.dimension(); ++k) l.scale.push_back(sys.derivative_of(k) >= 0 ? b : v_ref);
        res[i] = largest_lyapunov(sys, l).front();
      }
      return;
    }
    GearLanes sys(lanes, h);
    const auto r = largest_lyapunov(sys, l);
    for (std::size_t k = 0; k < r.size(); ++k) res[blk * per + k] = r[k];
  });
  const double wall = seconds_since(t0);
  const auto f_file = open_csv(common, "lyapunov");
  std::ostream& f = f_file->out();
  f << runs.column << ",exponent,max_log_growth,min_log_growth,intervals\n";
  std::vector<double> ex;
  for (int i = 0; i < n; ++i) {
    f << runs.values[i] << "," << res[i].exponent << "," << res[i].max_log_growth << "," << res[i].min_log_growth << ","
      << res[i].intervals << "\n";
    ex.push_back(res[i].exponent);
  }
  write_running(common, runs, res);
  double gmax = -1e300, gmin = 1e300;
  for (const auto& r : res) { gmax = std::max(gmax, r.max_log_growth); gmin = std::min(gmin, r.min_log_growth); }
  std::printf("# lyapunov (pairs, %s): h %g s, transient %g s, averaged over %g s, renormalised every %lld steps (%g s), d0 %g "
              "(units b = %g m, v_ref = %g m/s), mu %g, %d %s, %.1f s wall\n",
              bearings ? "bearings model, its 10 states" : "torsional model", h, lo.transient, lo.duration, static_cast<long long>(lo.renormalise_every), lo.renormalise_every * h,
              lo.separation, b, v_ref, c.friction_coefficient, n, runs.what.c_str(), wall);
  print_box("largest exponent [1/s]", ex);
  std::printf("ln(d/d0) per renormalisation interval: min %.3g, max %.3g\n", gmin, gmax);
  return 0;
}

}  // namespace

std::unique_ptr<Subcommand> make_lyapunov() { return std::make_unique<Lyapunov>(); }

}  // namespace gear_dynamics::tools::analyze
