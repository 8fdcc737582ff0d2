#include "gear_dynamics/ros/gear_simulator.hpp"

#include <rosgraph_msgs/Clock.h>
#include <std_msgs/Float64.h>

#include <cmath>
#include <cstdio>
#include <numeric>
#include <utility>
#include <vector>

#include "gear_dynamics/ros/conversions.hpp"

namespace gear_dynamics {

namespace {

// Outgoing queue per subscriber: one second of messages at the default rate, so a subscriber
// that stalls briefly while the node runs as fast as possible loses nothing.
constexpr uint32_t kQueue = 1000;
// Pacing does not burst to catch up a lag longer than this; it restarts from the present.
constexpr auto kMaxLag = std::chrono::milliseconds(100);
// While paused, /clock is republished this often so that sim-time nodes see the time.
constexpr auto kIdleClockPeriod = std::chrono::milliseconds(100);
// While running, /clock goes out at every publish instant but at most every 0.5 ms of wall time
// (as Gazebo throttles its clock): every sim-time node, this one included, wakes up for each
// /clock message. Real time at 1 kHz keeps every one.
constexpr auto kClockInterval = std::chrono::microseconds(500);

LaneSpec lane_of(const ModelConfig& c, const SimulatorSettings& s) {
  return s.deterministic ? deterministic_lane(c, c.friction_coefficient)
                         : stochastic_lane(c, c.friction_coefficient, s.realization);
}

SimulatorSettings load_settings(const ros::NodeHandle& nh, double time_step) {
  return parse_simulator_settings(yaml_from_parameters(nh, {"simulator"}), time_step);
}

std::string seconds(double t) {
  char text[32];
  std::snprintf(text, sizeof text, "%.9g s", t);
  return text;
}

void publish_scalar(const ros::Publisher& pub, double value) {
  if (pub.getNumSubscribers() == 0) return;
  std_msgs::Float64 m;
  m.data = value;
  pub.publish(m);
}

// Simulator.cfg's double parameters (all of them) as (name, field), from the generated description.
std::vector<std::pair<std::string, double SimulatorConfig::*>> double_parameters() {
  std::vector<std::pair<std::string, double SimulatorConfig::*>> out;
  for (const auto& p : SimulatorConfig::__getParamDescriptions__())
    if (const auto* d = dynamic_cast<const SimulatorConfig::ParamDescription<double>*>(p.get()))
      out.emplace_back(d->name, d->field);
  return out;
}

}  // namespace

void ClampLoggedConfig::__clamp__() {
  const SimulatorConfig requested = *this;
  SimulatorConfig::__clamp__();
  for (const auto& [name, field] : double_parameters()) {
    const double asked = requested.*field, used = this->*field;
    if (asked != used && !std::isnan(asked))
      ROS_WARN("dynamic_reconfigure: %s = %g is out of range [%g, %g]; clamped to %g", name.c_str(), asked,
               __getMin__().*field, __getMax__().*field, used);
  }
}

GearSimulator::GearSimulator(const ros::NodeHandle& nh, const ros::NodeHandle& private_nh)
    : nh_(nh),
      private_nh_(private_nh),
      config_(load_model_config(private_nh)),
      settings_(load_settings(private_nh, config_.run.time_step)),
      end_step_(config_.run.steps_for(settings_.t_end)),
      ensemble_(derive(config_.gear), config_.run.time_step, config_.initial,
                {lane_of(config_, settings_)}, config_.seed),
      real_time_factor_(settings_.real_time_factor),
      publish_rate_(settings_.publish_rate),
      period_(publish_period_steps(publish_rate_, config_.run.time_step)),
      window_(make_window()),
      paused_(settings_.paused),
      reconfigure_server_(reconfigure_mutex_, private_nh),
      updater_(nh, private_nh) {
  state_pub_ = nh_.advertise<GearState>("state", kQueue);
  if (settings_.publish_scalars) {
    delta_pub_ = nh_.advertise<std_msgs::Float64>("delta", kQueue);
    delta_dot_pub_ = nh_.advertise<std_msgs::Float64>("delta_dot", kQueue);
    phi_pub_ = nh_.advertise<std_msgs::Float64>("phi", kQueue);
    center_distance_pub_ = nh_.advertise<std_msgs::Float64>("center_distance", kQueue);
  }
  if (settings_.publish_clock) clock_pub_ = nh_.advertise<rosgraph_msgs::Clock>("/clock", 10);
  run_info_pub_ = nh_.advertise<RunInfo>("run_info", 1, /*latch=*/true);
  pause_srv_ = private_nh_.advertiseService("pause", &GearSimulator::pause, this);
  unpause_srv_ = private_nh_.advertiseService("unpause", &GearSimulator::unpause, this);
  reset_srv_ = private_nh_.advertiseService("reset", &GearSimulator::reset, this);
  step_srv_ = private_nh_.advertiseService("step", &GearSimulator::step, this);

  // The first callback gets the values loaded from YAML, not the .cfg defaults.
  const LaneSpec& lane = ensemble_.lane(0);
  dynamic_.mu = lane.mu;
  dynamic_.sigma = lane.sigma;
  dynamic_.lambda = lane.drift;
  dynamic_.real_time_factor = real_time_factor_;
  dynamic_.publish_rate = publish_rate_;
  reconfigure_server_.updateConfig(dynamic_);
  reconfigure_server_.setCallback(
      [this](ClampLoggedConfig& config, uint32_t level) { reconfigure(config, level); });

  updater_.setHardwareID("none");
  updater_.add("simulation", this, &GearSimulator::diagnose);
  diagnostics_timer_ = nh_.createWallTimer(ros::WallDuration(1.0),
                                           [this](const ros::WallTimerEvent&) { updater_.force_update(); });

  const std::string load = settings_.deterministic
                               ? "the deterministic load S1"
                               : "stochastic realization " + std::to_string(settings_.realization);
  const std::string end = settings_.t_end == 0.0 ? "run on forever"
                          : settings_.loop       ? "loop at t_end = " + seconds(settings_.t_end)
                                                 : "stop at t_end = " + seconds(settings_.t_end);
  ROS_INFO("gear_simulator: %s, seed %llu, mu %g, sigma %g m/s^2/sqrt(s), lambda %g m/s^3, h = %s, %s; "
           "publishing every %lld steps (%g Hz simulated), real_time_factor %g%s",
           load.c_str(), static_cast<unsigned long long>(config_.seed), lane.mu, lane.sigma, lane.drift,
           seconds(config_.run.time_step).c_str(), end.c_str(), static_cast<long long>(period_),
           1.0 / (static_cast<double>(period_) * config_.run.time_step), real_time_factor_,
           paused_ ? ", paused" : "");
  thread_ = std::thread(&GearSimulator::run, this);
}

GearSimulator::~GearSimulator() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stop_ = true;
  }
  wake_.notify_all();
  done_.notify_all();
  if (thread_.joinable()) thread_.join();
}

