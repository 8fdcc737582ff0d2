// gear_analyze safety: P(delta in I_d and delta_dot in I_v) over time, the first passage out of
// that safe set, Kaplan-Meier survival and the PDFs at the end, of stochastic realizations (or
// of a bag's run).
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "common.hpp"
#include "gear_dynamics/engine/ensemble.hpp"
#include "gear_dynamics/engine/simulation.hpp"
#include "gear_dynamics/maths/safety.hpp"
#include "gear_dynamics/maths/statistics.hpp"

namespace gear_dynamics::tools::analyze {
namespace {

class Safety : public Subcommand {
 public:
  std::string name() const override { return "safety"; }
  std::string description() const override {
    return "P(delta in I_d and delta_dot in I_v) over time with Wilson bands, first passage out of the safe set "
           "after --settle, Kaplan-Meier survival, PDFs (histogram + KDE)";
  }
  void add_options(CLI::App& app) override {
    app.add_option("--duration", duration_, "simulated time [s] (default: run.duration)")->type_name("S")->check(positive());
    app.add_option("--realizations", realizations_, "stochastic realizations")->type_name("R")->check(in_range(2))
        ->capture_default_str();
    app.add_option("--record-every", record_every_, "record every N steps")->type_name("N")->check(in_range(1))
        ->capture_default_str();
    app.add_option("--settle", settle_, "settling time [s]")->type_name("S")->check(in_range(0))->capture_default_str();
    app.add_option("--delta-interval", delta_mm_, "I_d [mm]")->type_name("LO,HI")->delimiter(',')
        ->default_str(pair_text(delta_mm_));
    app.add_option("--velocity-interval", velocity_mm_, "I_v [mm/s]")->type_name("LO,HI")->delimiter(',')
        ->default_str(pair_text(velocity_mm_));
    add_bag_option(app, bag_);
  }
  int run(const Common& c) override { return bag_.empty() ? simulate(c) : from_bag(c); }

 private:
  int simulate(const Common& c) const;
  int from_bag(const Common& c) const;
  // An interval in mm (or mm/s) as given, in m (m/s); LO < HI.
  static Interval metres(const char* option, const std::pair<double, double>& mm) {
    if (!(mm.first < mm.second))
      throw std::runtime_error(std::string(option) + " = " + std::to_string(mm.first) + "," +
                               std::to_string(mm.second) + " is not an interval; allowed LO < HI");
    return {mm.first * 1e-3, mm.second * 1e-3};
  }

