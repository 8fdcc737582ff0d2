#include "gear_dynamics/batch.hpp"

#include <tbb/info.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <exception>
#include <map>
#include <mutex>
#include <set>
#include <sstream>
#include <tuple>

namespace gear_dynamics {

namespace {

// Reads the keys of one section, collecting a message per problem (key, value, allowed range).
class SectionReader {
 public:
  SectionReader(const YAML::Node& node, std::string section, std::vector<std::string>& errors)
      : node_(node), section_(std::move(section)), errors_(errors) {}

  double number(const char* key, double lo, double hi, bool integer, const char* unit) {
    const YAML::Node v = get(key);
    double x = lo;
    if (!v) return x;
    std::ostringstream range;
    range.precision(12);
    range << "[" << lo << ", " << hi << "]" << (integer ? " (integer)" : "") << " " << unit;
    if (!detail::as_number(v, x)) {
      error(key) << " = " << detail::show(v) << " has the wrong type: expected a number in " << range.str();
    } else if (!std::isfinite(x) || x < lo || x > hi || (integer && x != std::floor(x))) {
      error(key) << " = " << x << " is out of range; allowed " << range.str();
    } else {
      return x;
    }
    return lo;
  }

  bool boolean(const char* key) {
    const YAML::Node v = get(key);
    if (!v) return false;
    if (v.IsScalar()) {
      const std::string& s = v.Scalar();
      if (s == "true" || s == "True") return true;
      if (s == "false" || s == "False") return false;
    }
    error(key) << " = " << detail::show(v) << " has the wrong type: expected true or false";
    return false;
  }

  std::string text(const char* key) {
    const YAML::Node v = get(key);
    if (v && v.IsScalar() && !v.Scalar().empty()) return v.Scalar();
    if (v) error(key) << " = " << detail::show(v) << " is not allowed: expected a non-empty path";
    return "";
  }

  std::vector<double> numbers(const char* key, double lo, double hi, const char* unit) {
    const YAML::Node v = get(key);
    std::vector<double> out;
    if (!v) return out;
    if (!v.IsSequence() || v.size() == 0) {
      error(key) << " = " << detail::show(v) << " is not allowed: expected a non-empty list of numbers in ["
                 << lo << ", " << hi << "] " << unit;
      return out;
    }
    for (std::size_t i = 0; i < v.size(); ++i) {
      double x;
      if (!detail::as_number(v[i], x) || !std::isfinite(x) || x < lo || x > hi) {
        error(key) << "[" << i << "] = " << detail::show(v[i]) << " is out of range; allowed [" << lo
                   << ", " << hi << "] " << unit;
      } else {
        out.push_back(x);
      }
    }
    return out;
  }

  // A message about `key`; flushed into the list when the next one starts or on finish().
  std::ostringstream& error(const std::string& key) {
    flush();
    pending_.precision(12);
    pending_ << section_ << "." << key;
    return pending_;
  }

  // Unknown keys are typos: refuse them, naming the valid ones.
  void finish() {
    flush();
    for (const auto& kv : node_) {
      const std::string key = kv.first.as<std::string>();
      if (seen_.count(key)) continue;
      std::string valid;
      for (const std::string& k : seen_) valid += (valid.empty() ? "" : ", ") + k;
      errors_.push_back(section_ + "." + key + " is not a known key (a typo?); valid keys: " + valid);
    }
  }

 private:
  YAML::Node get(const char* key) {
    seen_.insert(key);
    const YAML::Node v = node_[key];
    if (!v || v.IsNull()) {
      error(key) << " is missing";
      return YAML::Node();
    }
    return v;
  }

  void flush() {
    if (!pending_.str().empty()) errors_.push_back(pending_.str());
    pending_.str("");
  }

