// gear_analyze stiffness: the mesh stiffness over one pinion revolution, its levels and jumps.
#include <algorithm>
#include <cmath>
#include <cstdio>

#include "common.hpp"
#include "gear_dynamics/model/mesh_schedule.hpp"

namespace gear_dynamics::tools::analyze {
namespace {

class Stiffness : public Subcommand {
 public:
  std::string name() const override { return "stiffness"; }
  std::string description() const override {
    return "the mesh stiffness K over one pinion revolution from theta1 = 0 (PREFIX_stiffness.csv: "
           "angle[rad],stiffness[N/m]), its levels and jumps";
  }
  void add_options(CLI::App& app) override {
    app.add_option("--points", points_, "points per mesh period")->type_name("N")->check(in_range(8))
        ->capture_default_str();
  }
  int run(const Common& c) override;

 private:
  int points_ = 512;
};

int Stiffness::run(const Common& c) {
  const ModelConfig cfg = load_config(c);
  GearInputs in = cfg.gear;
  in.mesh_phase = 0.0;  // angles from the model's theta1 = 0
  const GearPair g = derive(in);
  const MeshSchedule mesh(g, cfg.run.time_step);
  const int per = points_;
  const long N = static_cast<long>(per) * g.in.pinion_teeth;
  const auto f_file = open_csv(c, "stiffness");
  std::ostream& f = f_file->out();
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
              g.in.mesh_stiffness == MeshStiffnessModel::kSquareWave ? "square_wave" : "potential_energy",
              g.in.pinion_teeth, per, g.contact_ratio, g.single_pair_angle, g.mesh_period_angle);
  std::printf("K: mean %.6g N/m, min %.6g, max %.6g; ISO 6336 square wave k1 = %.6g, k2 = %.6g, mean %.6g\n", sum / N,
              lo, hi, g.k1, g.k2, g.k_mean);
  if (const MeshTable* t = mesh.table()) {
    std::printf("schedule: %d mesh periods, %d pieces, %d nodes; jumps in the first mesh period at", t->mesh_periods(),
                t->pieces(), t->nodes());
    for (double b : t->breaks())
      if (b > 0.0 && b < g.mesh_period_angle) std::printf(" %.6g", b);
    std::printf(" rad\n");
  }
  return 0;
}

}  // namespace

std::unique_ptr<Subcommand> make_stiffness() { return std::make_unique<Stiffness>(); }

}  // namespace gear_dynamics::tools::analyze
