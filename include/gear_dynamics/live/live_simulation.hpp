// The live simulation without ROS (doc/gear_simulator.md §13): one realization of the gear model
// (doc/model.md) stepped in simulated time, paced by wall time against a real-time factor, with
// run-time requests (mu, sigma, lambda, real_time_factor, publish_rate, pause, reset, step) handed
// over from other threads and applied between two steps at the next publish instant, an optional
// external load command applied at the next step, t_end (stop or loop) and divergence.
//
// It reports through a LiveSink (the state at every publish instant, run-info changes, log lines),
// so the ROS node gear_simulator is a thin adapter (publishers, services, dynamic_reconfigure,
// diagnostics), and it is unit-tested without a master (test/core/live/test_live_simulation.cpp) with an
// injected clock: iterate() does one step of the loop and says until when the loop would wait.
#pragma once

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "gear_dynamics/config/config.hpp"
#include "gear_dynamics/config/simulator_settings.hpp"
#include "gear_dynamics/engine/bearings.hpp"
#include "gear_dynamics/engine/ensemble.hpp"
#include "gear_dynamics/engine/realization.hpp"
#include "gear_dynamics/engine/observers.hpp"

namespace gear_dynamics {

// Where the external load comes from (simulator.load_input).
// (simulator.load_input; commands through LiveSimulation::command_load).
enum class LoadInput {
  Sde,                // the load SDE of load.yaml (Eq. 19); load commands are ignored
  External,           // Phi = the last command, held constant (sigma and lambda not applied)
  ExternalPlusNoise,  // Phi = the last command + the SDE's own increments since the first command
};
LoadInput load_input_from_string(const std::string& name);  // throws ConfigError
std::string to_string(LoadInput mode);

// The state of the lane at one publish instant (SI; the fields of GearState).
struct LiveSample {
  std::int64_t step = 0;  // grid index n; t = n h
  double t = 0.0;         // grid_time(n, h): n h rounded to whole ns (engine/simulation.hpp) [s]
  // The mesh deflection and its rate (delta_m in the bearings model, as the batch's GearState).
  double delta = 0.0, delta_dot = 0.0, phi = 0.0;
  // The torsional coordinate Rb1 theta1 - Rb2 theta2 and its rate (the gears' angles): delta itself
  // in the torsional model.
  double delta_t = 0.0, delta_t_dot = 0.0;
  // The bearings model's outputs (doc/model.md §11); empty for the torsional model.
  std::optional<BearingsOutputs> bearings;
  double center_distance = 0.0;  // d(t) over the trailing window (0 if the sink did not want it)
  double mesh_stiffness = 0.0, mesh_phase = 0.0;
  double mu = 0.0, sigma = 0.0, drift = 0.0;
  std::uint64_t realization = 0, seed = 0;
  // The pacing clock's time this state stands for [s since the clock's epoch]: where pacing is
  // anchored, the time at which it is due; otherwise the clock's time when it was taken. A node
  // that follows another's clock stamps its messages with it.
  double clock_time = 0.0;
};

// What the run's parameters are from `step` on (for RunInfo).
struct LiveRunInfo {
  std::int64_t step = 0;
  double t = 0.0;
  ModelConfig config;          // with the friction coefficient (and sigma, lambda) in effect
  SimulatorSettings settings;  // with real_time_factor and publish_rate in effect
  LaneSpec lane;               // the lane as it steps from here on
  LoadInput load_input;
};

// The bearings model's forces over a finite run's analysis window [t_end - W, t_end] (W =
// run.window, or from t = 0 if t_end is shorter): what the batch's RunResult::bearings holds for
// the same run, summed by the same BearingForceSums.
struct LiveWindowForces {
  std::string run_name;  // as a batch names the run: mu label and S1 or r<realization>
  double t = 0.0;             // t_end [s]
  double window_start = 0.0;  // t_end - W, or 0 [s]
  BearingForces forces;
};

enum class LiveLogLevel { Debug, Info, Warn, Error };

// The spectrum topic's trailing window: delta and the mesh force, the last `capacity` samples, in a
// ring. The stepping loop only stores two doubles per sample; the PSD is the sink's business.
class SampleRing {
 public:
  explicit SampleRing(std::size_t capacity = 0) : delta_(capacity), force_(capacity) {}
  void clear() { next_ = size_ = 0; }
  void push(double delta, double force) {
    delta_[next_] = delta;
    force_[next_] = force;
    if (++next_ == delta_.size()) next_ = 0;
    if (size_ < delta_.size()) ++size_;
  }
  std::size_t size() const { return size_; }
  std::size_t capacity() const { return delta_.size(); }
  // The samples, oldest first (resizes the vectors to size()).
  void copy_to(std::vector<double>& delta, std::vector<double>& force) const;

