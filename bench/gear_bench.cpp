// gear_bench: the C++ side of bench/run.
//   gear_bench params                 the model parameters (JSON) for the numpy and Octave versions
//   gear_bench engine --threads N ... times the package's engine (its batch runner) on the workload
//   gear_bench scalar ...             times the plain scalar loop (scalar_loop.hpp)
// Each timing run writes JSON: wall time, end states of the stochastic realizations, and a
// deterministic run (S1) sampled on a coarse grid for the pathwise cross-check.
#include <algorithm>
#include <chrono>
#include <ctime>
#include <cstdio>
#include <functional>
#include <iostream>
#include <string>
#include <vector>

#include "gear_dynamics/montecarlo/batch.hpp"
#include "gear_dynamics/config/config.hpp"
#include "gear_dynamics/engine/ensemble.hpp"
#include "cli.hpp"
#include "params_json.hpp"
#include "scalar_loop.hpp"

namespace gd = gear_dynamics;
using gear_bench::ScalarState;

namespace {

struct Options {
  std::string mode;
  int realizations = 64;
  double duration = 0.05, check_duration = 0.02, check_every = 0.001;
  int threads = 1, block = 32, repeat = 3;
  bool noise = true;
  std::string output = "-";
  std::vector<std::string> sets;
};

Options parse(int argc, char** argv) {
  Options o;
  CLI::App app("The C++ side of bench/run. The model is the package's default configuration (config/*.yaml).",
               "gear_bench");
  app.add_option("mode", o.mode,
                 "params: the model parameters (JSON) for the numpy and Octave versions; engine: times the "
                 "package's engine (its batch runner); scalar: times the plain scalar loop")
      ->required()->check(CLI::IsMember({"params", "engine", "scalar"}));
  app.add_option("--realizations", o.realizations, "stochastic realizations 0..R-1")
      ->type_name("R")->capture_default_str();
  app.add_option("--duration", o.duration, "simulated time [s]")->type_name("T")->capture_default_str();
  app.add_option("--check-duration", o.check_duration, "deterministic run S1 for the pathwise check [s]")
      ->type_name("T")->capture_default_str();
  app.add_option("--check-every", o.check_every, "its sampling interval [s]")->type_name("T")->capture_default_str();
  app.add_option("--threads", o.threads, "engine threads")->type_name("N")->capture_default_str();
  app.add_option("--block", o.block, "lanes per engine block")->type_name("L")->capture_default_str();
  app.add_option("--repeat", o.repeat, "timed repetitions; the JSON reports each")->type_name("K")
      ->capture_default_str();
  app.add_flag("!--no-noise", o.noise,
               "engine only: R copies of the deterministic run S1, lanes without random streams: the engine "
               "without the normal generation");
  app.add_option("--output", o.output, "JSON output ('-' = stdout)")->type_name("FILE")->capture_default_str();
  gd::tools::add_repeatable(app, "--set", o.sets,
                            "engine only: override one model parameter, e.g. --set gear_pair.mesh_stiffness="
                            "potential_energy (repeatable)")
      ->type_name("SEC.KEY=VAL");
  gd::tools::parse_or_exit(app, argc, argv);
  if (!o.sets.empty() && o.mode != "engine")
    throw std::runtime_error("--set is for the engine mode only (the numpy, Octave and scalar versions know the paper's model)");
  if (o.realizations < 1) throw std::runtime_error("--realizations must be >= 1");
  if (o.threads < 1 || o.block < 1 || o.repeat < 1)
    throw std::runtime_error("--threads, --block and --repeat must be >= 1");
  if (!(o.duration > 0) || !(o.check_duration > 0) || !(o.check_every > 0))
    throw std::runtime_error("--duration, --check-duration and --check-every must be > 0 s");
  return o;
}

gd::ModelConfig default_config(const std::vector<std::string>& sets = {}) {
  const std::string dir = GEAR_DYNAMICS_CONFIG_DIR;
  YAML::Node root = gd::read_yaml_files({dir + "/gear_pair.yaml", dir + "/load.yaml", dir + "/run.yaml"});
  for (const std::string& s : sets) gd::tools::apply_set(root, s);
  return gd::parse_config(root);
}

std::string json_array(const std::vector<double>& v) {
  std::string s = "[";
  char buf[32];
  for (std::size_t i = 0; i < v.size(); ++i) {
    std::snprintf(buf, sizeof buf, "%s%.17g", i ? ", " : "", v[i]);
    s += buf;
  }
  return s + "]";
}

void write(const std::string& path, const std::string& text) {
  if (path == "-") {
    std::cout << text;
    return;
  }
  FILE* f = std::fopen(path.c_str(), "w");
  if (!f || std::fputs(text.c_str(), f) < 0 || std::fclose(f) != 0)
    throw std::runtime_error("cannot write '" + path + "'");
}

// End states of the stochastic realizations and the S1 samples of one implementation.
struct Outcome {
  std::vector<double> delta, velocity;
  std::vector<double> check_delta, check_velocity;
};

// End states of the runs a batch finishes; slot = run id - first id.
class EndStates : public gd::BatchSink {
 public:
  EndStates(Outcome& out, std::size_t first_id) : out_(out), first_(first_id) {}
  void started(const std::vector<gd::RunSpec>&) override {}
  void recorded(const std::vector<gd::RunSpec>&, const gd::Ensemble&, const Eigen::ArrayXd&) override {}
  void finished(const std::vector<gd::RunSpec>& block, const std::vector<gd::RunResult>& results) override {
    for (std::size_t i = 0; i < block.size(); ++i) {  // blocks write disjoint slots
      out_.delta[block[i].id - first_] = results[i].final_delta;
      out_.velocity[block[i].id - first_] = results[i].final_delta_dot;
    }
  }
  void abandoned(const std::vector<gd::RunSpec>&) override {}