  std::optional<double> duration_;
  int realizations_ = 100;
  std::int64_t record_every_ = 1000;
  double settle_ = 0.3;
  std::pair<double, double> delta_mm_{0.040, 0.055};
  std::pair<double, double> velocity_mm_{-16, 16};
  std::string bag_;
};

int Safety::simulate(const Common& common) const {
  const ModelConfig c = load_config(common, duration_);
  const GearPair g = derive(c.gear);
  const int R = realizations_;
  const std::int64_t every = record_every_;
  const double settle = settle_, h = c.run.time_step;
  const Interval di = metres("--delta-interval", delta_mm_);
  const Interval vi = metres("--velocity-interval", velocity_mm_);
  RecordedRuns runs;
  runs.delta.assign(R, {});
  runs.velocity.assign(R, {});
  const std::int64_t N = c.run.steps();
  for (std::int64_t n = 0; n <= N; n += every) runs.time.push_back(n * h);
  const auto t0 = std::chrono::steady_clock::now();
  const int per = 16;
  tbb::parallel_for(0, (R + per - 1) / per, [&](int blk) {
    std::vector<LaneSpec> lanes;
    for (int r = blk * per; r < std::min(R, blk * per + per); ++r)
      lanes.push_back(stochastic_lane(c, c.friction_coefficient, r));
    Ensemble e(g, h, c.initial, lanes, c.seed);
    // The engine's loop records at the multiples of `every`, as runs.time above.
    const Recorder record{every, [&](const Ensemble& en, const Eigen::ArrayXd&) {
                            for (int l = 0; l < en.lanes(); ++l) {
                              runs.delta[blk * per + l].push_back(en.delta()[l]);
                              runs.velocity[blk * per + l].push_back(en.velocity()[l]);
                            }
                          }};
    gear_dynamics::simulate(e, c.run, record);
  });
  const double wall = seconds_since(t0);
  const auto s = safety_over_time(runs, di, vi);
  const auto f_file = open_csv(common, "safety");
  std::ostream& f = f_file->out();
  f << "t,joint,joint_low,joint_high,delta,delta_low,delta_high,velocity,velocity_low,velocity_high\n";
  for (std::size_t j = 0; j < s.time.size(); ++j)
    f << s.time[j] << "," << s.joint[j].estimate << "," << s.joint[j].low << "," << s.joint[j].high << ","
      << s.delta_only[j].estimate << "," << s.delta_only[j].low << "," << s.delta_only[j].high << ","
      << s.velocity_only[j].estimate << "," << s.velocity_only[j].low << "," << s.velocity_only[j].high << "\n";
  const auto fp = first_passage(runs, di, vi, settle);
  const auto fpf_file = open_csv(common, "safety_exit");
  std::ostream& fpf = fpf_file->out();
  fpf << "run,time,event\n";
  std::size_t events = 0;
  for (int r = 0; r < R; ++r) {
    fpf << r << "," << fp.time[r] << "," << fp.event[r] << "\n";
    events += fp.event[r];
  }
  const auto km = kaplan_meier(fp.time, fp.event);
  const auto kf_file = open_csv(common, "safety_survival");
  std::ostream& kf = kf_file->out();
  kf << "t,survival,low,high,at_risk,events\n";
  kf << settle << ",1,1,1," << R << ",0\n";
  for (std::size_t i = 0; i < km.time.size(); ++i)
    kf << km.time[i] << "," << km.survival[i] << "," << km.low[i] << "," << km.high[i] << "," << km.at_risk[i] << ","
       << km.events[i] << "\n";
  // The curve ends at the last recorded time (censoring), with the last values.
  if (!km.time.empty() && km.time.back() < runs.time.back())
    kf << runs.time.back() << "," << km.survival.back() << "," << km.low.back() << "," << km.high.back() << ",0,0\n";
  // PDFs at T: histogram (doc/model.md §8 edges) and KDE with Silverman's bandwidth.
  const auto pf_file = open_csv(common, "pdf");
  std::ostream& pf = pf_file->out();
  pf << "variable,x,histogram,kde,bandwidth\n";
  const auto pdf = [&](const std::string& name, const std::vector<double>& x, double lo, double hi, double width) {
    const double bw = silverman_bandwidth(x);
    std::vector<double> grid;
    for (double v = lo; v <= hi + 1e-12 * std::abs(hi); v += width / 8) grid.push_back(v);
    const auto kde = gaussian_kde(x, grid, bw);
    const BinSpec spec{lo, hi, width};
    const Histogram hist = histogram(x, spec);
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



int Safety::from_bag(const Common& common) const {
  const BagRun b = load_bag(bag_, common);
  const double settle = settle_;
  const Interval di = metres("--delta-interval", delta_mm_);
  const Interval vi = metres("--velocity-interval", velocity_mm_);
  RecordedRuns runs;
  runs.time = b.run.t;
  runs.delta = {b.run.delta};
  runs.velocity = {b.run.delta_dot};
  const auto s = safety_over_time(runs, di, vi);
  const auto f_file = open_csv(common, "safety");
  std::ostream& f = f_file->out();
  f << "t,joint,delta,velocity\n";
  std::size_t after = 0, inside = 0;
  for (std::size_t j = 0; j < s.time.size(); ++j) {
    f << s.time[j] << "," << s.joint[j].estimate << "," << s.delta_only[j].estimate << ","
      << s.velocity_only[j].estimate << "\n";
    if (s.time[j] >= settle) ++after, inside += s.joint[j].estimate > 0.5;
  }
  const auto fp = first_passage(runs, di, vi, settle);
  const auto fpf_file = open_csv(common, "safety_exit");
  std::ostream& fpf = fpf_file->out();
  fpf << "run,time,event\n" << 0 << "," << fp.time[0] << "," << fp.event[0] << "\n";
  std::printf("# safety of the bag's run: delta in [%g, %g] m, delta_dot in [%g, %g] m/s; after %g s %zu of %zu "
              "recorded states inside (%.1f %%); %s\n",
              di.lo, di.hi, vi.lo, vi.hi, settle, inside, after, after ? 100.0 * inside / after : 0.0,
              fp.event[0] ? ("first left the safe set at t = " + std::to_string(fp.time[0]) + " s").c_str()
                          : "never left it (censored at the last state)");
  return 0;
}


}  // namespace

std::unique_ptr<Subcommand> make_safety() { return std::make_unique<Safety>(); }

}  // namespace gear_dynamics::tools::analyze
