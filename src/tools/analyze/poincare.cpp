// gear_analyze poincare: (delta, delta_dot) once per mesh period at mesh phase 0, of S1, the phase
// ensemble and stochastic realizations (or of a bag's run), and S1's period. For the bearings model
// (delta, delta_dot) are the mesh deflection delta_m and its rate.
#include <tbb/parallel_for.h>

#include <cmath>
#include <cstdio>

#include "common.hpp"
#include "gear_dynamics/dynamics/bifurcation.hpp"
#include "gear_dynamics/dynamics/poincare.hpp"
#include "gear_dynamics/engine/ensemble.hpp"

namespace gear_dynamics::tools::analyze {
namespace {

class Poincare : public Subcommand {
 public:
  std::string name() const override { return "poincare"; }
  std::string description() const override {
    return "(delta, delta_dot) once per mesh period at mesh phase 0: S1, the phase ensemble phi0 = j phi_n / P, "
           "and stochastic realizations 0..R-1";
  }
  void add_options(CLI::App& app) override {
    app.add_option("--duration", duration_, "simulated time [s] (default: run.duration)")->type_name("S")->check(positive());
    app.add_option("--phases", phases_, "members of the phase ensemble")->type_name("P")->check(in_range(1))
        ->capture_default_str();
    app.add_option("--realizations", realizations_, "stochastic realizations")->type_name("R")->check(in_range(0))
        ->capture_default_str();
    app.add_option("--transient", transient_, "start-up dropped [s]")->type_name("S")->check(in_range(0))
        ->capture_default_str();
    add_bag_option(app, bag_);
  }
  int run(const Common& c) override { return bag_.empty() ? simulate(c) : from_bag(c); }

 private:
  int simulate(const Common& c) const;
  int from_bag(const Common& c) const;

