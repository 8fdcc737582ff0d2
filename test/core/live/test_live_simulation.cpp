// LiveSimulation without a master: requests applied at the next publish instant, pause/step/reset,
// t_end and loop, divergence, pacing against an injected clock (no wall-time sleeps), the external
// load input, and the published states bit for bit equal to simulate() for the same realization.
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <mutex>
#include <cstdio>
#include <string>
#include <thread>
#include <vector>

#include "gear_dynamics/config/config.hpp"
#include "gear_dynamics/config/simulator_settings.hpp"
#include "gear_dynamics/engine/simulation.hpp"
#include "gear_dynamics/live/live_simulation.hpp"
#include "gear_dynamics/live/live_spectrum.hpp"

namespace gd = gear_dynamics;

namespace {

struct Loaded {
  gd::ModelConfig model;
  gd::SimulatorSettings sim;
};

constexpr double kH = 1e-6;  // the step these tests count in (run.time_step overridden)

// The shipped config/*.yaml at step kH with `overlay` (YAML text) merged on top.
Loaded load(const std::string& overlay) {
  const std::string dir = GEAR_DYNAMICS_CONFIG_DIR;
  YAML::Node root = gd::read_yaml_files({dir + "/gear_pair.yaml", dir + "/load.yaml", dir + "/run.yaml",
                                         dir + "/simulator.yaml"});
  root["run"]["time_step"] = kH;
  gd::merge_yaml(root, YAML::Load(overlay));
  Loaded l;
  l.model = gd::parse_config(root);
  l.sim = gd::parse_simulator_settings(root, l.model.run.time_step);
  return l;
}

struct RecordingSink : gd::LiveSink {
  std::vector<gd::LiveSample> samples;
  std::vector<gd::LiveRunInfo> infos;
  std::vector<std::pair<gd::LiveLogLevel, std::string>> lines;
  std::vector<gd::LiveSample> finishes;
  void publish(const gd::LiveSample& s) override { samples.push_back(s); }
  void run_info(const gd::LiveRunInfo& i) override { infos.push_back(i); }
  void log(gd::LiveLogLevel level, const std::string& line) override { lines.emplace_back(level, line); }
  void finished(const gd::LiveSample& s) override { finishes.push_back(s); }
  bool logged(gd::LiveLogLevel level, const std::string& part) const {
    for (const auto& [l, text] : lines)
      if (l == level && text.find(part) != std::string::npos) return true;
    return false;
  }
};

struct FakeClock : gd::LiveClock {
  time_point t{};
  time_point now() const override { return t; }
};

using Request = gd::LiveSimulation::Request;

// Runs iterate() until the simulation stops running or `max` iterations.
void run_until_stopped(gd::LiveSimulation& sim, int max = 100000) {
  for (int i = 0; i < max; ++i)
    if (!sim.iterate().running) return;
}

}  // namespace

TEST(LiveSimulation, StartPublishesTheInitialStateAndRunInfo) {
  const Loaded l = load("simulator: {paused: true, t_end: 0.01}");
  RecordingSink sink;
  gd::LiveSimulation sim(l.model, l.sim, sink);
  ASSERT_EQ(sink.samples.size(), 1u);
  EXPECT_EQ(sink.samples[0].step, 0);
  EXPECT_EQ(sink.samples[0].t, 0.0);
  ASSERT_EQ(sink.infos.size(), 1u);
  EXPECT_EQ(sink.infos[0].step, 0);
  EXPECT_EQ(sim.period_steps(), 1000);
  EXPECT_EQ(sim.end_step(), 10000);
  EXPECT_EQ(sim.status().state, "paused");
  // Paused: an iteration neither steps nor publishes.
  EXPECT_FALSE(sim.iterate().running);
  EXPECT_EQ(sink.samples.size(), 1u);
  EXPECT_EQ(sim.realization().step_index(), 0);
}