 private:
  std::vector<double> delta_, force_;
  std::size_t next_ = 0, size_ = 0;  // where the next sample goes; samples held
};

// At a spectrum update instant: the trailing window, its last sample at grid step `step`.
struct SpectrumSamples {
  std::int64_t step = 0;
  double t = 0.0;               // grid_time(step, h) [s]
  double window_start = 0.0;    // grid time of the window's first sample [s]
  double sample_rate = 0.0;     // [Hz]
  double mesh_frequency = 0.0;  // f_m [Hz]
  bool last = false;            // at t_end without loop: the run's final window
  const SampleRing* samples = nullptr;  // valid during the call only
};

// Where the simulation reports. Called on the stepping thread (or the thread calling iterate()).
class LiveSink {
 public:
  virtual ~LiveSink() = default;
  // Every publish instant (n a multiple of the publish period, t = 0 after a (re)start and t_end).
  virtual void publish(const LiveSample& sample) = 0;
  // At the start, at every reset and after every change of mu, sigma, lambda, rate or factor.
  virtual void run_info(const LiveRunInfo& info) = 0;
  virtual void log(LiveLogLevel level, const std::string& line) = 0;
  // While not running (paused, at t_end, diverged): about every idle period, with the last sample.
  virtual void idle(const LiveSample& /*last*/) {}
  // At t_end without loop: the last sample (already published), once per run, with its center
  // distance whatever wants_center_distance() says.
  virtual void finished(const LiveSample& /*last*/) {}
  // At every t_end reached with the bearings model (before finished(), or before a loop starts over),
  // with the last sample (already published).
  virtual void window_forces(const LiveWindowForces& /*forces*/, const LiveSample& /*last*/) {}
  // Before the loop waits (pacing, idle, a stop), and after an iteration that took kMinWait or
  // more: a sink may hold what publish() handed it until then (the ROS adapter publishes a burst of states back to back: one wake-up of roscpp's
  // writer thread per burst instead of per message). Also called by iterate()'s callers as they like.
  virtual void flush() {}
  // Whether publish() needs the center distance (it costs a window query).
  virtual bool wants_center_distance() const { return true; }
  // With simulator.spectrum_rate > 0: at every spectrum update instant (a whole number of sample
  // periods) once the window holds at least one Welch segment. The sink copies what it needs.
  virtual void spectrum(const SpectrumSamples& /*window*/) {}
};

// Wall time for pacing; tests inject a fake one. A clock that is not steady (another node's
// simulated time, which stops, resumes and may go back) is waited for in short slices of wall time.
class LiveClock {
 public:
  using time_point = std::chrono::steady_clock::time_point;
  virtual ~LiveClock() = default;
  virtual time_point now() const = 0;
  virtual bool steady() const { return true; }
};
class SteadyLiveClock : public LiveClock {
 public:
  time_point now() const override { return std::chrono::steady_clock::now(); }
};

// The live loop's one seam to the model (doc/architecture.md §2): one realization of the model that
// gear_pair.model names, stepped one grid step at a time by that model's own one-realization path
// (Realization, BearingsRealization), so a live run is the batch's realization bit for bit.
class LiveModel {
 public:
  virtual ~LiveModel() = default;
  // The time grid, lane, random stream and load, and their run-time changes (mu, sigma, lambda, Phi).
  virtual RealizationBase& realization() = 0;
  virtual const RealizationBase& realization() const = 0;
  virtual void step() = 0;  // one grid step; throws DivergenceError on a non-finite state
  virtual void reset() = 0;  // t = 0, the initial state, the random stream from its start
  // The mesh deflection and its rate, what the trailing window observes; the mesh force [N].
  virtual double deflection() const = 0;
  virtual double deflection_rate() const = 0;
  virtual double mesh_force() const = 0;
  // The model's fields of a sample: delta, delta_dot, delta_t, delta_t_dot and the outputs.
  virtual void describe(LiveSample& s) const = 0;
  // The bearings model's outputs of the present state; empty for a model without them.
  virtual std::optional<BearingsOutputs> bearings() const { return std::nullopt; }
};
// The realization of lane `lane` of `gear`'s model (gear.in.model): the one place that dispatches on it.
std::unique_ptr<LiveModel> make_live_model(const GearPair& gear, double time_step, const InitialState& initial,
                                           const LaneSpec& lane, std::uint64_t seed);

class LiveSimulation {
 public:
  // What callers ask of the stepping loop; merged until it takes them.
  struct Request {
    std::optional<double> mu, sigma, drift, real_time_factor, publish_rate;
    std::optional<bool> paused;
    bool reset = false;
    bool step = false;
  };
  // How a request was answered: `ok` false with the reason when refused.
  struct Outcome {
    bool ok = true;
    std::string message;
  };
  // For diagnostics.
  struct Status {
    double time = 0.0;
    std::string state = "starting";
    std::string divergence;
    double mu = 0.0, sigma = 0.0, drift = 0.0, real_time_factor = 0.0, publish_rate = 0.0;
    std::int64_t steps = 0;          // integration steps since start (monotonic, across resets)
    std::int64_t publications = 0;   // publish instants since start
    double running_wall = 0.0;       // wall seconds spent running (not paused) [s]
    std::int64_t load_commands = 0;  // external load commands applied
  };
  // What the loop does after one iteration.
  struct Next {
    bool running = false;            // false: idle (paused, at t_end or diverged) until a request
    std::optional<LiveClock::time_point> until;  // running and paced: wait until then
  };

