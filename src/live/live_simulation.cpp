#include "gear_dynamics/live/live_simulation.hpp"

#include <algorithm>
#include <cmath>
#include <cstdarg>
#include <cstdio>
#include <limits>
#include <numeric>
#include <utility>

#include "gear_dynamics/config/batch_settings.hpp"
#include "gear_dynamics/engine/simulation.hpp"

namespace gear_dynamics {

namespace {

std::string seconds(double t) {
  char text[32];
  std::snprintf(text, sizeof text, "%.9g s", t);
  return text;
}

std::string format(const char* fmt, ...) __attribute__((format(printf, 1, 2)));
std::string format(const char* fmt, ...) {
  char text[512];
  va_list args;
  va_start(args, fmt);
  std::vsnprintf(text, sizeof text, fmt, args);
  va_end(args);
  return text;
}

LaneSpec lane_of(const ModelConfig& c, const SimulatorSettings& s, LoadInput input) {
  LaneSpec lane = s.deterministic ? deterministic_lane(c, c.friction_coefficient)
                                  : stochastic_lane(c, c.friction_coefficient, s.realization);
  if (input == LoadInput::External) {  // Phi(0) of load.yaml's mean, then only the commands
    lane.sigma = lane.drift = lane.load_sd = 0.0;
  }
  return lane;
}

// The torsional model: Realization, the SIMD kernel's arithmetic one lane at a time.
class TorsionalLive final : public LiveModel {
 public:
  TorsionalLive(const GearPair& gear, double h, const InitialState& initial, const LaneSpec& lane, std::uint64_t seed)
      : r_(gear, h, initial, lane, seed) {}
  RealizationBase& realization() override { return r_; }
  const RealizationBase& realization() const override { return r_; }
  void step() override { r_.step(); }
  void reset() override { r_.reset(); }
  double deflection() const override { return r_.delta(); }
  double deflection_rate() const override { return r_.velocity(); }
  double mesh_force() const override {
    const double t = r_.time();
    return gear_dynamics::mesh_force(r_.gear(), r_.mesh().stiffness(t), r_.delta(), r_.velocity(),
                                     r_.mesh().transmission_error(t), r_.mesh().transmission_error_rate(t));
  }
  void describe(LiveSample& s) const override {
    s.delta = s.delta_t = r_.delta();
    s.delta_dot = s.delta_t_dot = r_.velocity();
  }

 private:
  Realization r_;
};

// The bearings model: BearingsRealization, bearings_step as in the batch's lanes.
class BearingsLive final : public LiveModel {
 public:
  BearingsLive(const GearPair& gear, double h, const InitialState& initial, const LaneSpec& lane, std::uint64_t seed)
      : r_(gear, h, initial, lane, seed) {}
  RealizationBase& realization() override { return r_; }
  const RealizationBase& realization() const override { return r_; }
  void step() override { r_.step(); }
  void reset() override { r_.reset(); }
  double deflection() const override { return r_.model().deflection(r_.state()); }
  double deflection_rate() const override { return r_.model().deflection_rate(r_.state()); }
  double mesh_force() const override { return r_.outputs().mesh_force; }
  void describe(LiveSample& s) const override {
    const BearingsOutputs o = r_.outputs();
    s.delta = o.delta_m;
    s.delta_dot = o.delta_m_dot;
    s.delta_t = r_.state()[BearingsModel::kDelta];
    s.delta_t_dot = r_.state()[BearingsModel::kDeltaDot];
    s.bearings = o;
  }
  std::optional<BearingsOutputs> bearings() const override { return r_.outputs(); }