// ---- callbacks ----

GearSimulator::Outcome GearSimulator::request(const Request& r) {
  std::unique_lock<std::mutex> lock(mutex_);
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
  const std::uint64_t id = ++requested_;
  wake_.notify_all();
  done_.wait(lock, [&] { return applied_ >= id || stop_; });
  return stop_ ? Outcome{false, "shutting down"} : outcome_;
}

void GearSimulator::reconfigure(SimulatorConfig& config, uint32_t /*level*/) {
  for (const auto& [name, field] : double_parameters()) {
    if (!std::isnan(config.*field)) continue;
    ROS_WARN("dynamic_reconfigure: %s = nan is not a number; keeping %g", name.c_str(), dynamic_.*field);
    config.*field = dynamic_.*field;
  }
  if (settings_.deterministic && (config.sigma != 0.0 || config.lambda != 0.0)) {
    ROS_WARN("sigma and lambda stay 0 with the deterministic load (simulator.deterministic: true)");
    config.sigma = 0.0;
    config.lambda = 0.0;
  }
  Request r;
  if (config.mu != dynamic_.mu) r.mu = config.mu;
  if (config.sigma != dynamic_.sigma) r.sigma = config.sigma;
  if (config.lambda != dynamic_.lambda) r.drift = config.lambda;
  if (config.real_time_factor != dynamic_.real_time_factor) r.real_time_factor = config.real_time_factor;
  if (config.publish_rate != dynamic_.publish_rate) r.publish_rate = config.publish_rate;
  dynamic_ = config;
  if (r.mu || r.sigma || r.drift || r.real_time_factor || r.publish_rate) request(r);
}