TEST(LiveSimulation, RequestsApplyAtTheNextPublishInstant) {
  const Loaded l = load("simulator: {real_time_factor: 0.0, t_end: 0.01}");
  RecordingSink sink;
  gd::LiveSimulation sim(l.model, l.sim, sink);
  sim.iterate();  // to t = 1 ms
  sim.iterate();  // to t = 2 ms
  ASSERT_EQ(sink.samples.back().step, 2000);
  Request r;
  r.mu = 0.1;
  sim.post(r);
  r = Request{};
  r.sigma = 7.0;
  sim.post(r);  // merged with the first
  EXPECT_EQ(sim.realization().lane().mu, l.model.friction_coefficient);  // not before the loop takes it
  sim.iterate();
  EXPECT_TRUE(sim.last_outcome().ok);
  // Both apply from step 2000 on: run_info says so, and the next sample carries them.
  ASSERT_EQ(sink.infos.size(), 2u);
  EXPECT_EQ(sink.infos[1].step, 2000);
  EXPECT_EQ(sink.infos[1].lane.mu, 0.1);
  EXPECT_EQ(sink.infos[1].lane.sigma, 7.0);
  EXPECT_EQ(sink.infos[1].config.friction_coefficient, 0.1);
  EXPECT_EQ(sink.samples.back().step, 3000);
  EXPECT_EQ(sink.samples.back().mu, 0.1);
  EXPECT_EQ(sink.samples.back().sigma, 7.0);
  EXPECT_TRUE(sink.logged(gd::LiveLogLevel::Info, "mu: 0.04 -> 0.1 from t = 0.002 s (step 2000)"));

  // The same dynamics as an ensemble that switches at step 2000.
  gd::Ensemble ref(gd::derive(l.model.gear), kH, l.model.initial,
                   {gd::stochastic_lane(l.model, l.model.friction_coefficient, l.sim.realization)}, l.model.seed);
  while (ref.step_index() < 2000) ref.step();
  ref.set_mu(0, 0.1);
  ref.set_sigma(0, 7.0);
  while (ref.step_index() < 3000) ref.step();
  EXPECT_EQ(sink.samples.back().delta, ref.delta()[0]);
  EXPECT_EQ(sink.samples.back().delta_dot, ref.velocity()[0]);
  EXPECT_EQ(sink.samples.back().phi, ref.load()[0]);

  // A new publish rate: the next instant is on the new grid.
  r = Request{};
  r.publish_rate = 500.0;
  sim.post(r);
  sim.iterate();
  EXPECT_EQ(sim.period_steps(), 2000);
  EXPECT_EQ(sink.samples.back().step, 4000);
  sim.iterate();
  EXPECT_EQ(sink.samples.back().step, 6000);
}

TEST(LiveSimulation, PauseStepReset) {
  const Loaded l = load("simulator: {real_time_factor: 0.0, t_end: 0.01}");
  RecordingSink sink;
  gd::LiveSimulation sim(l.model, l.sim, sink);
  sim.iterate();
  sim.iterate();
  const std::vector<gd::LiveSample> first(sink.samples.begin(), sink.samples.end());
  ASSERT_EQ(first.size(), 3u);

  Request r;
  r.step = true;
  sim.post(r);
  sim.iterate();
  EXPECT_FALSE(sim.last_outcome().ok);  // ~step while running is refused
  EXPECT_EQ(sim.last_outcome().message, "~step works while paused; call ~pause first");

  r = Request{};
  r.paused = true;
  sim.post(r);
  const std::size_t before = sink.samples.size();
  EXPECT_FALSE(sim.iterate().running);
  EXPECT_EQ(sink.samples.size(), before);
  EXPECT_EQ(sim.status().state, "paused");
  const std::int64_t at = sim.realization().step_index();

  r = Request{};
  r.step = true;
  sim.post(r);
  EXPECT_FALSE(sim.iterate().running);  // one publish period, then paused again
  EXPECT_TRUE(sim.last_outcome().ok);
  EXPECT_EQ(sim.realization().step_index(), at + 1000);
  EXPECT_EQ(sink.samples.size(), before + 1);
  EXPECT_EQ(at, 3000);  // the refused ~step's iteration still ran one period
  EXPECT_EQ(sim.last_outcome().message, "t = 0.004 s");

  // Reset: t = 0 published again, and the run repeats bit for bit.
  r = Request{};
  r.reset = true;
  r.paused = false;
  sim.post(r);
  sink.samples.clear();
  sim.iterate();
  sim.iterate();
  ASSERT_EQ(sink.samples.size(), 3u);
  for (std::size_t i = 0; i < first.size(); ++i) {
    EXPECT_EQ(sink.samples[i].step, first[i].step);
    EXPECT_EQ(sink.samples[i].delta, first[i].delta);
    EXPECT_EQ(sink.samples[i].delta_dot, first[i].delta_dot);
    EXPECT_EQ(sink.samples[i].phi, first[i].phi);
    EXPECT_EQ(sink.samples[i].center_distance, first[i].center_distance);
  }
}

