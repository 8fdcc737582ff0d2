// gear_batch_bench: the default Monte Carlo batch (config/*.yaml, config/monte_carlo.yaml) stepped
// alone: run_batch with every observer and the recorder's reads of the states, but nothing written.
// bench/batch puts it beside the same batch written to bags by gear_monte_carlo.
#include <chrono>
#include <cstdio>

#include "gear_dynamics/montecarlo/batch.hpp"

namespace gd = gear_dynamics;

namespace {

// Reads what the bag writer would read, writes nothing.
class NullSink : public gd::BatchSink {
 public:
  void started(const std::vector<gd::RunSpec>&) override {}
  void recorded(const std::vector<gd::RunSpec>&, const gd::Ensemble& e, const Eigen::ArrayXd& d) override {
    for (int i = 0; i < e.lanes(); ++i) checksum += e.delta()[i] + e.velocity()[i] + e.load()[i] + d[i];
  }
  void finished(const std::vector<gd::RunSpec>&, const std::vector<gd::RunResult>&) override {}
  void abandoned(const std::vector<gd::RunSpec>&) override {}
  double checksum = 0.0;
};

}  // namespace

int main() try {
  const std::string dir = GEAR_DYNAMICS_CONFIG_DIR;
  const YAML::Node defaults =
      gd::read_yaml_files({dir + "/gear_pair.yaml", dir + "/load.yaml", dir + "/run.yaml", dir + "/monte_carlo.yaml"});
  const gd::ModelConfig model = gd::parse_config(defaults);
  const gd::BatchSettings settings = gd::parse_batch_settings(defaults["monte_carlo"], model);
  const auto runs = gd::plan_runs(model, settings);
  const double steps = static_cast<double>(runs.size()) * static_cast<double>(model.run.steps());

  NullSink sink;
  gd::BatchControl control;
  const auto start = std::chrono::steady_clock::now();
  gd::run_batch(model, runs, settings, sink, control);
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  std::printf("default batch stepped alone (no bags): %zu runs, %.3g realization-steps in %.2f s wall on %d "
              "threads, %d lanes per block (%.3g realization-steps/s), h = %g s\n",
              runs.size(), steps, wall, gd::batch_threads(settings), settings.block_lanes, steps / wall,
              model.run.time_step);
  return sink.checksum == sink.checksum ? 0 : 1;  // NaN would mean a broken run
} catch (const std::exception& e) {
  std::fprintf(stderr, "gear_batch_bench: %s\n", e.what());
  return 1;
}