bool GearSimulator::pause(std_srvs::Empty::Request&, std_srvs::Empty::Response&) {
  Request r;
  r.paused = true;
  return request(r).ok;
}

bool GearSimulator::unpause(std_srvs::Empty::Request&, std_srvs::Empty::Response&) {
  Request r;
  r.paused = false;
  return request(r).ok;
}

bool GearSimulator::reset(std_srvs::Empty::Request&, std_srvs::Empty::Response&) {
  Request r;
  r.reset = true;
  return request(r).ok;
}

bool GearSimulator::step(std_srvs::Trigger::Request&, std_srvs::Trigger::Response& res) {
  Request r;
  r.step = true;
  const Outcome o = request(r);
  res.success = o.ok;
  res.message = o.message;
  return true;
}

void GearSimulator::diagnose(diagnostic_updater::DiagnosticStatusWrapper& stat) {
  Status s;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    s = status_;
  }
  const double wall = s.running_wall - last_diagnosis_.running_wall;
  const auto steps = static_cast<double>(s.steps - last_diagnosis_.steps);
  const auto publications = static_cast<double>(s.publications - last_diagnosis_.publications);
  last_diagnosis_ = s;
  const double rtf = wall > 0.0 ? steps * config_.run.time_step / wall : 0.0;

  using diagnostic_msgs::DiagnosticStatus;
  if (!s.divergence.empty()) {
    stat.summary(DiagnosticStatus::ERROR, "diverged: " + s.divergence);
  } else if (s.state == "running" && s.real_time_factor > 0.0 && wall > 0.5 &&
             rtf < 0.9 * s.real_time_factor) {
    stat.summaryf(DiagnosticStatus::WARN, "running slower than requested: real-time factor %.3g of %.3g",
                  rtf, s.real_time_factor);
  } else {
    stat.summary(DiagnosticStatus::OK, s.state);
  }
  stat.add("simulated time [s]", s.time);
  stat.add("achieved real-time factor", rtf);
  stat.add("requested real-time factor (0 = as fast as possible)", s.real_time_factor);
  stat.add("integration steps per wall second", wall > 0.0 ? steps / wall : 0.0);
  stat.add("publish rate [Hz simulated]", s.publish_rate);
  stat.add("publish rate [Hz wall]", wall > 0.0 ? publications / wall : 0.0);
  stat.add("mu", s.mu);
  stat.add("sigma [m/s^2/sqrt(s)]", s.sigma);
  stat.add("lambda [m/s^3]", s.drift);
}

// ---- stepping thread ----

void GearSimulator::run() {
  restart();
  while (!stop_) {
    Request r;
    std::uint64_t batch;
    {
      std::lock_guard<std::mutex> lock(mutex_);
      r = std::exchange(pending_, Request{});
      has_pending_ = false;
      batch = requested_;
    }
    Outcome outcome = apply(r);
    const auto start = WallClock::now();
    const bool stepping = r.step && outcome.ok;
    if (running() || stepping) advance();
    if (stepping) {
      outcome = diverged_ ? Outcome{false, divergence_} : Outcome{true, "t = " + seconds(ensemble_.time())};
    }
    const LaneSpec& lane = ensemble_.lane(0);
    local_.time = ensemble_.time();
    local_.state = state_name();
    local_.mu = lane.mu;
    local_.sigma = lane.sigma;
    local_.drift = lane.drift;
    local_.real_time_factor = real_time_factor_;
    local_.publish_rate = 1.0 / (static_cast<double>(period_) * config_.run.time_step);
    {
      std::lock_guard<std::mutex> lock(mutex_);
      applied_ = batch;
      outcome_ = outcome;
      status_ = local_;
    }
    done_.notify_all();
    if (running()) {
      pace();
      local_.running_wall += std::chrono::duration<double>(WallClock::now() - start).count();
    } else {
      anchored_ = false;
      idle();
    }
  }
}