TEST(LiveSimulation, StopsAtTEnd) {
  const Loaded l = load("simulator: {real_time_factor: 0.0, t_end: 0.0105}");  // not a publish instant
  RecordingSink sink;
  gd::LiveSimulation sim(l.model, l.sim, sink);
  run_until_stopped(sim);
  EXPECT_TRUE(sim.finished());
  EXPECT_EQ(sim.status().state, "stopped at t_end");
  ASSERT_EQ(sink.samples.size(), 12u);  // t = 0, 1, ..., 10 ms and t_end
  EXPECT_EQ(sink.samples.back().step, 10500);
  ASSERT_EQ(sink.finishes.size(), 1u);
  EXPECT_EQ(sink.finishes[0].step, 10500);
  EXPECT_EQ(sink.finishes[0].delta, sink.samples.back().delta);
  EXPECT_TRUE(sink.logged(gd::LiveLogLevel::Info, "t_end = 0.0105 s reached: stopped"));
  Request r;
  r.paused = false;
  sim.post(r);
  EXPECT_FALSE(sim.iterate().running);
  EXPECT_FALSE(sim.last_outcome().ok);
  EXPECT_EQ(sink.samples.size(), 12u);
  r = Request{};
  r.step = true;
  sim.post(r);
  sim.iterate();
  EXPECT_FALSE(sim.last_outcome().ok);
  r = Request{};
  r.reset = true;
  sim.post(r);
  EXPECT_TRUE(sim.iterate().running);
  EXPECT_FALSE(sim.finished());
}

TEST(LiveSimulation, FinalSampleHasTheCenterDistanceEvenUnwanted) {
  // The ROS node wants no center distance while nothing subscribes to the states; its latched
  // final state must still carry d(t_end), the one a subscribed run publishes last.
  struct Unwanted : RecordingSink {
    bool wants_center_distance() const override { return false; }
  };
  const Loaded l = load("simulator: {real_time_factor: 0.0, t_end: 0.06}");  // past the 0.05 s window
  RecordingSink wanting;
  Unwanted unwanted;
  gd::LiveSimulation a(l.model, l.sim, wanting);
  gd::LiveSimulation b(l.model, l.sim, unwanted);
  run_until_stopped(a);
  run_until_stopped(b);
  ASSERT_EQ(wanting.finishes.size(), 1u);
  ASSERT_EQ(unwanted.finishes.size(), 1u);
  EXPECT_GT(wanting.finishes[0].center_distance, 0.0);
  EXPECT_EQ(wanting.finishes[0].center_distance, wanting.samples.back().center_distance);
  EXPECT_EQ(unwanted.finishes[0].center_distance, wanting.finishes[0].center_distance);
  EXPECT_EQ(unwanted.samples.back().center_distance, 0.0);  // the published ones skip the query
}

TEST(LiveSimulation, LoopsAtTEnd) {
  const Loaded l = load("simulator: {real_time_factor: 0.0, t_end: 0.003, loop: true}");
  RecordingSink sink;
  gd::LiveSimulation sim(l.model, l.sim, sink);
  for (int i = 0; i < 6; ++i) EXPECT_TRUE(sim.iterate().running);
  // 0, 1, 2, 3 (t_end) then 0 again (restart publishes t = 0), 1, 2, 3, 0
  std::vector<std::int64_t> steps;
  for (const auto& s : sink.samples) steps.push_back(s.step);
  EXPECT_EQ(steps, (std::vector<std::int64_t>{0, 1000, 2000, 3000, 0, 1000, 2000, 3000, 0}));
  EXPECT_EQ(sink.samples[3].delta, sink.samples[7].delta);
  EXPECT_EQ(sink.infos.size(), 3u);
  EXPECT_TRUE(sink.finishes.empty());
}

TEST(LiveSimulation, DivergenceStopsWithAMessage) {
  // test/ros/diverge.yaml: blows up within the first publish period.
  const Loaded l = load("gear_pair: {initial_velocity: 10.0}\nrun: {time_step: 2.0e-5}\n"
                        "simulator: {real_time_factor: 0.0, publish_clock: false, t_end: 0.4}");
  RecordingSink sink;
  gd::LiveSimulation sim(l.model, l.sim, sink);
  EXPECT_FALSE(sim.iterate().running);
  EXPECT_TRUE(sim.diverged());
  EXPECT_EQ(sink.samples.size(), 1u);  // only t = 0: nothing non-finite went out
  EXPECT_TRUE(sink.logged(gd::LiveLogLevel::Error, "gear model diverged"));
  EXPECT_EQ(sim.status().state, "diverged");
  EXPECT_NE(sim.status().divergence.find("gear model diverged"), std::string::npos);
  Request r;
  r.paused = false;
  sim.post(r);
  sim.iterate();
  EXPECT_FALSE(sim.last_outcome().ok);
  EXPECT_NE(sim.last_outcome().message.find("call ~reset to start over"), std::string::npos);
  r = Request{};
  r.reset = true;
  sim.post(r);
  sim.iterate();
  EXPECT_FALSE(sim.diverged() && sim.realization().step_index() == 0);
  EXPECT_EQ(sink.samples.size(), 2u);  // t = 0 again
}