  const YAML::Node& node_;
  std::string section_;
  std::vector<std::string>& errors_;
  std::set<std::string> seen_;
  std::ostringstream pending_;
};

// Grid steps between recorded states at `rate` [Hz]; `rate` must give a whole number of steps
// that divides the run, so the series ends at T.
std::int64_t record_interval(SectionReader& in, const char* key, double rate, const ModelConfig& model) {
  if (rate <= 0.0) return 0;
  const double h = model.run.time_step, k = 1.0 / (rate * h);
  const std::int64_t every = std::llround(k), total = model.run.steps();
  if (every >= 1 && std::abs(k - static_cast<double>(every)) <= 1e-9 * k && total % every == 0)
    return every;
  in.error(key) << " = " << rate << " Hz does not fit the grid: 1 / (rate x run.time_step) = " << k
                << " steps, which must be a whole number >= 1 that divides the run's "
                << total << " steps (e.g. " << 1.0 / h << ", " << 0.1 / h << " or " << 0.001 / h << " Hz)";
  return 0;
}

std::string run_name(double mu, const std::string& kind, std::uint32_t index) {
  char buf[64];
  if (kind == kKindS1) std::snprintf(buf, sizeof buf, "mu%.4f_S1", mu);
  else if (kind == kKindPhase) std::snprintf(buf, sizeof buf, "mu%.4f_phase%02u", mu, index);
  else std::snprintf(buf, sizeof buf, "mu%.4f_r%05u", mu, index);
  return buf;
}

}  // namespace

BatchSettings parse_batch_settings(const YAML::Node& section, const ModelConfig& model) {
  if (!section || !section.IsMap())
    throw ConfigError("invalid configuration: missing section 'monte_carlo' (a map of the batch settings)");
  std::vector<std::string> errors;
  SectionReader in(section, "monte_carlo", errors);
  BatchSettings s;
  s.mu = in.numbers("mu", 0.0, kMaxFrictionCoefficient, "-");
  std::set<std::string> names;
  for (double mu : s.mu) {
    if (!names.insert(run_name(mu, kKindS1, 0)).second)
      in.error("mu") << " = " << detail::show(section["mu"]) << " repeats " << mu
                     << " (values must differ in the 4th decimal, which names the runs)";
  }
  s.realizations = static_cast<std::uint32_t>(in.number("realizations", 1, 1e6, true, "-"));
  s.phase_ensemble = in.boolean("phase_ensemble");
  s.record_rate = in.number("record_rate", 0, 1e9, false, "Hz");
  if (s.record_rate == 0.0) in.error("record_rate") << " = 0 Hz is out of range; allowed (0, 1 / run.time_step] Hz";
  s.record_realizations = static_cast<std::uint32_t>(in.number("record_realizations", 0, s.realizations, true, "-"));
  s.sparse_record_rate = in.number("sparse_record_rate", 0, 1e9, false, "Hz (0 = no series)");
  record_interval(in, "record_rate", s.record_rate, model);
  record_interval(in, "sparse_record_rate", s.sparse_record_rate, model);
  s.output_dir = in.text("output_dir");
  s.overwrite = in.boolean("overwrite");
  s.shard_count = static_cast<int>(in.number("shard_count", 1, 1e6, true, "-"));
  s.shard_index = static_cast<int>(in.number("shard_index", 0, s.shard_count - 1, true, "- (below shard_count)"));
  s.block_lanes = static_cast<int>(in.number("block_lanes", 1, 4096, true, "lanes"));
  s.threads = static_cast<int>(in.number("threads", 0, 1024, true, "threads (0 = all cores)"));
  in.finish();
  detail::throw_if_errors(errors);
  return s;
}

YAML::Node content_yaml(const BatchSettings& s) {
  YAML::Node n;
  for (double mu : s.mu) n["mu"].push_back(mu);
  n["mu"].SetStyle(YAML::EmitterStyle::Flow);
  n["realizations"] = s.realizations;
  n["phase_ensemble"] = s.phase_ensemble;
  n["record_rate"] = s.record_rate;
  n["record_realizations"] = s.record_realizations;
  n["sparse_record_rate"] = s.sparse_record_rate;
  return n;
}

std::vector<RunSpec> plan_runs(const ModelConfig& model, const BatchSettings& s) {
  const double h = model.run.time_step;
  const auto every = [h](double rate) { return rate > 0.0 ? std::llround(1.0 / (rate * h)) : 0; };
  const double phase_step = derive(model.gear).mesh_period_angle / kPhaseEnsembleSize;
  std::vector<RunSpec> runs;
  const auto add = [&](double mu, const char* kind, std::uint32_t index, double phase, double rate) {
    RunSpec r;
    r.id = runs.size();
    r.name = run_name(mu, kind, index);
    r.kind = kind;
    r.mu = mu;
    r.index = index;
    r.mesh_phase = phase;
    r.record_every = every(rate);
    runs.push_back(std::move(r));
  };
  for (double mu : s.mu) {
    add(mu, kKindS1, 0, model.gear.mesh_phase, s.record_rate);
    if (s.phase_ensemble) {
      for (int j = 0; j < kPhaseEnsembleSize; ++j)
        add(mu, kKindPhase, static_cast<std::uint32_t>(j), j * phase_step, s.sparse_record_rate);
    }
    for (std::uint32_t r = 0; r < s.realizations; ++r)
      add(mu, kKindStochastic, r, model.gear.mesh_phase,
          r < s.record_realizations ? s.record_rate : s.sparse_record_rate);
  }
  return runs;
}

std::vector<RunSpec> shard_runs(const std::vector<RunSpec>& runs, int index, int count) {
  std::vector<RunSpec> out;
  for (std::size_t i = static_cast<std::size_t>(index); i < runs.size(); i += static_cast<std::size_t>(count))
    out.push_back(runs[i]);
  return out;
}

ModelConfig run_config(const ModelConfig& model, const RunSpec& run) {
  ModelConfig c = model;
  c.friction_coefficient = run.mu;
  c.gear.mesh_phase = run.mesh_phase;
  return c;
}

LaneSpec run_lane(const ModelConfig& model, const RunSpec& run) {
  if (run.kind == kKindStochastic) return stochastic_lane(model, run.mu, run.index);
  return deterministic_lane(model, run.mu);
}

std::vector<std::vector<RunSpec>> make_blocks(const std::vector<RunSpec>& runs, int lanes) {
  // Lanes of one Ensemble share its mesh schedule (phi0) and one Recorder (record interval).
  std::map<std::tuple<double, std::int64_t>, std::vector<RunSpec>> groups;
  std::vector<std::vector<RunSpec>> blocks;
  for (const RunSpec& r : runs) {
    std::vector<RunSpec>& g = groups[{r.mesh_phase, r.record_every}];
    g.push_back(r);
    if (static_cast<int>(g.size()) == lanes) blocks.push_back(std::move(g)), g.clear();
  }
  for (auto& kv : groups)
    if (!kv.second.empty()) blocks.push_back(std::move(kv.second));
  return blocks;
}

int batch_threads(const BatchSettings& settings) {
  return settings.threads > 0 ? settings.threads : tbb::info::default_concurrency();
}

void run_batch(const ModelConfig& model, const std::vector<RunSpec>& runs,
               const BatchSettings& settings, BatchSink& sink, BatchControl& control) {
  struct Abandon {};  // thrown out of simulate() by the recorder once stop is set
  // Densely recorded blocks first: their bags take the writer longest, so it starts on them while
  // the other blocks are stepped.
  std::vector<std::vector<RunSpec>> blocks = make_blocks(runs, settings.block_lanes);
  const auto density = [](const std::vector<RunSpec>& b) {
    return b.front().record_every > 0 ? 1.0 / static_cast<double>(b.front().record_every) : 0.0;
  };
  std::stable_sort(blocks.begin(), blocks.end(),
                   [&](const auto& a, const auto& b) { return density(a) > density(b); });
  const std::int64_t total = model.run.steps();
  std::exception_ptr error;
  std::mutex error_mutex;

  const auto run_block = [&](const std::vector<RunSpec>& block) {
    if (control.stop) return;
    const auto width = static_cast<std::int64_t>(block.size());
    Recorder recorder;
    recorder.every = block.front().record_every;
    recorder.record = [&](const Ensemble& e, const Eigen::ArrayXd& d) {
      if (control.stop) throw Abandon{};
      sink.recorded(block, e, d);
      if (e.step_index() > 0) control.realization_steps += width * recorder.every;
    };
    try {
      GearInputs gear = model.gear;
      gear.mesh_phase = block.front().mesh_phase;
      std::vector<LaneSpec> lanes;
      for (const RunSpec& r : block) lanes.push_back(run_lane(model, r));
      Ensemble ensemble(derive(gear), model.run.time_step, model.initial, std::move(lanes), model.seed);
      sink.started(block);
      const std::vector<RunResult> results = simulate(ensemble, model.run, recorder);
      if (recorder.every == 0) control.realization_steps += width * total;
      sink.finished(block, results);
    } catch (const Abandon&) {
      sink.abandoned(block);
    } catch (...) {
      sink.abandoned(block);
      std::lock_guard<std::mutex> lock(error_mutex);
      if (!error) error = std::current_exception();
      control.stop = true;
    }
  };

  // Every thread takes the next block in that order.
  const int threads = batch_threads(settings);
  std::atomic<std::size_t> next{0};
  tbb::task_arena arena(threads);
  arena.execute([&] {
    tbb::parallel_for(0, threads, [&](int) {
      for (std::size_t i = next++; i < blocks.size(); i = next++) run_block(blocks[i]);
    });
  });
  if (error) std::rethrow_exception(error);
}

}  // namespace gear_dynamics