 private:
  BearingsRealization r_;
};

}  // namespace

std::unique_ptr<LiveModel> make_live_model(const GearPair& gear, double time_step, const InitialState& initial,
                                           const LaneSpec& lane, std::uint64_t seed) {
  switch (gear.in.model) {
    case GearModel::kBearings: return std::make_unique<BearingsLive>(gear, time_step, initial, lane, seed);
    case GearModel::kTorsional: break;
  }
  return std::make_unique<TorsionalLive>(gear, time_step, initial, lane, seed);
}

LoadInput load_input_from_string(const std::string& name) {
  if (name == "sde") return LoadInput::Sde;
  if (name == "external") return LoadInput::External;
  if (name == "external_plus_noise") return LoadInput::ExternalPlusNoise;
  throw ConfigError("invalid configuration: simulator.load_input = '" + name +
                    "' is not one of sde, external, external_plus_noise");
}

std::string to_string(LoadInput mode) {
  switch (mode) {
    case LoadInput::External: return "external";
    case LoadInput::ExternalPlusNoise: return "external_plus_noise";
    default: return "sde";
  }
}

void SampleRing::copy_to(std::vector<double>& delta, std::vector<double>& force) const {
  const std::size_t first = size_ < delta_.size() ? 0 : next_;  // the oldest sample
  delta.resize(size_);
  force.resize(size_);
  const std::size_t tail = std::min(size_, delta_.size() - first);
  std::copy_n(delta_.begin() + first, tail, delta.begin());
  std::copy_n(force_.begin() + first, tail, force.begin());
  std::copy_n(delta_.begin(), size_ - tail, delta.begin() + tail);
  std::copy_n(force_.begin(), size_ - tail, force.begin() + tail);
}

const LiveClock& LiveSimulation::default_clock() {
  static const SteadyLiveClock clock;
  return clock;
}

LiveSimulation::LiveSimulation(const ModelConfig& config, const SimulatorSettings& settings, LiveSink& sink,
                               const LiveClock& clock)
    : config_(config),
      settings_(settings),
      sink_(sink),
      clock_(clock),
      load_input_(load_input_from_string(settings.load_input)),
      end_step_(config.run.steps_for(settings.t_end)),
      spectrum_(spectrum_sampling(settings, config.run.time_step)),
      gear_(derive(config.gear)),
      model_(make_live_model(gear_, config.run.time_step, config.initial, lane_of(config, settings, load_input_),
                             config.seed)),
      realization_(model_->realization()),
      real_time_factor_(settings.real_time_factor),
      publish_rate_(settings.publish_rate),
      period_(publish_period_steps(publish_rate_, config.run.time_step)),
      window_(make_window()),
      spectrum_samples_(spectrum_.enabled() ? static_cast<std::size_t>(spectrum_.window_samples) : 0),
      forces_from_(std::numeric_limits<std::int64_t>::max()),
      paused_(settings.paused) {
  // The window of simulate(): the grid points from T - W to T, both included.
  if (gear_.in.model == GearModel::kBearings && end_step_ > 0) {
    forces_.emplace(1);
    forces_from_ = end_step_ - config.run.steps_for(config.run.window);
  }
  restart();
  local_.state = state_name();
  status_ = local_;
}

LiveSimulation::~LiveSimulation() { stop(); }

// ---- any thread ----

void LiveSimulation::post(const Request& r) {
  std::lock_guard<std::mutex> lock(mutex_);
  const auto take = [](auto& to, const auto& from) {
    if (from) to = from;
  };
  take(pending_.mu, r.mu);
  take(pending_.sigma, r.sigma);
  take(pending_.drift, r.drift);
  take(pending_.real_time_factor, r.real_time_factor);
  take(pending_.publish_rate, r.publish_rate);
  take(pending_.paused, r.paused);
  pending_.reset = pending_.reset || r.reset;
  pending_.step = pending_.step || r.step;
  has_pending_ = true;
  ++requested_;
  wake_.notify_all();
}

LiveSimulation::Outcome LiveSimulation::request(const Request& r) {
  post(r);
  std::unique_lock<std::mutex> lock(mutex_);
  const std::uint64_t id = requested_;
  done_.wait(lock, [&] { return applied_ >= id || stop_; });
  return applied_ >= id ? outcome_ : Outcome{false, "shutting down"};
}

void LiveSimulation::command_load(double value, double stamp) {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    load_command_ = std::make_pair(value, stamp);
  }
  load_pending_.store(true, std::memory_order_release);
}

LiveSimulation::Status LiveSimulation::status() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return status_;
}

LiveSimulation::Outcome LiveSimulation::last_outcome() const { return last_outcome_; }

// ---- the loop ----

void LiveSimulation::start() {
  if (thread_.joinable()) return;
  stop_ = false;
  thread_ = std::thread(&LiveSimulation::loop, this);
}

void LiveSimulation::stop() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stop_ = true;
  }
  wake_.notify_all();
  done_.notify_all();
  if (thread_.joinable()) thread_.join();
}