// Following another node's clock: each state carries the clock time it is due at (what a follower
// stamps), a clock that stands still keeps the target where it is, and a clock that goes back (its
// owner was reset) makes pacing start again from the clock's present, with a warning.
TEST(LiveSimulation, FollowsAClockThatStopsAndGoesBack) {
  using std::chrono::microseconds;
  struct Followed : FakeClock {
    bool steady() const override { return false; }
  };
  const Loaded l = load("simulator: {real_time_factor: 1.0, t_end: 0, publish_clock: false}");
  RecordingSink sink;
  Followed clock;
  clock.t += std::chrono::seconds(7);
  gd::LiveSimulation sim(l.model, l.sim, sink, clock);
  const auto seconds_of = [](gd::LiveClock::time_point t) {
    return std::chrono::duration<double>(t.time_since_epoch()).count();
  };
  EXPECT_DOUBLE_EQ(sink.samples.at(0).clock_time, seconds_of(clock.t));  // t = 0: not anchored yet
  sim.iterate();  // anchors at 7 s
  const auto t0 = clock.t;
  gd::LiveSimulation::Next n = sim.iterate();
  ASSERT_TRUE(n.until);
  EXPECT_EQ(*n.until - t0, microseconds(1000));
  // The second state (1 ms) was published before the loop waited: it is due at 7.001 s.
  EXPECT_DOUBLE_EQ(sink.samples.back().clock_time, seconds_of(t0 + microseconds(1000)));
  // The owner paused: its clock stands still and the target stays.
  n = sim.iterate();
  ASSERT_TRUE(n.until);
  EXPECT_EQ(*n.until - t0, microseconds(2000));
  EXPECT_FALSE(sink.logged(gd::LiveLogLevel::Warn, "went back"));
  // The owner was reset: its clock went back 5 s. No wait for 5 s of the old time line.
  clock.t -= std::chrono::seconds(5);
  n = sim.iterate();
  EXPECT_FALSE(n.until);
  EXPECT_TRUE(sink.logged(gd::LiveLogLevel::Warn, "the pacing clock went back by 5 s"));
  const auto t1 = clock.t;
  n = sim.iterate();
  ASSERT_TRUE(n.until);
  EXPECT_EQ(*n.until - t1, microseconds(1000));
  EXPECT_DOUBLE_EQ(sink.samples.back().clock_time, seconds_of(t1 + microseconds(1000)));
}

