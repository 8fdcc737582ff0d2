// gear_analyze poincare: (delta, delta_dot) once per mesh period at mesh phase 0, of S1, the phase
// ensemble and stochastic realizations (or of a bag's run), and S1's period; with --signal, an
// output of the model at the same points. For the bearings model the whole ten-component state is
// sampled (each displacement Hermite-interpolated with its rate): (delta, delta_dot) are the mesh
// deflection delta_m and its rate, and S1's period is tested on the whole state.
#include <tbb/parallel_for.h>

#include <cmath>
#include <cstdio>

#include "common.hpp"
#include "gear_dynamics/dynamics/bifurcation.hpp"
#include "gear_dynamics/dynamics/poincare.hpp"
#include "gear_dynamics/engine/bearings.hpp"
#include "gear_dynamics/engine/ensemble.hpp"

namespace gear_dynamics::tools::analyze {
namespace {

// One point of a set as written: the mesh deflection, its rate and the --signal's value.
struct SectionRow {
  double delta, delta_dot, signal;
};

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
    app.add_option("--signal", signal_,
                   "an output also written at each point (a column of that name): mesh_force, or with "
                   "gear_pair.model = bearings any output of gear_run's CSV (delta_t, pinion_fx, pinion_fy, "
                   "wheel_fx, wheel_fy)")
        ->type_name("NAME");
    add_bag_option(app, bag_);
  }
  int run(const Common& c) override { return bag_.empty() ? simulate(c) : from_bag(c); }

 private:
  // A section's points as rows: the state's (delta, delta_dot) and the signal at each point's time.
  std::vector<SectionRow> rows(const std::vector<SectionState>& points, const GearPair& gear,
                               const MeshSchedule& mesh, const BearingsModel* bearings) const;
  int simulate(const Common& c) const;
  int from_bag(const Common& c) const;

  std::optional<double> duration_;
  int phases_ = 64;
  int realizations_ = 0;
  double transient_ = 0.2;
  std::string signal_;
  std::string bag_;
};

// The schedule's K, e and e_dot at the point's time: at a stiffness switch, the value after it
// (the schedule's value at t), the same in every period.
std::vector<SectionRow> Poincare::rows(const std::vector<SectionState>& points, const GearPair& gear,
                                       const MeshSchedule& mesh, const BearingsModel* bearings) const {
  const BearingsOutputSpec* output = signal_.empty() ? nullptr : signal_output(signal_, gear.in.model);
  std::vector<SectionRow> out;
  out.reserve(points.size());
  for (const SectionState& p : points) {
    const model_step::MeshPoint m = output_mesh_point(mesh, p.time);
    if (bearings) {
      const BearingsModel::State y = Eigen::Map<const BearingsModel::State>(p.x.data());
      const BearingsOutputs o = bearings_outputs(*bearings, gear, m, y);
      out.push_back({o.delta_m, o.delta_m_dot, output ? o.*output->value : o.mesh_force});
    } else {
      out.push_back({p.x[0], p.x[1], signal_.empty() ? 0.0
                                                      : mesh_force(gear, m.stiffness, p.x[0], p.x[1], m.error,
                                                                   m.error_rate)});
    }
  }
  return out;
}

