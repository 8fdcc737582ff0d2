// The live loop with gear_pair.model: bearings (LiveModel, doc/architecture.md §2): its published
// samples are BearingsRealization's states stepped directly, bit for bit (the same bearings_step,
// the same random stream), also across a run-time change of mu and a reset; the torsional model's
// samples carry no bearings outputs and delta_t = delta. At t_end its window forces are the batch's
// (simulate()'s RunResult::bearings) for the same run, bit for bit.
#include <gtest/gtest.h>

#include <algorithm>
#include <string>
#include <vector>

#include "gear_dynamics/config/config.hpp"
#include "gear_dynamics/config/simulator_settings.hpp"
#include "gear_dynamics/engine/bearings.hpp"
#include "gear_dynamics/engine/ensemble.hpp"
#include "gear_dynamics/engine/simulation.hpp"
#include "gear_dynamics/live/live_simulation.hpp"

namespace gd = gear_dynamics;

namespace {

struct Loaded {
  gd::ModelConfig model;
  gd::SimulatorSettings sim;
};

// The shipped config/*.yaml with `overlay` (YAML text) merged on top: real_time_factor 0 (no
// pacing), a state every 100 grid steps, 10 ms.
Loaded load(const std::string& overlay) {
  const std::string dir = GEAR_DYNAMICS_CONFIG_DIR;
  YAML::Node root = gd::read_yaml_files({dir + "/gear_pair.yaml", dir + "/load.yaml", dir + "/run.yaml",
                                         dir + "/simulator.yaml"});
  gd::merge_yaml(root, YAML::Load("simulator: {real_time_factor: 0.0, publish_rate: 4000, t_end: 0.01}"));
  gd::merge_yaml(root, YAML::Load(overlay));
  Loaded l;
  l.model = gd::parse_config(root);
  l.sim = gd::parse_simulator_settings(root, l.model.run.time_step);
  return l;
}

struct RecordingSink : gd::LiveSink {
  std::vector<gd::LiveSample> samples;
  void publish(const gd::LiveSample& s) override { samples.push_back(s); }
  void run_info(const gd::LiveRunInfo&) override {}
  void log(gd::LiveLogLevel, const std::string&) override {}
};

// Also keeps what the live loop reports at every t_end.
struct WindowSink : RecordingSink {
  std::vector<gd::LiveWindowForces> windows;
  std::vector<std::int64_t> steps;  // the last sample's step at each report
  void window_forces(const gd::LiveWindowForces& w, const gd::LiveSample& last) override {
    windows.push_back(w);
    steps.push_back(last.step);
  }
};

void expect_forces_equal(const gd::BearingForces& a, const gd::BearingForces& b) {
  for (const gd::BearingsOutputSpec& s : gd::bearing_force_outputs()) {
    SCOPED_TRACE(s.name);
    EXPECT_EQ((a.*s.window).mean, (b.*s.window).mean);
    EXPECT_EQ((a.*s.window).rms, (b.*s.window).rms);
  }
}

// The batch's window forces of the run the live node makes of `l`: a run of duration t_end, with its
// window cut to t_end when t_end is the shorter.
gd::BearingForces batch_forces(const Loaded& l) {
  gd::RunSettings run = l.model.run;
  run.duration = l.sim.t_end;
  run.window = std::min(run.window, run.duration);
  const gd::LaneSpec lane = l.sim.deterministic
                                ? gd::deterministic_lane(l.model, l.model.friction_coefficient)
                                : gd::stochastic_lane(l.model, l.model.friction_coefficient, l.sim.realization);
  gd::Ensemble ensemble(gd::derive(l.model.gear), run.time_step, l.model.initial, {lane}, l.model.seed);
  const std::vector<gd::RunResult> results = gd::simulate(ensemble, run, gd::Recorder{});
  EXPECT_TRUE(results.at(0).bearings.has_value());
  return results.at(0).bearings.value_or(gd::BearingForces{});
}

void run_until_stopped(gd::LiveSimulation& sim) {
  for (int i = 0; i < 100000; ++i)
    if (!sim.iterate().running) return;
}

// Every field the model gives a sample, equal (bit for bit) to the realization's.
void expect_sample_is(const gd::LiveSample& s, const gd::BearingsRealization& r) {
  SCOPED_TRACE("step " + std::to_string(s.step));
  ASSERT_EQ(s.step, r.step_index());
  ASSERT_TRUE(s.bearings.has_value());
  const gd::BearingsOutputs o = r.outputs();
  EXPECT_EQ(s.delta, o.delta_m);
  EXPECT_EQ(s.delta_dot, o.delta_m_dot);
  EXPECT_EQ(s.delta_t, r.state()[gd::BearingsModel::kDelta]);
  EXPECT_EQ(s.delta_t_dot, r.state()[gd::BearingsModel::kDeltaDot]);
  EXPECT_EQ(s.phi, r.load());
  EXPECT_EQ(s.bearings->delta_m, o.delta_m);
  EXPECT_EQ(s.bearings->delta_m_dot, o.delta_m_dot);
  EXPECT_EQ(s.bearings->mesh_force, o.mesh_force);
  EXPECT_EQ(s.bearings->pinion_fx, o.pinion_fx);
  EXPECT_EQ(s.bearings->pinion_fy, o.pinion_fy);
  EXPECT_EQ(s.bearings->wheel_fx, o.wheel_fx);
  EXPECT_EQ(s.bearings->wheel_fy, o.wheel_fy);
}

}  // namespace