TEST(LiveSimulation, PacesByTheInjectedClock) {
  using std::chrono::microseconds;
  const Loaded l = load("simulator: {real_time_factor: 1.0, t_end: 0}");
  RecordingSink sink;
  FakeClock clock;
  clock.t += std::chrono::seconds(10);
  gd::LiveSimulation sim(l.model, l.sim, sink, clock);
  const auto t0 = clock.t;
  // The first iteration anchors (no wait), the next ones wait until one publish period (1 ms of
  // simulated time) per step at factor 1.
  gd::LiveSimulation::Next n = sim.iterate();
  EXPECT_TRUE(n.running);
  EXPECT_FALSE(n.until);
  n = sim.iterate();
  ASSERT_TRUE(n.until);
  EXPECT_EQ(*n.until - t0, microseconds(1000));
  clock.t += microseconds(300);  // the loop ran early: the target does not move
  n = sim.iterate();
  ASSERT_TRUE(n.until);
  EXPECT_EQ(*n.until - t0, microseconds(2000));

  // Factor 4: a quarter of the wall time per simulated ms, from a new anchor. The loop sleeps only
  // when the target is kMinWait (1 ms) ahead or more: three periods go by without a wait.
  Request r;
  r.real_time_factor = 4.0;
  sim.post(r);
  n = sim.iterate();
  EXPECT_FALSE(n.until);  // re-anchored at the change
  const auto t1 = clock.t;
  for (int i = 1; i <= 3; ++i) EXPECT_FALSE(sim.iterate().until) << i;  // 250, 500, 750 us ahead
  n = sim.iterate();
  ASSERT_TRUE(n.until);
  EXPECT_EQ(*n.until - t1, microseconds(1000));

  // A lag over kMaxLag: no burst to catch up, pacing restarts from the present.
  clock.t += std::chrono::milliseconds(150);
  n = sim.iterate();
  EXPECT_FALSE(n.until);
  const auto t2 = clock.t;
  for (int i = 1; i <= 3; ++i) EXPECT_FALSE(sim.iterate().until) << i;
  n = sim.iterate();
  ASSERT_TRUE(n.until);
  EXPECT_EQ(*n.until - t2, microseconds(1000));

  // Factor 0: as fast as possible, never a wait.
  r = Request{};
  r.real_time_factor = 0.0;
  sim.post(r);
  for (int i = 0; i < 3; ++i) EXPECT_FALSE(sim.iterate().until);

  // 1000 publish periods at factor 1 take 1 s of (fake) wall time when the loop waits as told.
  r = Request{};
  r.real_time_factor = 1.0;
  sim.post(r);
  sim.iterate();
  const auto start = clock.t;
  const std::int64_t from = sim.realization().step_index();
  for (int i = 0; i < 1000; ++i) {
    n = sim.iterate();
    ASSERT_TRUE(n.until) << i;
    clock.t = *n.until;
  }
  EXPECT_EQ(clock.t - start, std::chrono::seconds(1));
  EXPECT_EQ(sim.realization().step_index() - from, 1000 * 1000);

  // 10 kHz at factor 1: one sleep per 10 publish periods (1 ms), 1000 per wall second, not 10000.
  r = Request{};
  r.publish_rate = 10000.0;
  sim.post(r);
  int waits = 0;
  const auto start10 = clock.t;
  const std::int64_t from10 = sim.realization().step_index();
  while (clock.t - start10 < std::chrono::seconds(1)) {
    n = sim.iterate();
    if (n.until) {
      ++waits;
      clock.t = *n.until;
    }
  }
  EXPECT_NEAR(waits, 1000, 10);
  EXPECT_NEAR(static_cast<double>(sim.realization().step_index() - from10), 1e6, 2000.0);
}

namespace {

// simulate()'s recording of the same lane, at the same decimation.
std::vector<gd::LiveSample> reference(const Loaded& l, std::int64_t every) {
  gd::RunSettings run = l.model.run;
  run.duration = l.sim.t_end;
  run.snapshot_times.clear();
  const gd::LaneSpec lane = l.sim.deterministic ? gd::deterministic_lane(l.model, l.model.friction_coefficient)
                                                : gd::stochastic_lane(l.model, l.model.friction_coefficient,
                                                                      l.sim.realization);
  gd::Ensemble e(gd::derive(l.model.gear), run.time_step, l.model.initial, {lane}, l.model.seed);
  std::vector<gd::LiveSample> out;
  gd::Recorder rec;
  rec.every = every;
  rec.record = [&](const gd::Ensemble& en, const Eigen::ArrayXd& d) {
    gd::LiveSample s;
    s.step = en.step_index();
    s.t = gd::grid_time(en.step_index(), en.time_step());
    s.delta = en.delta()[0];
    s.delta_dot = en.velocity()[0];
    s.phi = en.load()[0];
    s.center_distance = d[0];
    out.push_back(s);
  };
  gd::simulate(e, run, rec);
  return out;
}

void expect_same_series(const Loaded& l) {
  RecordingSink sink;
  gd::LiveSimulation sim(l.model, l.sim, sink);
  run_until_stopped(sim);
  const auto ref = reference(l, sim.period_steps());
  ASSERT_EQ(sink.samples.size(), ref.size());
  for (std::size_t i = 0; i < ref.size(); ++i) {
    SCOPED_TRACE("sample " + std::to_string(i));
    EXPECT_EQ(sink.samples[i].step, ref[i].step);
    EXPECT_EQ(sink.samples[i].t, ref[i].t);
    EXPECT_EQ(sink.samples[i].delta, ref[i].delta);
    EXPECT_EQ(sink.samples[i].delta_dot, ref[i].delta_dot);
    EXPECT_EQ(sink.samples[i].phi, ref[i].phi);
    EXPECT_EQ(sink.samples[i].center_distance, ref[i].center_distance);
  }
}

}  // namespace