GearSimulator::Outcome GearSimulator::apply(const Request& r) {
  const double t = ensemble_.time();
  const auto n = static_cast<long long>(ensemble_.step_index());
  const auto changed = [&](const char* name, double from, double to, const char* unit) {
    ROS_INFO("%s: %g -> %g%s from t = %.9g s (step %lld)", name, from, to, unit, t, n);
  };
  const LaneSpec& lane = ensemble_.lane(0);
  if (r.mu) {
    changed("mu", lane.mu, *r.mu, "");
    ensemble_.set_mu(0, *r.mu);
  }
  if (r.sigma) {
    changed("sigma", lane.sigma, *r.sigma, " m/s^2/sqrt(s)");
    ensemble_.set_sigma(0, *r.sigma);
  }
  if (r.drift) {
    changed("lambda", lane.drift, *r.drift, " m/s^3");
    ensemble_.set_drift(0, *r.drift);
  }
  if (r.real_time_factor) {
    changed("real_time_factor", real_time_factor_, *r.real_time_factor, " (0 = as fast as possible)");
    real_time_factor_ = *r.real_time_factor;
    anchored_ = false;
  }
  if (r.publish_rate) {
    publish_rate_ = *r.publish_rate;
    period_ = publish_period_steps(publish_rate_, config_.run.time_step);
    const double effective = 1.0 / (static_cast<double>(period_) * config_.run.time_step);
    changed("publish_rate", local_.publish_rate, effective, " Hz simulated");
    if (period_ % window_.block_steps() != 0)
      ROS_INFO("center_distance windows may start up to %lld steps early until ~reset (block of the "
               "trailing-window observer)", static_cast<long long>(window_.block_steps() - 1));
  }
  if (r.reset) {
    ROS_INFO("reset: t = 0, initial state, random stream from its start");
    restart();
  } else if (r.mu || r.sigma || r.drift || r.real_time_factor || r.publish_rate) {
    publish_run_info();
  }

  Outcome out;
  const auto refuse = [&](const std::string& why) {
    ROS_WARN("%s", why.c_str());
    out = Outcome{false, why};
  };
  const std::string at_end =
      "the run is at t_end = " + seconds(settings_.t_end) + "; call ~reset to run again";
  const std::string blew_up = "the run diverged (" + divergence_ + "); call ~reset to start over";
  if (r.paused) {
    if (*r.paused) {
      if (!paused_) ROS_INFO("paused at t = %.9g s", ensemble_.time());
      paused_ = true;
    } else if (diverged_) {
      refuse(blew_up);
    } else if (finished_) {
      refuse(at_end);
    } else {
      if (paused_) ROS_INFO("running from t = %.9g s", ensemble_.time());
      paused_ = false;
    }
  }
  if (r.step) {
    if (diverged_) refuse(blew_up);
    else if (finished_) refuse(at_end);
    else if (!paused_) refuse("~step works while paused; call ~pause first");
  }
  return out;
}

void GearSimulator::advance() {
  const std::int64_t from = ensemble_.step_index();
  std::int64_t to = (from / period_ + 1) * period_;
  if (end_step_ > 0) to = std::min(to, end_step_);
  try {
    while (ensemble_.step_index() < to) {
      if (stop_.load(std::memory_order_relaxed)) return;
      ensemble_.step();
      window_.observe(ensemble_.step_index(), ensemble_.delta(), ensemble_.velocity());
    }
  } catch (const DivergenceError& e) {
    local_.steps += ensemble_.step_index() - from;
    diverge(e.what());
    return;
  }
  local_.steps += to - from;
  publish();
  if (to == end_step_ && !diverged_) {
    if (settings_.loop) {
      ROS_INFO("t_end = %g s reached: starting over", settings_.t_end);
      restart();
    } else {
      ROS_INFO("t_end = %g s reached: stopped (~reset runs again)", settings_.t_end);
      finished_ = true;
    }
  }
}

