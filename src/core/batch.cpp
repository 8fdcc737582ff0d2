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
#include <tuple>

#include "gear_dynamics/section_reader.hpp"

namespace gear_dynamics {

namespace {

// Grid steps between recorded states at `rate` [Hz]; `rate` must give a whole number of steps
// that divides the run, so the series ends at T.
std::int64_t record_interval(SectionReader& in, const char* key, double rate, const ModelConfig& model) {
  if (rate <= 0.0) return 0;
  const double h = model.run.time_step, k = 1.0 / (rate * h);
  const std::int64_t every = std::llround(k), total = model.run.steps();
  if (every >= 1 && std::abs(k - static_cast<double>(every)) <= 1e-9 * k && total % every == 0)
    return every;
  in.error(key, " = " + SectionReader::text_of(rate) + " Hz does not fit the grid: 1 / (rate x run.time_step) = " +
                    SectionReader::text_of(k) + " steps, which must be a whole number >= 1 that divides the run's " +
                    std::to_string(total) + " steps (e.g. " + SectionReader::text_of(1.0 / h) + ", " +
                    SectionReader::text_of(0.1 / h) + " or " + SectionReader::text_of(0.001 / h) + " Hz)");
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
  // A key that is missing or bad keeps its default below; the checks that depend on it are left
  // out, so each problem is reported once.
  if (const auto mu = in.numbers("mu", 0.0, kMaxFrictionCoefficient, "-")) {
    s.mu = *mu;
    std::set<std::string> names;
    for (double m : s.mu)
      if (!names.insert(run_name(m, kKindS1, 0)).second)
        in.error("mu", " = " + detail::show(section["mu"]) + " repeats " + SectionReader::text_of(m) +
                           " (values must differ in the 4th decimal, which names the runs)");
  }
  const auto realizations = in.number("realizations", 1, 1e6, true, "-");
  if (realizations) s.realizations = static_cast<std::uint32_t>(*realizations);
  if (const auto v = in.flag("phase_ensemble")) s.phase_ensemble = *v;
  // record_interval checks that a rate fits the grid (at most one state per step).
  if (const auto v = in.number("record_rate", 0, 1e9, false, "Hz", /*open_lo=*/true)) {
    s.record_rate = *v;
    record_interval(in, "record_rate", s.record_rate, model);
  }
  if (const auto v = in.number("record_realizations", 0, realizations ? *realizations : 1e6, true, "-"))
    s.record_realizations = static_cast<std::uint32_t>(*v);
  if (const auto v = in.number("sparse_record_rate", 0, 1e9, false, "Hz (0 = no series)")) {
    s.sparse_record_rate = *v;
    record_interval(in, "sparse_record_rate", s.sparse_record_rate, model);
  }
  if (const auto v = in.text("output_dir")) s.output_dir = *v;
  if (const auto v = in.flag("overwrite")) s.overwrite = *v;
  const auto shard_count = in.number("shard_count", 1, 1e6, true, "-");
  if (shard_count) s.shard_count = static_cast<int>(*shard_count);
  if (const auto v = in.number("shard_index", 0, shard_count ? *shard_count - 1 : 1e6, true, "- (below shard_count)"))
    s.shard_index = static_cast<int>(*v);
  if (const auto v = in.number("block_lanes", 1, 4096, true, "lanes")) s.block_lanes = static_cast<int>(*v);
  if (const auto v = in.number("threads", 0, 1024, true, "threads (0 = all cores)")) s.threads = static_cast<int>(*v);
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