TEST(LiveBearings, SamplesAreTheRealizationSteppedDirectly) {
  // The stochastic load and reversing friction: every term of bearings_step is exercised.
  const Loaded l = load("gear_pair: {model: bearings, friction_direction: reversing}");
  RecordingSink sink;
  gd::LiveSimulation sim(l.model, l.sim, sink);
  run_until_stopped(sim);
  ASSERT_TRUE(sim.finished());
  ASSERT_EQ(sink.samples.size(), 41u);  // t = 0 and every 0.25 ms to 10 ms

  gd::BearingsRealization r(gd::derive(l.model.gear), l.model.run.time_step, l.model.initial,
                            gd::stochastic_lane(l.model, l.model.friction_coefficient, l.sim.realization),
                            l.model.seed);
  for (const gd::LiveSample& s : sink.samples) {
    while (r.step_index() < s.step) r.step();
    expect_sample_is(s, r);
  }
  // Not a trivial path: the mesh carries the load and the friction moves the bodies across the LOA.
  bool loaded = false, across = false;
  for (const gd::LiveSample& s : sink.samples) {
    loaded = loaded || s.bearings->mesh_force > 0.0;
    across = across || s.bearings->pinion_fx != 0.0;
  }
  EXPECT_TRUE(loaded);
  EXPECT_TRUE(across);
}

TEST(LiveBearings, MuChangeAndResetFollowTheRealization) {
  const Loaded l = load("gear_pair: {model: bearings}");
  RecordingSink sink;
  gd::LiveSimulation sim(l.model, l.sim, sink);
  sim.iterate();  // to step 100
  gd::LiveSimulation::Request q;
  q.mu = 0.15;
  sim.post(q);
  sim.iterate();  // applied at step 100, then to step 200
  sim.iterate();  // to step 300
  ASSERT_EQ(sink.samples.back().step, 300);

  gd::BearingsRealization r(gd::derive(l.model.gear), l.model.run.time_step, l.model.initial,
                            gd::stochastic_lane(l.model, l.model.friction_coefficient, l.sim.realization),
                            l.model.seed);
  while (r.step_index() < 100) r.step();
  r.set_mu(0.15);
  while (r.step_index() < 300) r.step();
  expect_sample_is(sink.samples.back(), r);

  // A reset starts the realization over, with the mu in effect: t = 0 again, then its path.
  q = gd::LiveSimulation::Request{};
  q.reset = true;
  sim.post(q);
  sim.iterate();
  gd::BearingsRealization again(gd::derive(l.model.gear), l.model.run.time_step, l.model.initial,
                                gd::stochastic_lane(l.model, 0.15, l.sim.realization), l.model.seed);
  ASSERT_GE(sink.samples.size(), 2u);
  expect_sample_is(sink.samples[sink.samples.size() - 2], again);  // the reset's t = 0
  while (again.step_index() < 100) again.step();
  expect_sample_is(sink.samples.back(), again);
}