void GearSimulator::publish() {
  const bool want_state = state_pub_.getNumSubscribers() > 0;
  const bool want_d =
      want_state || (settings_.publish_scalars && center_distance_pub_.getNumSubscribers() > 0);
  const GearState m = make_state(ensemble_, 0, want_d ? window_.center_distance()[0] : 0.0);
  if (!std::isfinite(m.delta) || !std::isfinite(m.delta_dot) || !std::isfinite(m.phi) ||
      !std::isfinite(m.center_distance)) {
    diverge("non-finite state at t = " + seconds(m.t) + ": delta = " + std::to_string(m.delta) +
            " m, delta_dot = " + std::to_string(m.delta_dot) + " m/s, Phi = " + std::to_string(m.phi) + " m/s^2");
    return;
  }
  publish_clock(false);
  if (want_state) state_pub_.publish(m);
  if (settings_.publish_scalars) {
    publish_scalar(delta_pub_, m.delta);
    publish_scalar(delta_dot_pub_, m.delta_dot);
    publish_scalar(phi_pub_, m.phi);
    publish_scalar(center_distance_pub_, m.center_distance);
  }
  ++local_.publications;
}

void GearSimulator::publish_clock(bool always) {
  const auto now = WallClock::now();
  if (!settings_.publish_clock || (!always && now - last_clock_ < kClockInterval)) return;
  last_clock_ = now;
  rosgraph_msgs::Clock c;
  c.clock = sim_stamp(ensemble_.time());
  clock_pub_.publish(c);
}

void GearSimulator::publish_run_info() {
  const LaneSpec& lane = ensemble_.lane(0);
  ModelConfig current = config_;
  current.friction_coefficient = lane.mu;
  if (!settings_.deterministic) {  // S1 ignores the load noise settings: keep them as loaded
    current.load.sigma = lane.sigma;
    current.load.drift = lane.drift;
  }
  RunInfo info = make_run_info(current, settings_.deterministic ? RunKind::S1 : RunKind::Stochastic,
                               static_cast<std::uint32_t>(lane.realization), lane.mu, lane.sigma,
                               settings_.t_end);
  info.header.stamp = sim_stamp(ensemble_.time());  // these values hold from here on
  SimulatorSettings now = settings_;
  now.real_time_factor = real_time_factor_;
  now.publish_rate = publish_rate_;
  YAML::Node all = to_yaml(current);
  all["simulator"] = to_yaml(now);
  YAML::Emitter out;
  out << all;
  info.parameters_yaml = out.c_str();
  run_info_pub_.publish(info);
}

void GearSimulator::restart() {
  ensemble_.reset();
  window_ = make_window();
  window_.observe(0, ensemble_.delta(), ensemble_.velocity());
  finished_ = diverged_ = false;
  divergence_.clear();
  local_.divergence.clear();
  anchored_ = false;
  publish_run_info();
  publish();
}

void GearSimulator::diverge(const std::string& what) {
  ROS_ERROR("%s; simulation paused, nothing more is published; call ~reset to start over", what.c_str());
  diverged_ = true;
  paused_ = true;
  divergence_ = what;
  local_.divergence = what;
}

void GearSimulator::pace() {
  if (real_time_factor_ <= 0.0) return;
  const auto now = WallClock::now();
  const auto target =
      anchor_wall_ + std::chrono::duration_cast<WallClock::duration>(std::chrono::duration<double>(
                         static_cast<double>(ensemble_.step_index() - anchor_step_) *
                         config_.run.time_step / real_time_factor_));
  if (!anchored_ || now > target + kMaxLag) {
    anchor_wall_ = now;
    anchor_step_ = ensemble_.step_index();
    anchored_ = true;
    return;
  }
  std::unique_lock<std::mutex> lock(mutex_);
  wake_.wait_until(lock, target, [&] { return has_pending_ || stop_; });
}

void GearSimulator::idle() {
  publish_clock(true);  // where time stands, at once and every kIdleClockPeriod
  std::unique_lock<std::mutex> lock(mutex_);
  wake_.wait_for(lock, kIdleClockPeriod, [&] { return has_pending_ || stop_; });
}

std::string GearSimulator::state_name() const {
  if (diverged_) return "diverged";
  if (finished_) return "stopped at t_end";
  return paused_ ? "paused" : "running";
}

WindowRange GearSimulator::make_window() const {
  // Blocks that make the window exact at every publish instant and at t_end (as simulate() does).
  const std::int64_t window = std::max<std::int64_t>(config_.run.steps_for(config_.run.window), 1);
  return WindowRange(1, window, std::gcd(std::gcd(window, period_), end_step_));
}

}  // namespace gear_dynamics