TEST(LiveSimulation, SameSeriesAsSimulateStochastic) {
  expect_same_series(load("gear_pair: {friction_coefficient: 0.03}\nrun: {seed: 12345}\n"
                          "simulator: {realization: 3, real_time_factor: 0.0, t_end: 0.05}"));
}

TEST(LiveSimulation, SameSeriesAsSimulateDeterministic) {
  expect_same_series(load("simulator: {deterministic: true, real_time_factor: 0.0, t_end: 0.05, "
                          "publish_rate: 10000.0}"));
}

TEST(LiveSimulation, RequestWaitsForTheLoopThread) {
  const Loaded l = load("simulator: {paused: true, t_end: 0.01}");
  RecordingSink sink;  // written by the loop thread only while request() waits
  gd::LiveSimulation sim(l.model, l.sim, sink);
  sim.start();
  Request r;
  r.step = true;
  gd::LiveSimulation::Outcome o = sim.request(r);
  EXPECT_TRUE(o.ok);
  EXPECT_EQ(o.message, "t = 0.001 s");
  o = sim.request(r);
  EXPECT_EQ(o.message, "t = 0.002 s");
  EXPECT_EQ(sim.status().time, 0.002);
  sim.stop();
  EXPECT_EQ(sim.request(r).message, "shutting down");
  EXPECT_EQ(sink.samples.size(), 3u);
}

TEST(LiveSimulation, ExternalLoadHoldsTheCommandFromTheNextStep) {
  const Loaded l = load("simulator: {real_time_factor: 0.0, t_end: 0.01, load_input: external}");
  RecordingSink sink;
  gd::LiveSimulation sim(l.model, l.sim, sink);
  EXPECT_EQ(sim.load_input(), gd::LoadInput::External);
  EXPECT_EQ(sim.realization().lane().sigma, 0.0);
  EXPECT_EQ(sink.samples[0].phi, l.model.load.initial_mean);  // before any command: Phi(0), held
  sim.iterate();
  EXPECT_EQ(sink.samples.back().phi, l.model.load.initial_mean);
  sim.command_load(25.0, 12.5);
  sim.iterate();
  EXPECT_EQ(sink.samples.back().phi, 25.0);
  EXPECT_TRUE(sink.logged(gd::LiveLogLevel::Info, "load command 25 m/s^2 (stamp 12.500000000 s) in effect from step 1000"));
  // The dynamics equal an ensemble whose load is set to 25 at step 1000.
  gd::LaneSpec lane = gd::stochastic_lane(l.model, l.model.friction_coefficient, l.sim.realization);
  lane.sigma = lane.drift = lane.load_sd = 0.0;
  gd::Ensemble ref(gd::derive(l.model.gear), kH, l.model.initial, {lane}, l.model.seed);
  while (ref.step_index() < 1000) ref.step();
  ref.set_load(0, 25.0);
  while (ref.step_index() < 2000) ref.step();
  EXPECT_EQ(sink.samples.back().delta, ref.delta()[0]);
  EXPECT_EQ(sim.status().load_commands, 1);
  // sigma requests are refused in this mode.
  Request r;
  r.sigma = 3.0;
  sim.post(r);
  sim.iterate();
  EXPECT_EQ(sim.realization().lane().sigma, 0.0);
  EXPECT_TRUE(sink.logged(gd::LiveLogLevel::Warn, "sigma and lambda stay 0 with the external load"));
}

TEST(LiveSimulation, DeterministicLoadRefusesNoise) {
  const Loaded l = load("simulator: {real_time_factor: 0.0, t_end: 0.01, deterministic: true}");
  RecordingSink sink;
  gd::LiveSimulation sim(l.model, l.sim, sink);
  Request r;
  r.sigma = 3.0;
  r.drift = 1.0;
  sim.post(r);
  sim.iterate();
  EXPECT_EQ(sim.realization().lane().sigma, 0.0);
  EXPECT_EQ(sim.realization().lane().drift, 0.0);
  EXPECT_EQ(sim.status().sigma, 0.0);
  EXPECT_TRUE(sink.logged(gd::LiveLogLevel::Warn, "sigma and lambda stay 0 with the deterministic load"));
}