void LiveSimulation::loop() {
  while (!stop_) {
    const auto start = std::chrono::steady_clock::now();
    const Next next = iterate();
    // About to wait, or this iteration alone took a while (a low publish rate without pacing): the
    // sink's held messages go out now, not one publish period late.
    if (!next.running || next.until || std::chrono::steady_clock::now() - start >= kMinWait) sink_.flush();
    std::unique_lock<std::mutex> lock(mutex_);
    if (next.running) {
      if (next.until) wait_for_clock(lock, *next.until);
      local_.running_wall += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
      status_.running_wall = local_.running_wall;
    } else {
      lock.unlock();
      sink_.idle(sample());
      lock.lock();
      wake_.wait_for(lock, kIdlePeriod, [&] { return has_pending_ || stop_; });
    }
  }
  sink_.flush();
}

void LiveSimulation::wait_for_clock(std::unique_lock<std::mutex>& lock, LiveClock::time_point until) {
  const auto woken = [&] { return has_pending_ || stop_.load(); };
  if (clock_.steady()) {
    wake_.wait_until(lock, until, woken);
    return;
  }
  // Another node's time: it may stand still (paused) or go back (reset), so it is read again
  // every slice; going back ends the wait and pace() starts again from the present.
  for (auto before = clock_.now(); !woken();) {
    const auto now = clock_.now();
    if (now >= until || now < before) return;
    before = now;
    wake_.wait_for(lock, kFollowSlice, woken);
  }
}

LiveSimulation::Next LiveSimulation::iterate() {
  Request r;
  std::uint64_t batch;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    r = std::exchange(pending_, Request{});
    has_pending_ = false;
    batch = requested_;
  }
  Outcome outcome = apply(r);
  notice_clock_going_back();
  const bool stepping = r.step && outcome.ok;
  if (running() || stepping) advance();
  if (stepping)
    outcome = diverged_ ? Outcome{false, divergence_} : Outcome{true, "t = " + seconds(realization_.time())};
  const LaneSpec& lane = realization_.lane();
  local_.time = realization_.time();
  local_.state = state_name();
  local_.divergence = divergence_;
  local_.mu = lane.mu;
  local_.sigma = lane.sigma;
  local_.drift = lane.drift;
  local_.real_time_factor = real_time_factor_;
  local_.publish_rate = 1.0 / (static_cast<double>(period_) * config_.run.time_step);
  last_outcome_ = outcome;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    applied_ = batch;
    outcome_ = outcome;
    status_ = local_;
  }
  done_.notify_all();
  Next next;
  next.running = running();
  if (next.running) next.until = pace();
  else anchored_ = false;
  return next;
}

