// gear_batch_bench: what the Monte Carlo batch costs without its bags (bench/batch prints the rest).
//   1. The engine as the batch drives it (run_batch: Ensemble blocks + the online observers, no
//      output) at 1 and 2 threads, and the bare Ensemble::step loop for comparison, on one workload.
//   2. With --default-batch: the whole default batch (config/*.yaml, config/monte_carlo.yaml)
//      stepped alone, i.e. with every observer and the recorder's state reads but nothing written.
#include <chrono>
#include <cstdio>
#include <iostream>
#include <string>

#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include "gear_dynamics/batch.hpp"

namespace gd = gear_dynamics;

namespace {

const char* kUsage = R"(usage: gear_batch_bench [--realizations R] [--duration T] [--block L] [--default-batch]
  --realizations R   stochastic realizations of the timed workload (default 256)
  --duration T       their simulated time [s] (default 0.05)
  --block L          lanes per block (default: monte_carlo.block_lanes)
  --default-batch    also step the whole default batch without writing (tens of seconds)
)";

// Reads states as the bag writer would, writes nothing.
class NullSink : public gd::BatchSink {
 public:
  void started(const std::vector<gd::RunSpec>&) override {}
  void recorded(const std::vector<gd::RunSpec>&, const gd::Ensemble& e, const Eigen::ArrayXd& d) override {
    checksum_ += e.delta()[0] + d[0];  // keeps the reads
  }
  void finished(const std::vector<gd::RunSpec>&, const std::vector<gd::RunResult>&) override {}
  void abandoned(const std::vector<gd::RunSpec>&) override {}
  double checksum_ = 0.0;
};

double seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

// run_batch over `runs`: wall seconds.
double time_batch(const gd::ModelConfig& model, const std::vector<gd::RunSpec>& runs, gd::BatchSettings s,
                  int threads) {
  s.threads = threads;
  NullSink sink;
  gd::BatchControl control;
  const auto start = std::chrono::steady_clock::now();
  gd::run_batch(model, runs, s, sink, control);
  return seconds_since(start);
}

// Bare Ensemble::step over the same blocks: wall seconds.
double time_bare(const gd::ModelConfig& model, const std::vector<gd::RunSpec>& runs, int lanes, int threads) {
  const auto blocks = gd::make_blocks(runs, lanes);
  const std::int64_t steps = model.run.steps();
  const auto start = std::chrono::steady_clock::now();
  tbb::task_arena arena(threads);
  arena.execute([&] {
    tbb::parallel_for(std::size_t{0}, blocks.size(), [&](std::size_t k) {
      std::vector<gd::LaneSpec> specs;
      for (const gd::RunSpec& r : blocks[k]) specs.push_back(gd::run_lane(model, r));
      gd::Ensemble e(gd::derive(model.gear), model.run.time_step, model.initial, specs, model.seed);
      for (std::int64_t n = 0; n < steps; ++n) e.step();
    });
  });
  return seconds_since(start);
}

}  // namespace

int main(int argc, char** argv) try {
  int realizations = 256, block = 0;
  double duration = 0.05;
  bool default_batch = false;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    const auto value = [&]() -> std::string {
      if (i + 1 >= argc) throw std::runtime_error("option " + a + " needs a value");
      return argv[++i];
    };
    if (a == "--realizations") realizations = std::stoi(value());
    else if (a == "--duration") duration = std::stod(value());
    else if (a == "--block") block = std::stoi(value());
    else if (a == "--default-batch") default_batch = true;
    else throw std::runtime_error(kUsage);
  }
  const std::string dir = GEAR_DYNAMICS_CONFIG_DIR;
  const YAML::Node defaults =
      gd::read_yaml_files({dir + "/gear_pair.yaml", dir + "/load.yaml", dir + "/run.yaml", dir + "/monte_carlo.yaml"});
  const gd::ModelConfig model = gd::parse_config(defaults);
  gd::BatchSettings settings = gd::parse_batch_settings(defaults["monte_carlo"], model);
  if (block > 0) settings.block_lanes = block;

  // The timed workload: R realizations at mu = 0.04 over `duration`, no series.
  YAML::Node small = YAML::Clone(defaults);
  small["run"]["duration"] = duration;
  small["run"]["window"] = duration / 2;
  small["run"]["snapshot_times"] = std::vector<double>{duration};
  const gd::ModelConfig short_model = gd::parse_config(small);
  gd::BatchSettings w = settings;
  w.mu = {0.04};
  w.realizations = static_cast<std::uint32_t>(realizations);
  w.phase_ensemble = false;
  w.record_realizations = 0;
  w.sparse_record_rate = 0.0;
  const auto runs = gd::plan_runs(short_model, w);
  const double work = static_cast<double>(runs.size()) * static_cast<double>(short_model.run.steps());
  std::printf("workload: %zu realizations x %lld steps (T = %g s, h = %g s), %d lanes per block\n", runs.size(),
              static_cast<long long>(short_model.run.steps()), duration, short_model.run.time_step, w.block_lanes);
  for (int threads : {1, 2}) {
    const double bare = time_bare(short_model, runs, w.block_lanes, threads);
    const double batch = time_batch(short_model, runs, w, threads);
    std::printf("  %d thread%s: Ensemble::step alone %.3g realization-steps/s; run_batch (with observers) %.3g "
                "realization-steps/s\n",
                threads, threads > 1 ? "s" : " ", work / bare, work / batch);
  }

  if (default_batch) {
    const auto plan = gd::plan_runs(model, settings);
    const double steps = static_cast<double>(plan.size()) * static_cast<double>(model.run.steps());
    const double wall = time_batch(model, plan, settings, gd::batch_threads(settings));
    std::printf("default batch, stepping alone: %zu runs, %.3g realization-steps in %.2f s wall on %d threads "
                "(%.3g realization-steps/s)\n",
                plan.size(), steps, wall, gd::batch_threads(settings), steps / wall);
  }
  return 0;
} catch (const std::exception& e) {
  std::fprintf(stderr, "gear_batch_bench: %s\n", e.what());
  return 1;
}