  // Pacing does not burst to catch up a lag longer than this; it restarts from the present.
  static constexpr std::chrono::milliseconds kMaxLag{100};
  // Pacing sleeps only when the target is at least this far ahead: at high publish rates the loop
  // steps several publish periods per wake-up (bursts), instead of one futex sleep per period.
  // The simulation then leads its wall-time target by less than this.
  static constexpr std::chrono::milliseconds kMinWait{1};
  // While not running, the loop wakes this often (LiveSink::idle).
  static constexpr std::chrono::milliseconds kIdlePeriod{100};
  // A clock that is not steady is looked at again after at most this much wall time.
  static constexpr std::chrono::milliseconds kFollowSlice{2};

  // Validated configuration (parse_config, parse_simulator_settings; settings.load_input names the
  // LoadInput). Publishes t = 0 and the run
  // info through `sink` at once (on the constructing thread). `sink` and `clock` must outlive it.
  LiveSimulation(const ModelConfig& config, const SimulatorSettings& settings, LiveSink& sink,
                 const LiveClock& clock = default_clock());
  ~LiveSimulation();  // stop()

  LiveSimulation(const LiveSimulation&) = delete;
  LiveSimulation& operator=(const LiveSimulation&) = delete;

  // ---- any thread ----
  // Hands `r` over and waits until the loop has applied it (needs start(), or iterate() called by
  // another thread). After stop(): {false, "shutting down"}.
  Outcome request(const Request& r);
  // Hands `r` over without waiting (merged with what is pending); the next iterate() applies it.
  void post(const Request& r);
  // An external load command [m/s^2] (used with LoadInput External/ExternalPlusNoise), applied at
  // the next integration step; `stamp` [s] is the sender's time, logged with the step it takes
  // effect at. The last command wins.
  void command_load(double value, double stamp);
  Status status() const;