LiveSimulation::Outcome LiveSimulation::apply(const Request& r) {
  if (!r.mu && !r.sigma && !r.drift && !r.real_time_factor && !r.publish_rate && !r.paused && !r.reset && !r.step)
    return Outcome{};  // the usual case: nothing asked
  const double t = realization_.time();
  const auto n = static_cast<long long>(realization_.step_index());
  const auto changed = [&](const char* name, double from, double to, const char* unit) {
    log(LiveLogLevel::Info, format("%s: %g -> %g%s from t = %.9g s (step %lld)", name, from, to, unit, t, n));
  };
  const LaneSpec& lane = realization_.lane();
  Request q = r;
  // Without a load SDE there is no noise to set: the deterministic load S1 and the external load.
  const bool no_noise = settings_.deterministic || load_input_ == LoadInput::External;
  if (no_noise && ((q.sigma && *q.sigma != 0.0) || (q.drift && *q.drift != 0.0))) {
    log(LiveLogLevel::Warn, settings_.deterministic
                                ? "sigma and lambda stay 0 with the deterministic load (simulator.deterministic: true)"
                                : "sigma and lambda stay 0 with the external load (simulator.load_input: external)");
    q.sigma.reset();
    q.drift.reset();
  }
  if (q.mu) {
    changed("mu", lane.mu, *q.mu, "");
    realization_.set_mu(*q.mu);
  }
  if (q.sigma) {
    changed("sigma", lane.sigma, *q.sigma, " m/s^2/sqrt(s)");
    realization_.set_sigma(*q.sigma);
  }
  if (q.drift) {
    changed("lambda", lane.drift, *q.drift, " m/s^3");
    realization_.set_drift(*q.drift);
  }
  if (q.real_time_factor) {
    changed("real_time_factor", real_time_factor_, *q.real_time_factor, " (0 = as fast as possible)");
    real_time_factor_ = *q.real_time_factor;
    anchored_ = false;
  }
  if (q.publish_rate) {
    const double before = 1.0 / (static_cast<double>(period_) * config_.run.time_step);
    publish_rate_ = *q.publish_rate;
    period_ = publish_period_steps(publish_rate_, config_.run.time_step);
    const double effective = 1.0 / (static_cast<double>(period_) * config_.run.time_step);
    changed("publish_rate", before, effective, " Hz simulated");
    if (period_ % window_.block_steps() != 0)
      log(LiveLogLevel::Info,
          format("center_distance windows may start up to %lld steps early until ~reset (block of the "
                 "trailing-window observer)",
                 static_cast<long long>(window_.block_steps() - 1)));
  }
  if (q.reset) {
    log(LiveLogLevel::Info, "reset: t = 0, initial state, random stream from its start");
    restart();
  } else if (q.mu || q.sigma || q.drift || q.real_time_factor || q.publish_rate) {
    publish_run_info();
  }

  Outcome out;
  const auto refuse = [&](const std::string& why) {
    log(LiveLogLevel::Warn, why);
    out = Outcome{false, why};
  };
  // Built only when refused: apply() runs at every publish instant, mostly with nothing to apply.
  const auto at_end = [&] { return "the run is at t_end = " + seconds(settings_.t_end) + "; call ~reset to run again"; };
  const auto blew_up = [&] { return "the run diverged (" + divergence_ + "); call ~reset to start over"; };
  if (q.paused) {
    if (*q.paused) {
      if (!paused_) log(LiveLogLevel::Info, format("paused at t = %.9g s", realization_.time()));
      paused_ = true;
    } else if (diverged_) {
      refuse(blew_up());
    } else if (finished_) {
      refuse(at_end());
    } else {
      if (paused_) log(LiveLogLevel::Info, format("running from t = %.9g s", realization_.time()));
      paused_ = false;
    }
  }
  if (q.step) {
    if (diverged_) refuse(blew_up());
    else if (finished_) refuse(at_end());
    else if (!paused_) refuse("~step works while paused; call ~pause first");
  }
  return out;
}

void LiveSimulation::take_load_command() {
  load_pending_.store(false, std::memory_order_relaxed);
  std::optional<std::pair<double, double>> c;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    c = std::exchange(load_command_, std::nullopt);
  }
  if (!c || load_input_ == LoadInput::Sde) return;
  const auto [value, stamp] = *c;
  if (!std::isfinite(value)) {
    log(LiveLogLevel::Warn, format("load command %g is not finite: ignored (stamp %.9f s)", value, stamp));
    return;
  }
  const double phi = realization_.load();
  const double next = load_input_ == LoadInput::External || !load_applied_ ? value : phi + (value - *load_applied_);
  const bool first = !load_applied_;
  load_applied_ = value;
  realization_.set_load(next);
  ++local_.load_commands;
  log(first ? LiveLogLevel::Info : LiveLogLevel::Debug,
      format("load command %g m/s^2 (stamp %.9f s) in effect from step %lld (t = %.9g s): Phi = %.17g m/s^2",
             value, stamp, static_cast<long long>(realization_.step_index()), realization_.time(), next));
}