  std::optional<double> duration_;
  int phases_ = 64;
  int realizations_ = 0;
  double transient_ = 0.2;
  std::string bag_;
};

int Poincare::simulate(const Common& c) const {
  const ModelConfig cfg = load_config(c, duration_);
  const GearPair g = derive(cfg.gear);
  const int P = phases_, R = realizations_;
  const double transient = transient_, h = cfg.run.time_step, Tm = mesh_period(g);
  const auto t0 = std::chrono::steady_clock::now();
  // Phase ensemble (member 0 = S1 when phi0 = 0): GearLanes, one per phase, sampled at mesh phase 0,
  // i.e. at t = (phi_n - phi0)/Omega mod T_m + k T_m (interpolated unless on the grid).
  std::vector<std::vector<SectionState>> ph(P);
  tbb::parallel_for(0, P, [&](int j) {
    GearInputs gi = cfg.gear;
    gi.mesh_phase = j * g.mesh_period_angle / P;
    const double offset = first_mesh_period_start(derive(gi));  // as the batch's /gear/poincare
    const PoincareOptions section{Tm, offset, transient, cfg.run.duration, {}};
    if (cfg.gear.model == GearModel::kBearings) {  // the engine's lanes: delta_m and its rate
      Ensemble e(derive(gi), h, cfg.initial, {deterministic_lane(cfg, cfg.friction_coefficient)}, cfg.seed);
      EnsembleLanes sys(e);
      ph[j] = poincare_section(sys, section);
    } else {
      GearLanes sys({GearLaneSpec{gi, cfg.friction_coefficient, cfg.load.initial_mean, cfg.initial}}, h);
      ph[j] = poincare_section(sys, section);
    }
  });
  std::vector<SectionState> st;
  if (R > 0) {
    std::vector<LaneSpec> lanes;
    for (int r = 0; r < R; ++r) lanes.push_back(stochastic_lane(cfg, cfg.friction_coefficient, r));
    Ensemble e(g, h, cfg.initial, lanes, cfg.seed);
    EnsembleLanes sys(e);
    st = poincare_section(sys, {Tm, 0.0, transient, cfg.run.duration, {}});
  }
  const auto f_file = open_csv(c, "poincare");
  std::ostream& f = f_file->out();
  f << "set,run,phase0,k,t,delta,delta_dot,on_grid\n";
  for (int j = 0; j < P; ++j)
    for (const auto& p : ph[j])
      f << (j == 0 ? "S1" : "phase") << "," << j << "," << j * g.mesh_period_angle / P << "," << p.k << "," << p.time
        << "," << p.x[0] << "," << p.x[1] << "," << p.on_grid << "\n";
  for (const auto& p : st)
    f << "stochastic,r" << p.lane << ",0," << p.k << "," << p.time << "," << p.x[0] << "," << p.x[1] << "," << p.on_grid << "\n";
  std::printf("# poincare: mesh period %.6g s (%s), transient %g s, T %g s, %d phases, %d realizations, %.1f s wall\n",
              Tm, on_step_grid(Tm, h) ? "a whole number of steps: grid states" : "interpolated", transient,
              cfg.run.duration, P, R, seconds_since(t0));
  const int limit = period_search_limit(cfg.gear, 16);
  const int period = detect_period(ph[0], limit, {1e-3 * g.in.backlash, 1e-3 * std::sqrt(2 * cfg.load.initial_mean * g.in.backlash)});
  std::printf("S1: %zu points, %s\n", ph[0].size(), period > 0 ? ("period " + std::to_string(period)).c_str() : ("no period <= " + std::to_string(limit) + " (aperiodic)").c_str());
  return 0;
}

int Poincare::from_bag(const Common& c) const {
  const BagRun b = load_bag(bag_, c);
  const GearPair g = derive(b.config.gear);
  const double transient = transient_, Tm = mesh_period(g), dt = b.period;
  const auto& r = b.run;
  const auto f_file = open_csv(c, "poincare");
  std::ostream& f = f_file->out();
  f << "set,run,phase0,k,t,delta,delta_dot,on_grid\n";
  // Mesh phase 0 at t = first_mesh_period_start + k T_m: a recorded state where that is a recording
  // time, else the cubic Hermite through the two recorded states around it.
  std::vector<SectionState> points;
  const double offset = first_mesh_period_start(g);
  for (std::int64_t k = 0;; ++k) {
    const double t = offset + static_cast<double>(k) * Tm;
    if (t > r.t.back() + 1e-9 * dt) break;
    if (t < transient - 1e-9 * dt) continue;
    const double u = (t - r.t.front()) / dt;
    const auto i = static_cast<std::size_t>(std::max(0.0, std::floor(u + 1e-9)));
    const double s = t - r.t[i];
    SectionState p;
    p.k = k, p.time = t;
    p.on_grid = std::abs(s) <= 1e-9 * dt || i + 1 >= r.t.size();
    p.x = p.on_grid ? std::vector<double>{r.delta[i], r.delta_dot[i]}
                    : std::vector<double>{hermite_in_step(r.delta[i], r.delta_dot[i], r.delta[i + 1],
                                                               r.delta_dot[i + 1], s, dt),
                                          hermite_slope_in_step(r.delta[i], r.delta_dot[i], r.delta[i + 1],
                                                                    r.delta_dot[i + 1], s, dt)};
    f << "bag,0," << g.in.mesh_phase << "," << p.k << "," << p.time << "," << p.x[0] << "," << p.x[1] << ","
      << p.on_grid << "\n";
    points.push_back(p);
  }
  const int limit = period_search_limit(b.config.gear, 16);
  const int period = detect_period(points, limit, {1e-3 * g.in.backlash, 1e-3 * std::sqrt(2 * b.config.load.initial_mean * g.in.backlash)});
  std::printf("# poincare of the bag: mesh period %.6g s (%s), transient %g s; %zu points, %s\n", Tm,
              on_step_grid(Tm, dt) ? "a whole number of recording periods: recorded states"
                                       : "interpolated between recorded states",
              transient, points.size(), period > 0 ? ("period " + std::to_string(period)).c_str() : ("no period <= " + std::to_string(limit)).c_str());
  return 0;
}


}  // namespace

std::unique_ptr<Subcommand> make_poincare() { return std::make_unique<Poincare>(); }

}  // namespace gear_dynamics::tools::analyze