TEST(LiveSimulation, ExternalPlusNoiseShiftsTheSdeByTheCommand) {
  const Loaded l = load("simulator: {real_time_factor: 0.0, t_end: 0.01, load_input: external_plus_noise}\n"
                        "load: {sigma: 5.0}");
  RecordingSink sink;
  gd::LiveSimulation sim(l.model, l.sim, sink);
  sim.command_load(30.0, 0.0);
  sim.iterate();  // first command: Phi = 30 at step 0, then the SDE's increments
  gd::Ensemble ref(gd::derive(l.model.gear), kH, l.model.initial,
                   {gd::stochastic_lane(l.model, l.model.friction_coefficient, l.sim.realization)}, l.model.seed);
  ref.set_load(0, 30.0);
  while (ref.step_index() < 1000) ref.step();
  EXPECT_EQ(sink.samples.back().phi, ref.load()[0]);
  EXPECT_NE(sink.samples.back().phi, 30.0);
  sim.command_load(32.0, 0.001);  // +2 on top of wherever the noise is
  sim.iterate();
  ref.set_load(0, ref.load()[0] + 2.0);
  while (ref.step_index() < 2000) ref.step();
  EXPECT_EQ(sink.samples.back().phi, ref.load()[0]);
  EXPECT_EQ(sink.samples.back().delta, ref.delta()[0]);
}

TEST(LiveSimulation, SdeIgnoresLoadCommands) {
  const Loaded l = load("simulator: {real_time_factor: 0.0, t_end: 0.01}");
  RecordingSink a, b;
  gd::LiveSimulation with(l.model, l.sim, a), without(l.model, l.sim, b);
  with.command_load(99.0, 0.0);
  with.iterate();
  without.iterate();
  EXPECT_EQ(a.samples.back().phi, b.samples.back().phi);
  EXPECT_EQ(with.status().load_commands, 0);
}

TEST(LiveSimulation, TimeIsTheGridTimeRoundedToNanoseconds) {
  EXPECT_EQ(gd::grid_time_ns(83123000, 1e-6), 83123000000);
  EXPECT_EQ(gd::grid_time(83123000, 1e-6), 83.123);  // n * h would be 83.12299999999999
  EXPECT_NE(83123000 * 1e-6, 83.123);
  const Loaded l = load("simulator: {real_time_factor: 0.0, t_end: 0.01, publish_rate: 10000.0}");
  RecordingSink sink;
  gd::LiveSimulation sim(l.model, l.sim, sink);
  run_until_stopped(sim);
  for (const auto& s : sink.samples) {
    char text[40];
    std::snprintf(text, sizeof text, "%.17g", s.t);
    double shortest = 0.0;
    char again[40];
    std::snprintf(again, sizeof again, "%.4f", s.t);  // every publish instant is a multiple of 0.1 ms
    std::sscanf(again, "%lf", &shortest);
    EXPECT_EQ(s.t, shortest) << text;
  }
}

TEST(LoadInput, Names) {
  EXPECT_EQ(gd::load_input_from_string("sde"), gd::LoadInput::Sde);
  EXPECT_EQ(gd::load_input_from_string("external"), gd::LoadInput::External);
  EXPECT_EQ(gd::load_input_from_string("external_plus_noise"), gd::LoadInput::ExternalPlusNoise);
  EXPECT_THROW(gd::load_input_from_string("extern"), gd::ConfigError);
  EXPECT_EQ(gd::to_string(gd::LoadInput::ExternalPlusNoise), "external_plus_noise");
}

// ---- the spectrum topic's samples (doc/gear_simulator.md §3) ----

TEST(SampleRing, OldestFirstAcrossTheWrap) {
  gd::SampleRing ring(5);
  std::vector<double> d, f;
  ring.copy_to(d, f);
  EXPECT_TRUE(d.empty());
  for (int i = 0; i < 3; ++i) ring.push(i, 10 * i);
  ring.copy_to(d, f);
  EXPECT_EQ(d, (std::vector<double>{0, 1, 2}));
  EXPECT_EQ(f, (std::vector<double>{0, 10, 20}));
  for (int i = 3; i < 12; ++i) ring.push(i, 10 * i);  // wrapped: the last 5
  ring.copy_to(d, f);
  EXPECT_EQ(d, (std::vector<double>{7, 8, 9, 10, 11}));
  EXPECT_EQ(f, (std::vector<double>{70, 80, 90, 100, 110}));
  ring.clear();
  ring.copy_to(d, f);
  EXPECT_TRUE(d.empty());
}

namespace {

struct SpectrumSink : RecordingSink {
  struct Window {
    gd::SpectrumSamples meta;
    std::vector<double> delta, force;
  };
  std::vector<Window> windows;
  void spectrum(const gd::SpectrumSamples& w) override {
    windows.push_back(Window{w, {}, {}});
    w.samples->copy_to(windows.back().delta, windows.back().force);
  }
};

}  // namespace

