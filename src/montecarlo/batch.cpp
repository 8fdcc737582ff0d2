#include "gear_dynamics/montecarlo/batch.hpp"

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


namespace gear_dynamics {

namespace {

std::string run_name(const Study& study, std::size_t point, double mu, RunKind kind, std::uint32_t index) {
  char prefix[16] = "";
  if (study.swept()) std::snprintf(prefix, sizeof prefix, "p%04zu_", point);
  if (kind == RunKind::S1) return prefix + s1_run_label(mu);
  if (kind == RunKind::Phase) return prefix + phase_run_label(mu, index);
  return prefix + realization_run_label(mu, index);
}

}  // namespace

Study make_study(const ModelConfig& model, const BatchSettings& settings) {
  return make_study(model, settings.mu, settings.sweep);
}

std::vector<RunSpec> plan_runs(const Study& study, const BatchSettings& s) {
  std::vector<RunSpec> runs;
  for (const StudyPoint& point : study.points) {
    const ModelConfig& model = point.config;
    const double h = model.run.time_step;
    const auto every = [h](double rate) { return rate > 0.0 ? std::llround(1.0 / (rate * h)) : 0; };
    const double phase_step = derive(model.gear).mesh_period_angle / kPhaseEnsembleSize;
    const double mu = model.friction_coefficient;
    const auto add = [&](RunKind kind, std::uint32_t index, double phase, double rate) {
      RunSpec r;
      r.id = runs.size();
      r.name = run_name(study, point.index, mu, kind, index);
      r.kind = kind;
      r.mu = mu;
      r.index = index;
      r.mesh_phase = phase;
      r.record_every = every(rate);
      r.point = point.index;
      r.schedule = point.schedule;
      runs.push_back(std::move(r));
    };
    add(RunKind::S1, 0, model.gear.mesh_phase, s.record_rate);
    if (s.phase_ensemble) {
      for (int j = 0; j < kPhaseEnsembleSize; ++j)
        add(RunKind::Phase, static_cast<std::uint32_t>(j), j * phase_step, s.sparse_record_rate);
    }
    for (std::uint32_t r = 0; r < s.realizations; ++r)
      add(RunKind::Stochastic, r, model.gear.mesh_phase, r < s.record_realizations ? s.record_rate : s.sparse_record_rate);
  }
  return runs;
}

std::vector<RunSpec> plan_runs(const ModelConfig& model, const BatchSettings& s) {
  return plan_runs(make_study(model, s), s);
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
  if (run.kind == RunKind::Stochastic) return stochastic_lane(model, run.mu, run.index);
  return deterministic_lane(model, run.mu);
}

ModelConfig run_config(const Study& study, const RunSpec& run) {
  return run_config(study.points.at(run.point).config, run);
}

LaneSpec run_lane(const Study& study, const RunSpec& run) { return run_lane(study.points.at(run.point).config, run); }

std::vector<std::vector<RunSpec>> make_blocks(const std::vector<RunSpec>& runs, int lanes) {
  // Lanes of one Ensemble share its mesh schedule (phi0) and one Recorder (record interval).
  // Lanes may differ only in what LaneSpec carries (mu, the load): the schedule groups study points
  // that share everything else (a pinion speed, a backlash... need blocks of their own).
  std::map<std::tuple<std::size_t, double, std::int64_t>, std::vector<RunSpec>> groups;
  std::vector<std::vector<RunSpec>> blocks;
  for (const RunSpec& r : runs) {
    std::vector<RunSpec>& g = groups[{r.schedule, r.mesh_phase, r.record_every}];
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
  run_batch(make_study(model, settings), runs, settings, sink, control);
}

void run_batch(const Study& study, const std::vector<RunSpec>& runs,
               const BatchSettings& settings, BatchSink& sink, BatchControl& control) {
  const ModelConfig& model = study.base;  // run.* is common to every point
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
      const ModelConfig& point = study.points.at(block.front().point).config;  // shared by the block
      GearInputs gear = point.gear;
      gear.mesh_phase = block.front().mesh_phase;
      std::vector<LaneSpec> lanes;
      for (const RunSpec& r : block) lanes.push_back(run_lane(study, r));
      const GearPair pair = derive(gear);
      // The deterministic runs' Poincare section at mesh phase 0, once per mesh period
      // (doc/batch-folder.md §5): the same times as gear_analyze poincare.
      SectionTimes section;
      if (std::any_of(block.begin(), block.end(), [](const RunSpec& r) { return r.kind != RunKind::Stochastic; }))
        section = {pair.mesh_period_angle / pair.in.pinion_speed, first_mesh_period_start(pair)};
      Ensemble ensemble(pair, point.run.time_step, point.initial, std::move(lanes), point.seed);
      sink.started(block);
      const std::vector<RunResult> results = simulate(ensemble, point.run, recorder, section);
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