void LiveSimulation::advance() {
  const std::int64_t from = realization_.step_index();
  std::int64_t to = (from / period_ + 1) * period_;
  if (end_step_ > 0) to = std::min(to, end_step_);
  // The trailing-window observer fused into the loop: each step's extrema fold into four scalars,
  // merged into window_ at the end of every block of the observer and at the end (the same
  // maxima as observing step by step, WindowRange::observe_extrema).
  constexpr double kInf = std::numeric_limits<double>::infinity();
  const std::int64_t block = window_.block_steps();
  double hi_d = -kInf, lo_d = -kInf, hi_v = -kInf, lo_v = -kInf;  // lo: max of the negated values
  std::int64_t n = from;
  std::int64_t block_end = ((from + 1) / block + 1) * block;  // the block after that of step from + 1
  bool folded = false;  // steps folded in since the last merge
  const auto flush = [&] {
    window_.observe_extrema(n, hi_d, lo_d, hi_v, lo_v);
    hi_d = lo_d = hi_v = lo_v = -kInf;
    folded = false;
  };
  try {
    while (n < to) {
      if (stop_.load(std::memory_order_relaxed)) break;
      if (load_pending_.load(std::memory_order_acquire)) take_load_command();
      model_->step();
      n = realization_.step_index();
      if (n == next_sample_) take_spectrum_sample(n);
      if (n >= forces_from_) forces_->observe([&](int) { return *model_->bearings(); });
      const double d = model_->deflection(), v = model_->deflection_rate();
      hi_d = std::max(hi_d, d);
      lo_d = std::max(lo_d, -d);
      hi_v = std::max(hi_v, v);
      lo_v = std::max(lo_v, -v);
      folded = true;
      if (n + 1 == block_end) {
        flush();
        block_end += block;
      }
    }
  } catch (const DivergenceError& e) {
    local_.steps += realization_.step_index() - from;
    diverge(e.what());
    return;
  }
  if (folded) flush();  // the steps of a block not finished yet
  if (n < to) return;  // stopped
  local_.steps += to - from;
  publish();
  if (to == end_step_ && !diverged_) {
    if (forces_) report_window_forces();
    if (settings_.loop) {
      log(LiveLogLevel::Info, format("t_end = %g s reached: starting over", settings_.t_end));
      restart();
    } else {
      log(LiveLogLevel::Info, format("t_end = %g s reached: stopped (~reset runs again)", settings_.t_end));
      finished_ = true;
      // The final state is latched: it carries d(t_end) even when no one wanted the published ones.
      LiveSample last = sample();
      last.center_distance = window_.center_distance(0);
      sink_.finished(last);
    }
  }
}

LiveSample LiveSimulation::sample() const {
  const RealizationBase& e = realization_;
  LiveSample s;
  s.step = e.step_index();
  const auto due = anchored_ && real_time_factor_ > 0.0
                       ? anchor_wall_ + std::chrono::round<LiveClock::time_point::duration>(std::chrono::duration<double>(
                                            static_cast<double>(s.step - anchor_step_) * config_.run.time_step /
                                            real_time_factor_))
                       : clock_.now();
  s.clock_time = std::chrono::duration<double>(due.time_since_epoch()).count();
  s.t = grid_time(s.step, e.time_step());
  model_->describe(s);
  s.phi = e.load();
  s.mesh_stiffness = e.mesh().stiffness(e.time());
  s.mesh_phase = e.mesh().phase(e.time());
  s.mu = e.lane().mu;
  s.sigma = e.lane().sigma;
  s.drift = e.lane().drift;
  s.realization = e.lane().realization;
  s.seed = e.seed();
  return s;
}

void LiveSimulation::take_spectrum_sample(std::int64_t n) {
  const RealizationBase& e = realization_;
  spectrum_samples_.push(model_->deflection(), model_->mesh_force());
  next_sample_ += spectrum_.sample_steps;
  if (n != next_update_) return;
  next_update_ += spectrum_.update_steps;
  if (spectrum_samples_.size() < static_cast<std::size_t>(spectrum_.segment_samples)) return;
  SpectrumSamples w;
  w.step = n;
  w.t = grid_time(n, e.time_step());
  w.window_start =
      grid_time(n - static_cast<std::int64_t>(spectrum_samples_.size() - 1) * spectrum_.sample_steps, e.time_step());
  w.sample_rate = spectrum_.sample_rate;
  w.mesh_frequency = gear_.mesh_frequency();
  w.last = n == end_step_ && !settings_.loop;
  w.samples = &spectrum_samples_;
  sink_.spectrum(w);
}

void LiveSimulation::report_window_forces() {
  const LaneSpec& lane = realization_.lane();
  LiveWindowForces w;
  w.run_name = settings_.deterministic ? s1_run_label(lane.mu) : realization_run_label(lane.mu, lane.realization);
  w.t = settings_.t_end;
  w.window_start = forces_from_ >= 0 ? settings_.t_end - config_.run.window : 0.0;  // the batch's T - W
  w.forces = forces_->result();
  sink_.window_forces(w, sample());
}