// The windows are the grid states every sample period (not the published ones: the publish period
// here, 3333 steps, is no multiple of the 50-step sample period), delta and the mesh force of the
// same realization stepped by an Ensemble, at every update instant (every 10000 steps) once a segment
// is full, partial until the window is; a reset starts the window again from t = 0.
TEST(LiveSimulation, SpectrumWindowsAreTheGridSamples) {
  const Loaded l = load("gear_pair: {friction_coefficient: 0.03}\n"
                        "simulator: {real_time_factor: 0.0, t_end: 0.05, publish_rate: 300.0, spectrum_rate: 100.0,"
                        " spectrum_sample_rate: 20000.0, spectrum_window: 0.012, spectrum_segment: 0.001}");
  constexpr std::int64_t kSampleSteps = 50, kUpdateSteps = 10000;
  constexpr std::size_t kWindow = 240;
  const gd::GearPair g = gd::derive(l.model.gear);
  gd::Ensemble ref(g, kH, l.model.initial, {gd::stochastic_lane(l.model, l.model.friction_coefficient, 0)},
                   l.model.seed);
  std::vector<double> delta, force;  // every sample of the reference, from n = 0
  while (ref.step_index() <= 50000) {
    if (ref.step_index() % kSampleSteps == 0) {
      delta.push_back(ref.delta()[0]);
      force.push_back(gd::mesh_force(g, ref.mesh().stiffness(ref.time()), ref.delta()[0], ref.velocity()[0]));
    }
    ref.step();
  }

  SpectrumSink sink;
  gd::LiveSimulation sim(l.model, l.sim, sink);
  run_until_stopped(sim);
  ASSERT_EQ(sim.realization().step_index(), 50000);
  const auto check = [&](const SpectrumSink::Window& w, std::int64_t step) {
    EXPECT_EQ(w.meta.step, step);
    EXPECT_EQ(w.meta.t, gd::grid_time(step, kH));
    EXPECT_DOUBLE_EQ(w.meta.sample_rate, 20000.0);
    EXPECT_DOUBLE_EQ(w.meta.mesh_frequency, 1000.0 / 60.0 * 20.0);  // 1000 rpm, 20 teeth
    const std::size_t last = static_cast<std::size_t>(step / kSampleSteps);
    const std::size_t size = std::min(kWindow, last + 1);
    ASSERT_EQ(w.delta.size(), size);
    EXPECT_EQ(w.meta.window_start, gd::grid_time(step - static_cast<std::int64_t>(size - 1) * kSampleSteps, kH));
    for (std::size_t i = 0; i < size; ++i) {
      EXPECT_EQ(w.delta[i], delta[last + 1 - size + i]) << "step " << step << ", sample " << i;
      EXPECT_EQ(w.force[i], force[last + 1 - size + i]) << "step " << step << ", sample " << i;
    }
  };
  // Updates at 10, 20, ..., 50 ms: 201 samples at the first (a segment is 20), the full window after.
  ASSERT_EQ(sink.windows.size(), 5u);
  EXPECT_EQ(sink.windows[0].delta.size(), 201u);
  for (std::size_t k = 0; k < sink.windows.size(); ++k) {
    check(sink.windows[k], kUpdateSteps * (k + 1));
    EXPECT_EQ(sink.windows[k].meta.last, k == 4);  // t_end = 50 ms without loop: the run's last window
  }

  // The mesh force in contact is K g(delta) > 0 under the positive load, and 0 inside the backlash.
  bool contact = false;
  for (std::size_t i = 0; i < delta.size(); ++i) {
    if (std::abs(delta[i]) <= l.model.gear.backlash) {
      EXPECT_EQ(force[i], 0.0);
    }
    contact = contact || force[i] != 0.0;
  }
  EXPECT_TRUE(contact);

  Request r;
  r.reset = true;
  sim.post(r);
  sink.windows.clear();
  for (int i = 0; i < 4; ++i) sim.iterate();  // reset, then to 4 x 3333 steps: the update at 10 ms
  ASSERT_EQ(sink.windows.size(), 1u);
  check(sink.windows[0], 10000);
}

TEST(LiveSimulation, NoSpectrumByDefault) {
  const Loaded l = load("simulator: {real_time_factor: 0.0, t_end: 0.003}");
  EXPECT_EQ(l.sim.spectrum_rate, 0.0);
  SpectrumSink sink;
  gd::LiveSimulation sim(l.model, l.sim, sink);
  run_until_stopped(sim);
  EXPECT_TRUE(sink.windows.empty());
}