 private:
  Outcome& out_;
  std::size_t first_;
};

// The package's Monte Carlo runner (batch.hpp): realizations 0..R-1 at the configured mu in
// blocks of `block` lanes on `threads` threads, through simulate() with its observers, no series.
// --no-noise runs R copies of S1 instead: lanes without random streams.
void run_engine(const gd::ModelConfig& c, const Options& o, Outcome& out) {
  gd::ModelConfig model = c;
  model.run.duration = o.duration;
  model.run.window = std::min(model.run.window, o.duration);
  model.run.snapshot_times.clear();
  gd::BatchSettings s;
  s.mu.assign(o.noise ? 1 : o.realizations, c.friction_coefficient);
  s.realizations = o.noise ? o.realizations : 0;
  s.phase_ensemble = false;
  s.record_rate = s.sparse_record_rate = 0.0;
  s.record_realizations = 0;
  s.block_lanes = o.block;
  s.threads = o.threads;
  std::vector<gd::RunSpec> runs;
  for (const gd::RunSpec& r : gd::plan_runs(model, s))
    if ((r.kind == gd::RunKind::Stochastic) == o.noise) runs.push_back(r);
  out.delta.assign(runs.size(), 0.0);
  out.velocity.assign(runs.size(), 0.0);
  EndStates sink(out, runs.front().id);
  gd::BatchControl control;
  gd::run_batch(model, runs, s, sink, control);
}

void check_engine(const gd::ModelConfig& c, std::int64_t steps, std::int64_t every, Outcome& out) {
  gd::Ensemble e(gd::derive(c.gear), c.run.time_step, c.initial,
                 {gd::deterministic_lane(c, c.friction_coefficient)}, c.seed);
  for (std::int64_t n = 0; n <= steps; ++n) {
    if (n > 0) e.step();
    if (n % every == 0) {
      out.check_delta.push_back(e.delta()[0]);
      out.check_velocity.push_back(e.velocity()[0]);
    }
  }
}

void run_scalar(const gd::ModelConfig& c, const Options& o, std::int64_t steps, Outcome& out) {
  const gear_bench::ScalarModel model(gd::derive(c.gear), c.run.time_step);
  out.delta.clear();
  out.velocity.clear();
  for (int r = 0; r < o.realizations; ++r) {
    const ScalarState s = model.run(gd::stochastic_lane(c, c.friction_coefficient, r), c.seed,
                                    c.initial.deflection, c.initial.velocity, steps);
    out.delta.push_back(s.delta);
    out.velocity.push_back(s.velocity);
  }
}

void check_scalar(const gd::ModelConfig& c, std::int64_t steps, std::int64_t every, Outcome& out) {
  const gear_bench::ScalarModel model(gd::derive(c.gear), c.run.time_step);
  std::vector<ScalarState> samples;
  model.run(gd::deterministic_lane(c, c.friction_coefficient), c.seed, c.initial.deflection,
            c.initial.velocity, steps, every, &samples);
  for (const ScalarState& s : samples) {
    out.check_delta.push_back(s.delta);
    out.check_velocity.push_back(s.velocity);
  }
}

}  // namespace

int main(int argc, char** argv) try {
  const Options o = parse(argc, argv);
  const gd::ModelConfig c = default_config(o.sets);
  if (o.mode == "params") {
    write(o.output, gear_bench::params_json(c));
    return 0;
  }
  const std::int64_t steps = c.run.steps_for(o.duration);
  const std::int64_t check_steps = c.run.steps_for(o.check_duration);
  const std::int64_t every = std::max<std::int64_t>(1, c.run.steps_for(o.check_every));
  const bool engine = o.mode == "engine";

  Outcome out;
  std::vector<double> seconds, cpu_seconds;  // wall time, CPU time of all threads
  for (int k = 0; k < o.repeat; ++k) {
    const auto start = std::chrono::steady_clock::now();
    const std::clock_t cpu_start = std::clock();
    if (engine) run_engine(c, o, out);
    else run_scalar(c, o, steps, out);
    cpu_seconds.push_back(static_cast<double>(std::clock() - cpu_start) / CLOCKS_PER_SEC);
    seconds.push_back(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
  }
  if (engine) check_engine(c, check_steps, every, out);
  else check_scalar(c, check_steps, every, out);

  char head[256];
  std::snprintf(head, sizeof head,
                "{\n\"realizations\": %d,\n\"steps\": %lld,\n\"threads\": %d,\n\"check_every\": %lld,\n",
                o.realizations, static_cast<long long>(steps), engine ? o.threads : 1,
                static_cast<long long>(every));
  write(o.output, head + ("\"seconds\": " + json_array(seconds) +
                          ",\n\"cpu_seconds\": " + json_array(cpu_seconds) +
                          ",\n\"delta\": " + json_array(out.delta) +
                          ",\n\"velocity\": " + json_array(out.velocity) +
                          ",\n\"check_delta\": " + json_array(out.check_delta) +
                          ",\n\"check_velocity\": " + json_array(out.check_velocity) + "\n}\n"));
  return 0;
} catch (const std::exception& e) {
  std::fprintf(stderr, "gear_bench: %s\n", e.what());
  return 1;
}
