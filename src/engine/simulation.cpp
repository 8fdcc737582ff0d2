#include "gear_dynamics/engine/simulation.hpp"

#include <cmath>
#include <numeric>
#include <optional>

#include "gear_dynamics/engine/bearings.hpp"
#include "gear_dynamics/engine/observers.hpp"

namespace gear_dynamics {

std::int64_t RunSettings::steps() const { return steps_for(duration); }

std::int64_t RunSettings::steps_for(double t) const {
  return static_cast<std::int64_t>(std::llround(t / time_step));
}

std::int64_t grid_time_ns(std::int64_t n, double time_step) {
  return static_cast<std::int64_t>(std::llround(static_cast<double>(n) * time_step * 1e9));
}

double grid_time(std::int64_t n, double time_step) {
  return static_cast<double>(grid_time_ns(n, time_step)) / 1e9;  // correctly rounded: nearest the decimal
}

std::vector<RunResult> simulate(Ensemble& ensemble, const RunSettings& settings,
                                const Recorder& recorder, const SectionTimes& section) {
  const int lanes = ensemble.lanes();
  // The observers keep the padding lanes too, so that each step is one pass over whole packets.
  const int padded = ensemble.padded_lanes();
  const std::int64_t total = settings.steps();
  const std::int64_t window = settings.steps_for(settings.window);
  // Blocks that make the window exact at T and at every recorded step.
  std::int64_t block = std::gcd(std::max<std::int64_t>(window, 1), total);
  if (recorder.every > 0) block = std::gcd(block, recorder.every);
  WindowRange range(padded, window, std::max<std::int64_t>(block, 1));

  const double b = ensemble.gear().in.backlash;
  SteadyStateTime settle(padded, b, settings.steady_state_tolerance * b);
  SteadyStateTime settle_fine(padded, b, settings.steady_state_tolerance_fine * b);
  std::vector<std::int64_t> snapshot_steps;
  for (double t : settings.snapshot_times) snapshot_steps.push_back(settings.steps_for(t));
  Snapshots snaps(lanes, snapshot_steps);
  std::optional<PoincareSampler> poincare;
  if (section.period > 0)
    poincare.emplace(lanes, settings.time_step, section.period, section.offset, settings.duration);

  std::optional<BearingForceSums> forces;
  if (ensemble.model_state().size() > 0) forces.emplace(lanes);
  const std::int64_t window_from = total - window;

  // Only the windows that are ever read need the sliding observer: the last one, or all of them
  // when recording.
  const std::int64_t range_from = recorder.every > 0 ? 0 : total - window;
  // The recorded steps are the multiples of recorder.every (counted, not a division per step).
  const std::int64_t every = recorder.every;
  std::int64_t next_record = every > 0 ? (ensemble.step_index() + every - 1) / every * every : -1;
  using Packet = Eigen::Array<double, Ensemble::kPacket, 1>;
  const auto observe = [&](std::int64_t n) {
    const double t = ensemble.time();
    const bool ranged = n >= range_from;
    if (ranged) range.start(n);
    const double* delta = ensemble.padded_delta().data();
    const double* velocity = ensemble.padded_velocity().data();
    for (Eigen::Index p = 0; p < padded; p += Ensemble::kPacket) {  // every observer in one pass
      const Packet d = Eigen::Map<const Packet>(delta + p);
      settle.observe_packet(t, p, d);
      settle_fine.observe_packet(t, p, d);
      if (ranged) range.observe_packet(p, d, Packet(Eigen::Map<const Packet>(velocity + p)));
    }
    if (forces && n >= window_from) {
      const model_step::MeshPoint mesh = output_mesh_point(ensemble.mesh(), ensemble.time());
      forces->observe([&](int i) { return bearings_outputs(ensemble, mesh, i); });
    }
    if (snaps.due(n)) snaps.observe(n, ensemble.delta(), ensemble.velocity(), ensemble.load());
    if (poincare) poincare->observe(n, ensemble.delta(), ensemble.velocity());
    if (n == next_record) {
      recorder.record(ensemble, range.center_distance().head(lanes));
      next_record += every;
    }
  };

  observe(ensemble.step_index());
  while (ensemble.step_index() < total) {
    ensemble.step();
    observe(ensemble.step_index());
  }

  const Eigen::ArrayXd d = range.center_distance();
  const Eigen::ArrayXd dr = range.delta_range();
  const Eigen::ArrayXd vr = range.velocity_range();
  std::vector<RunResult> results(lanes);
  for (int i = 0; i < lanes; ++i) {
    RunResult& r = results[i];
    r.center_distance = d[i];
    r.delta_range = dr[i];
    r.delta_dot_range = vr[i];
    r.steady_state_time = settle.time()[i];
    r.steady_state_time_fine = settle_fine.time()[i];
    r.reached_steady_state = settings.steps_for(r.steady_state_time) < total;
    r.final_delta = ensemble.delta()[i];
    r.final_delta_dot = ensemble.velocity()[i];
    r.final_load = ensemble.load()[i];
    if (poincare) r.section = poincare->points()[static_cast<std::size_t>(i)];
    if (forces) r.bearings = forces->result(i);
    for (std::size_t k = 0; k < snaps.taken(); ++k) {
      const auto kk = static_cast<Eigen::Index>(k);
      r.snapshots.push_back({static_cast<double>(snapshot_steps[k]) * settings.time_step,
                             snaps.delta()(i, kk), snaps.velocity()(i, kk), snaps.load()(i, kk)});
    }
  }
  return results;
}

}  // namespace gear_dynamics
