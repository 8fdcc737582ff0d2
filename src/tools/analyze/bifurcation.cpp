// gear_analyze bifurcation: Poincare points of deterministic runs along one parameter, each value's
// period and regime.
#include <cstdio>

#include "common.hpp"
#include "gear_dynamics/dynamics/bifurcation.hpp"

namespace gear_dynamics::tools::analyze {
namespace {

class Bifurcation : public Subcommand {
 public:
  std::string name() const override { return "bifurcation"; }
  std::string description() const override { return "Poincare points of deterministic runs vs one parameter"; }
  void add_options(CLI::App& app) override {
    add_parameter_options(app, range_);
    range_.from_option->required();
    range_.to_option->required();
    app.add_option("--duration", duration_, "simulated time of each value [s]")->type_name("S")->check(positive())
        ->capture_default_str();
    app.add_option("--transient", transient_, "start-up dropped [s]")->type_name("S")->check(in_range(0))
        ->capture_default_str();
  }
  int run(const Common& c) override;

 private:
  ParameterRange range_;
  double duration_ = 2.0;
  double transient_ = 1.0;
};

int Bifurcation::run(const Common& c) {
  const ModelConfig cfg = load_config(c);
  const ScanParameter p = parse_scan_parameter(range_.parameter);
  const std::vector<double> values = parameter_values(range_);
  ScanOptions so;
  so.duration = duration_;
  so.transient = transient_;
  const auto t0 = std::chrono::steady_clock::now();
  const auto r = bifurcation_scan(cfg, p, values, so);
  const double wall = seconds_since(t0);
  const auto f_file = open_csv(c, "bifurcation");
  std::ostream& f = f_file->out();
  f << "value,k,t,delta,delta_dot\n";
  for (const auto& v : r)
    for (const auto& q : v.points) f << v.value << "," << q.k << "," << q.time << "," << q.x[0] << "," << q.x[1] << "\n";
  const auto s_file = open_csv(c, "bifurcation_summary");
  std::ostream& s = s_file->out();
  s << "parameter,value,period,regime,min_gap,min_delta,points\n";
  for (const auto& v : r) {
    s << scan_parameter_name(p) << "," << v.value << "," << v.period << ",\"" << v.regime << "\"," << v.min_gap << ","
      << v.min_delta << "," << v.points.size() << "\n";
  }
  std::printf("# bifurcation over %s: %zu values %g..%g%s, %g s each (transient %g s), mu %g, %.1f s wall\n",
              scan_parameter_name(p).c_str(), values.size(), values.front(), values.back(), range_.log ? " (log)" : "",
              so.duration, so.transient, cfg.friction_coefficient, wall);
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

}  // namespace

std::unique_ptr<Subcommand> make_bifurcation() { return std::make_unique<Bifurcation>(); }

}  // namespace gear_dynamics::tools::analyze