int Poincare::simulate(const Common& c) const {
  const ModelConfig cfg = load_config(c, duration_);
  if (!signal_.empty()) signal_output(signal_, cfg.gear.model);  // refuses a bad --signal before anything runs
  const bool bearings = cfg.gear.model == GearModel::kBearings;
  const GearPair g = derive(cfg.gear);
  const int P = phases_, R = realizations_;
  const double transient = transient_, h = cfg.run.time_step, Tm = mesh_period(g);
  const auto t0 = std::chrono::steady_clock::now();
  // Phase ensemble (member 0 = S1 when phi0 = 0), one system per phase, sampled at mesh phase 0,
  // i.e. at t = (phi_n - phi0)/Omega mod T_m + k T_m (interpolated unless on the grid): GearLanes,
  // or for the bearings model the engine's lanes with their whole state.
  std::vector<std::vector<SectionState>> ph(P);
  std::vector<std::vector<SectionRow>> ph_rows(P);
  tbb::parallel_for(0, P, [&](int j) {
    GearInputs gi = cfg.gear;
    gi.mesh_phase = j * g.mesh_period_angle / P;
    const double offset = first_mesh_period_start(derive(gi));  // as the batch's /gear/poincare
    const PoincareOptions section{Tm, offset, transient, cfg.run.duration, {}};
    if (bearings) {
      Ensemble e(derive(gi), h, cfg.initial, {deterministic_lane(cfg, cfg.friction_coefficient)}, cfg.seed);
      BearingsLanes sys(e);
      ph[j] = poincare_section(sys, section);
      ph_rows[j] = rows(ph[j], e.gear(), e.mesh(), e.bearings_model());
    } else {
      GearLanes sys({GearLaneSpec{gi, cfg.friction_coefficient, cfg.load.initial_mean, cfg.initial}}, h);
      ph[j] = poincare_section(sys, section);
      ph_rows[j] = rows(ph[j], sys.gear(0), sys.mesh(0), nullptr);
    }
  });
  std::vector<SectionState> st;
  std::vector<SectionRow> st_rows;
  if (R > 0) {
    std::vector<LaneSpec> lanes;
    for (int r = 0; r < R; ++r) lanes.push_back(stochastic_lane(cfg, cfg.friction_coefficient, r));
    Ensemble e(g, h, cfg.initial, lanes, cfg.seed);
    const PoincareOptions section{Tm, 0.0, transient, cfg.run.duration, {}};
    if (bearings) {
      BearingsLanes sys(e);
      st = poincare_section(sys, section);
    } else {
      EnsembleLanes sys(e);
      st = poincare_section(sys, section);
    }
    st_rows = rows(st, e.gear(), e.mesh(), e.bearings_model());
  }
  const auto f_file = open_csv(c, "poincare");
  std::ostream& f = f_file->out();
  f << "set,run,phase0,k,t,delta,delta_dot," << (signal_.empty() ? "" : signal_ + ",") << "on_grid\n";
  const auto write = [&](const std::string& set, const std::string& run, double phase0, const SectionState& p,
                         const SectionRow& r) {
    f << set << "," << run << "," << phase0 << "," << p.k << "," << p.time << "," << r.delta << "," << r.delta_dot
      << ",";
    if (!signal_.empty()) f << r.signal << ",";
    f << p.on_grid << "\n";
  };
  for (int j = 0; j < P; ++j)
    for (std::size_t i = 0; i < ph[j].size(); ++i)
      write(j == 0 ? "S1" : "phase", std::to_string(j), j * g.mesh_period_angle / P, ph[j][i], ph_rows[j][i]);
  for (std::size_t i = 0; i < st.size(); ++i) write("stochastic", "r" + std::to_string(st[i].lane), 0.0, st[i], st_rows[i]);
  std::printf("# poincare: mesh period %.6g s (%s), transient %g s, T %g s, %d phases, %d realizations, %.1f s wall\n",
              Tm, on_step_grid(Tm, h) ? "a whole number of steps: grid states" : "interpolated", transient,
              cfg.run.duration, P, R, seconds_since(t0));
  // Every displacement within 1e-3 b, every rate within 1e-3 of the speed a free fall across the
  // backlash reaches: the whole state, ten components for the bearings model.
  const double vref = std::sqrt(2 * cfg.load.initial_mean * g.in.backlash);
  std::vector<double> tolerance;
  for (std::size_t k = 0; k < (ph[0].empty() ? 2 : ph[0][0].x.size()); ++k)
    tolerance.push_back(1e-3 * (k % 2 == 0 ? g.in.backlash : vref));
  const int limit = period_search_limit(cfg.gear, 16);
  const int period = detect_period(ph[0], limit, tolerance);
  std::printf("S1: %zu points, %s%s\n", ph[0].size(),
              period > 0 ? ("period " + std::to_string(period)).c_str()
                         : ("no period <= " + std::to_string(limit) + " (aperiodic)").c_str(),
              bearings ? " (of the whole state)" : "");
  return 0;
}

int Poincare::from_bag(const Common& c) const {
  if (!signal_.empty())
    throw std::runtime_error("--signal " + signal_ + " with --bag: a bag's run gives delta and delta_dot only; "
                             "give --signal without --bag (a simulation)");
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