void LiveSimulation::publish() {
  LiveSample s = sample();
  if (sink_.wants_center_distance()) s.center_distance = window_.center_distance(0);
  if (!std::isfinite(s.delta) || !std::isfinite(s.delta_dot) || !std::isfinite(s.phi) ||
      !std::isfinite(s.center_distance)) {
    diverge("non-finite state at t = " + seconds(s.t) + ": delta = " + std::to_string(s.delta) +
            " m, delta_dot = " + std::to_string(s.delta_dot) + " m/s, Phi = " + std::to_string(s.phi) + " m/s^2");
    return;
  }
  sink_.publish(s);
  ++local_.publications;
}

void LiveSimulation::publish_run_info() {
  const LaneSpec& lane = realization_.lane();
  LiveRunInfo info;
  info.step = realization_.step_index();
  info.t = realization_.time();
  info.config = config_;
  info.config.friction_coefficient = lane.mu;
  if (!settings_.deterministic && load_input_ != LoadInput::External) {  // S1 ignores the load noise settings
    info.config.load.sigma = lane.sigma;
    info.config.load.drift = lane.drift;
  }
  info.settings = settings_;
  info.settings.real_time_factor = real_time_factor_;
  info.settings.publish_rate = publish_rate_;
  info.lane = lane;
  info.load_input = load_input_;
  sink_.run_info(info);
}

void LiveSimulation::restart() {
  model_->reset();
  window_ = make_window();
  window_.observe_extrema(0, model_->deflection(), -model_->deflection(), model_->deflection_rate(),
                          -model_->deflection_rate());
  finished_ = diverged_ = false;
  divergence_.clear();
  anchored_ = false;
  load_applied_.reset();
  // The spectrum's samples from t = 0 on: the first one now, at n = 0.
  constexpr std::int64_t kNever = std::numeric_limits<std::int64_t>::max();
  spectrum_samples_.clear();
  next_sample_ = next_update_ = spectrum_.enabled() ? 0 : kNever;
  if (spectrum_.enabled()) take_spectrum_sample(0);
  if (forces_) {
    forces_->clear();
    if (forces_from_ <= 0) forces_->observe([&](int) { return *model_->bearings(); });
  }
  publish_run_info();
  publish();
}

void LiveSimulation::diverge(const std::string& what) {
  log(LiveLogLevel::Error, what + "; simulation paused, nothing more is published; call ~reset to start over");
  diverged_ = true;
  paused_ = true;
  divergence_ = what;
}

void LiveSimulation::notice_clock_going_back() {
  if (!anchored_ || real_time_factor_ <= 0.0) return;
  const auto now = clock_.now();
  if (!(now < last_now_)) return;
  log(LiveLogLevel::Warn, format("the pacing clock went back by %.6g s (its owner was reset or its time jumped): "
                                 "pacing starts again from the clock's present, at t = %.9g s of this run",
                                 std::chrono::duration<double>(last_now_ - now).count(), realization_.time()));
  anchored_ = false;  // the states from here on are due in the clock's new time line
}

std::optional<LiveClock::time_point> LiveSimulation::pace() {
  if (real_time_factor_ <= 0.0) return std::nullopt;
  const auto now = clock_.now();
  last_now_ = now;
  // Rounded to the clock's tick, not truncated: 1000 steps of 1 us at factor 1 are 1 ms exactly,
  // whichever way the double product rounds.
  const auto target = anchor_wall_ + std::chrono::round<LiveClock::time_point::duration>(
                                         std::chrono::duration<double>(
                                             static_cast<double>(realization_.step_index() - anchor_step_) *
                                             config_.run.time_step / real_time_factor_));
  if (!anchored_ || now > target + kMaxLag) {
    anchor_wall_ = now;
    anchor_step_ = realization_.step_index();
    anchored_ = true;
    return std::nullopt;
  }
  if (target - now < kMinWait) return std::nullopt;  // close enough: step on, sleep later
  return target;
}

std::string LiveSimulation::state_name() const {
  if (diverged_) return "diverged";
  if (finished_) return "stopped at t_end";
  return paused_ ? "paused" : "running";
}

WindowRange LiveSimulation::make_window() const {
  // Blocks that make the window exact at every publish instant and at t_end (as simulate() does).
  const std::int64_t window = std::max<std::int64_t>(config_.run.steps_for(config_.run.window), 1);
  return WindowRange(1, window, std::gcd(std::gcd(window, period_), end_step_));
}

}  // namespace gear_dynamics