  // ---- the stepping loop ----
  // Runs the loop (iterate and wait, by the real steady clock) on a thread of its own.
  void start();
  // Stops and joins the loop; waiting request() calls return.
  void stop();
  // One iteration: applies what is pending, then (running, or a ~step) integrates to the next
  // publish instant or t_end and publishes. Returns whether it runs on and until when to wait.
  Next iterate();
  // The outcome of the last request applied by iterate().
  Outcome last_outcome() const;

  // ---- the stepping loop's own view (read it from the stepping thread or between iterate()) ----
  // The one realization, stepped by its model's one-lane path (bit for bit its path in a batch block).
  const RealizationBase& realization() const { return model_->realization(); }
  std::int64_t period_steps() const { return period_; }
  std::int64_t end_step() const { return end_step_; }
  bool paused() const { return paused_; }
  bool finished() const { return finished_; }
  bool diverged() const { return diverged_; }
  const std::string& divergence() const { return divergence_; }
  double real_time_factor() const { return real_time_factor_; }
  LoadInput load_input() const { return load_input_; }

  static const LiveClock& default_clock();

 private:
  Outcome apply(const Request& r);
  void advance();
  void publish();
  void publish_run_info();
  void restart();
  void diverge(const std::string& what);
  std::optional<LiveClock::time_point> pace();
  void notice_clock_going_back();
  void take_load_command();
  bool running() const { return !paused_ && !finished_ && !diverged_; }
  std::string state_name() const;
  WindowRange make_window() const;
  void take_spectrum_sample(std::int64_t n);
  void report_window_forces();
  LiveSample sample() const;
  void log(LiveLogLevel level, const std::string& line) { sink_.log(level, line); }
  void loop();
  void wait_for_clock(std::unique_lock<std::mutex>& lock, LiveClock::time_point until);

  // Fixed after construction.
  const ModelConfig config_;
  const SimulatorSettings settings_;
  LiveSink& sink_;
  const LiveClock& clock_;
  const LoadInput load_input_;
  const std::int64_t end_step_;  // 0 = run on forever
  const SpectrumSampling spectrum_;
  const GearPair gear_;  // for f_m of the spectrum samples

  // Owned by the stepping loop.
  const std::unique_ptr<LiveModel> model_;
  RealizationBase& realization_;  // *model_'s
  double real_time_factor_, publish_rate_;
  std::int64_t period_;  // grid steps per publish period
  WindowRange window_;   // trailing-window ranges for the center distance d(t)
  SampleRing spectrum_samples_;
  std::int64_t next_sample_, next_update_;  // grid steps; never reached without the spectrum topic
  // The bearings model's window sums of a finite run, from grid step forces_from_ (never reached
  // otherwise) to t_end.
  std::optional<BearingForceSums> forces_;
  std::int64_t forces_from_;
  bool paused_, finished_ = false, diverged_ = false;
  std::string divergence_;
  bool anchored_ = false;  // pacing restarts from (anchor_wall_, anchor_step_) when false
  LiveClock::time_point anchor_wall_, last_now_;
  std::int64_t anchor_step_ = 0;
  std::optional<double> load_applied_;  // the command in effect (external modes)
  Status local_;
  Outcome last_outcome_;

  // Shared between threads under mutex_.
  mutable std::mutex mutex_;
  std::condition_variable wake_;  // the loop waits here (pacing, idle)
  std::condition_variable done_;  // request() waits here
  Request pending_;
  bool has_pending_ = false;
  std::uint64_t requested_ = 0, applied_ = 0;
  Outcome outcome_;
  Status status_;
  std::optional<std::pair<double, double>> load_command_;  // (value, stamp)
  std::atomic<bool> load_pending_{false};
  std::atomic<bool> stop_{false};
  std::thread thread_;
};

}  // namespace gear_dynamics