TEST(LiveBearings, TorsionalSamplesCarryNoBearings) {
  const Loaded l = load("{}");
  RecordingSink sink;
  gd::LiveSimulation sim(l.model, l.sim, sink);
  sim.iterate();
  for (const gd::LiveSample& s : sink.samples) {
    EXPECT_FALSE(s.bearings.has_value());
    EXPECT_EQ(s.delta_t, s.delta);
    EXPECT_EQ(s.delta_t_dot, s.delta_dot);
  }
}

TEST(LiveBearings, DivergenceStopsWithTheModelsMessage) {
  // test/ros/diverge.yaml's blow-up (a 10 m/s impact at h = 20 us: the impact damping is unstable
  // for RK4) in the bearings model, whose modes are also stable at that step (omega_max h < 2 sqrt 2).
  const Loaded l = load("gear_pair: {model: bearings, initial_velocity: 10.0}\nrun: {time_step: 2.0e-5}\n"
                        "simulator: {publish_rate: 1000, t_end: 0.4}");
  RecordingSink sink;
  gd::LiveSimulation sim(l.model, l.sim, sink);
  EXPECT_FALSE(sim.iterate().running);
  ASSERT_TRUE(sim.diverged());
  EXPECT_EQ(sink.samples.size(), 1u);  // only t = 0: nothing non-finite went out
  EXPECT_NE(sim.status().divergence.find("gear model (bearings) diverged"), std::string::npos)
      << sim.status().divergence;
}

TEST(LiveBearings, WindowForcesAtTEndAreTheBatchRuns) {
  // A stochastic run with reversing friction over [0.01, 0.06] s (W = 0.05 s), S1 at another mu, and
  // a run shorter than W, whose window starts at t = 0 (the batch's window = T).
  struct Case {
    const char* overlay;
    const char* name;
    double window_start;
  };
  const Case cases[] = {
      {"gear_pair: {model: bearings, friction_direction: reversing}\nsimulator: {t_end: 0.06, realization: 3}",
       "mu0.0400_r00003", 0.06 - 0.05},
      {"gear_pair: {model: bearings, friction_coefficient: 0.1}\nsimulator: {t_end: 0.06, deterministic: true}",
       "mu0.1000_S1", 0.06 - 0.05},
      {"gear_pair: {model: bearings}\nsimulator: {t_end: 0.02}", "mu0.0400_r00000", 0.0},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.overlay);
    const Loaded l = load(c.overlay);
    WindowSink sink;
    gd::LiveSimulation sim(l.model, l.sim, sink);
    run_until_stopped(sim);
    ASSERT_TRUE(sim.finished());
    ASSERT_EQ(sink.windows.size(), 1u);
    const gd::LiveWindowForces& w = sink.windows[0];
    EXPECT_EQ(sink.steps[0], sim.end_step());
    EXPECT_EQ(w.run_name, c.name);
    EXPECT_EQ(w.t, l.sim.t_end);
    EXPECT_EQ(w.window_start, c.window_start);
    expect_forces_equal(w.forces, batch_forces(l));
    EXPECT_GT(w.forces.mesh_force.mean, 0.0);  // a loaded run, not zeros on both sides
  }
}

TEST(LiveBearings, WindowForcesRepeatAfterLoopAndReset) {
  // Each pass of a loop, and a run after ~reset, sums its own window only.
  const Loaded l = load("gear_pair: {model: bearings}\nsimulator: {t_end: 0.02, loop: true}");
  WindowSink sink;
  gd::LiveSimulation sim(l.model, l.sim, sink);
  while (sink.windows.size() < 2) sim.iterate();
  gd::LiveSimulation::Request q;
  q.reset = true;
  sim.post(q);
  while (sink.windows.size() < 3) sim.iterate();
  const gd::BearingForces batch = batch_forces(l);
  for (const gd::LiveWindowForces& w : sink.windows) expect_forces_equal(w.forces, batch);
}

TEST(LiveBearings, NoWindowForcesWithoutTEndOrBearings) {
  for (const char* overlay : {"gear_pair: {model: bearings}\nsimulator: {t_end: 0.0}", "simulator: {t_end: 0.01}"}) {
    SCOPED_TRACE(overlay);
    const Loaded l = load(overlay);
    WindowSink sink;
    gd::LiveSimulation sim(l.model, l.sim, sink);
    for (int i = 0; i < 60; ++i) sim.iterate();  // past 0.01 s
    EXPECT_GE(sink.samples.back().t, 0.01);
    EXPECT_TRUE(sink.windows.empty());
  }
}
