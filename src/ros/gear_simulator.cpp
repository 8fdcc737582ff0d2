#include "gear_dynamics/ros/gear_simulator.hpp"

#include <rosgraph_msgs/Clock.h>
#include <std_msgs/Float64.h>

#include <cmath>
#include <cstdio>
#include <ctime>
#include <sys/stat.h>
#include <numeric>
#include <thread>
#include <utility>
#include <vector>

#include "gear_dynamics/engine/instruction_set.hpp"
#include "gear_dynamics/ros/conversions.hpp"
#include "gear_dynamics/ros/stop_signal.hpp"

namespace gear_dynamics {

namespace {

// Outgoing queue per subscriber: one second of messages at the default rate, so a subscriber
// that stalls briefly while the node runs as fast as possible loses nothing.
constexpr uint32_t kQueue = 1000;
// While running, /clock goes out at a publish instant at most every 5 ms of wall time (200 Hz, as
// Gazebo throttles its clock): every sim-time node, this one included, wakes up for each /clock
// message, and nothing needs it finer than the state stamps, which carry the exact time.
constexpr auto kClockInterval = std::chrono::milliseconds(5);
// Messages of one burst go out together (GearSimulator::flush): roscpp wakes its writer thread for
// the first and queues the rest while it sends, instead of a wake-up (pipe write, epoll, futex) per
// message. The loop flushes before every wait; without waits (real_time_factor 0, or a slow
// machine) a burst ends after this many publish instants or this much wall time.
constexpr std::size_t kBurst = 64;
constexpr auto kBurstWall = std::chrono::milliseconds(1);
// At real_time_factor 0 the messages sent to subscribers (state, state_batch, the Float64 topics)
// are paced to at most this many per wall second, in all and per topic: rosbag record queues 100
// messages per topic, so a topic at 2000/s survives a 50 ms stall of the recorder
// (doc/gear_simulator.md §3.2). Without subscribers: full speed.
constexpr double kFullSpeedMessageRate = 4000.0;
constexpr double kFullSpeedTopicRate = 2000.0;
// With an external load input: a running node that got no command for this long [wall s] says so
// (diagnostics WARN, one log line per silence); Phi stays held.
constexpr double kLoadCommandTimeout = 1.0;

SimulatorSettings load_settings(const ros::NodeHandle& nh, double time_step) {
  return parse_simulator_settings(yaml_from_parameters(nh, {"simulator"}), time_step);
}

std::string seconds(double t) {
  char text[32];
  std::snprintf(text, sizeof text, "%.9g s", t);
  return text;
}

// Simulator.cfg's double parameters (all of them) as (name, field), from the generated description.
std::vector<std::pair<std::string, double SimulatorConfig::*>> double_parameters() {
  std::vector<std::pair<std::string, double SimulatorConfig::*>> out;
  for (const auto& p : SimulatorConfig::__getParamDescriptions__())
    if (const auto* d = dynamic_cast<const SimulatorConfig::ParamDescription<double>*>(p.get()))
      out.emplace_back(d->name, d->field);
  return out;
}

// The two gears as joints (doc/gear_simulator.md §3.3): the pinion turns at the constant nominal
// speed, theta1 = phi0 + Omega t (doc/model.md D3), and the torsional coordinate
// delta_t = Rb1 theta1 - Rb2 theta2 (delta itself in the torsional model) gives the wheel's angle;
// positive theta2 turns the wheel the way the pinion drives it.
sensor_msgs::JointState make_joint_state(const LiveSample& s, const GearPair& g, const ros::Time& stamp) {
  sensor_msgs::JointState m;
  m.header.stamp = stamp;
  m.name = {"pinion_joint", "wheel_joint"};
  const double theta1 = g.in.mesh_phase + g.in.pinion_speed * s.t;
  m.position = {theta1, (g.base_radius1 * theta1 - s.delta_t) / g.base_radius2};
  m.velocity = {g.in.pinion_speed, (g.base_radius1 * g.in.pinion_speed - s.delta_t_dot) / g.base_radius2};
  return m;
}

}  // namespace

void RefusingConfig::__clamp__() {
  // One rule for a bad value, at start and at run time: refused. At start the node ends with a
  // FATAL (ConfigError); here the value in effect stays (NaN marks it for reconfigure()).
  refused.clear();
  for (const auto& [name, field] : double_parameters()) {
    const double asked = this->*field, lo = __getMin__().*field, hi = __getMax__().*field;
    if (asked >= lo && asked <= hi) continue;
    char why[160];
    if (std::isnan(asked))
      std::snprintf(why, sizeof why, "%s = nan is not a number", name.c_str());
    else
      std::snprintf(why, sizeof why, "%s = %g is out of range [%g, %g]", name.c_str(), asked, lo, hi);
    refused[name] = why;
    this->*field = std::nan("");
  }
}

GearSimulator::GearSimulator(const ros::NodeHandle& nh, const ros::NodeHandle& private_nh)
    : nh_(nh),
      private_nh_(private_nh),
      config_(load_model_config(private_nh)),
      gear_(derive(config_.gear)),
      settings_(load_settings(private_nh, config_.run.time_step)),
      reconfigure_server_(reconfigure_mutex_, private_nh),
      updater_(nh, private_nh) {
  // The normal generator's variant (the one-lane step is portable code); refuses a bad GEAR_DYNAMICS_ISA.
  ROS_INFO("gear_simulator: %s", instruction_set_description().c_str());
  state_ = CountedPublisher::advertise<GearState>(nh_, "state", kQueue);
  state_batch_ = CountedPublisher::advertise<GearStateBatch>(nh_, "state_batch", kQueue);
  joint_states_ = CountedPublisher::advertise<sensor_msgs::JointState>(nh_, "joint_states", kQueue);
  if (settings_.publish_scalars) {
    delta_ = CountedPublisher::advertise<std_msgs::Float64>(nh_, "delta", kQueue);
    delta_dot_ = CountedPublisher::advertise<std_msgs::Float64>(nh_, "delta_dot", kQueue);
    phi_ = CountedPublisher::advertise<std_msgs::Float64>(nh_, "phi", kQueue);
    center_distance_ = CountedPublisher::advertise<std_msgs::Float64>(nh_, "center_distance", kQueue);
  }
  if (gear_.in.model == GearModel::kBearings) {
    mesh_ = CountedPublisher::advertise<MeshState>(nh_, "mesh", kQueue);
    pinion_wrench_ = CountedPublisher::advertise<geometry_msgs::WrenchStamped>(nh_, "pinion_bearing/wrench", kQueue);
    wheel_wrench_ = CountedPublisher::advertise<geometry_msgs::WrenchStamped>(nh_, "wheel_bearing/wrench", kQueue);
    // The wrenches' frames follow the configured gear (alpha_w from pressure_angle and the profile
    // shifts): published here, latched, also without tf:=true, so not in the URDF (gear_pair_urdf).
    bearing_frames_msg_.transforms = make_bearing_frames(gear_, sim_stamp(0.0));
    bearing_frames_ = std::make_unique<tf2_ros::StaticTransformBroadcaster>();
    bearing_frames_->sendTransform(bearing_frames_msg_.transforms);
    ROS_INFO("gear_simulator: the bearings model: state's delta is delta_m; %s, %s and %s at every state, in the "
             "frames %s and %s (/tf_static, turned by -alpha_w = %g rad)",
             mesh_.topic.c_str(), pinion_wrench_.topic.c_str(), wheel_wrench_.topic.c_str(), kPinionBearingFrame,
             kWheelBearingFrame, -gear_.operating_pressure_angle);
  }
  if (settings_.publish_clock) clock_pub_ = nh_.advertise<rosgraph_msgs::Clock>("/clock", 10);
  run_info_pub_ = nh_.advertise<RunInfo>("run_info", 1, /*latch=*/true);
  // The last state of a finite run, for late subscribers (latched, published at t_end).
  final_state_pub_ = nh_.advertise<GearState>("final_state", 1, /*latch=*/true);
  // The bearings model's forces over the analysis window of a finite run, as the batch bags hold them.
  if (gear_.in.model == GearModel::kBearings && settings_.t_end > 0.0)
    bearing_summary_pub_ = nh_.advertise<BearingSummary>("bearing_summary", 1, /*latch=*/true);
  if (settings_.load_input != "sde")
    load_sub_ = nh_.subscribe("load_command", 100, &GearSimulator::load_command, this,
                              ros::TransportHints().tcpNoDelay());
  private_nh_.param<std::string>("record_prefix", record_prefix_, "");
  record_open();  // throws ConfigError when the bag cannot be opened

  const SpectrumSampling spectrum = spectrum_sampling(settings_, config_.run.time_step);
  if (spectrum.enabled()) spectrum_ = std::make_unique<SpectrumPublisher>(nh_, spectrum);
  held_.reserve(5 * kBurst + 5);
  batch_.states.reserve(kBurst + 2);
  held_joints_.reserve(kBurst + 2);
  held_bearings_.reserve(kBurst + 2);
  following_ = !settings_.publish_clock && ros::Time::isSimTime();
  if (following_)
    ROS_INFO("gear_simulator: publish_clock false under /use_sim_time: this node follows the clock owner's /clock "
             "(paced against it at real_time_factor > 0, its messages stamped in the owner's time; it waits while "
             "the owner is paused, and starts again from the owner's present when /clock goes back)");
  // Publishes t = 0 and the run info at once.
  // At real_time_factor 0 the run would be over before a recorder started first has found the
  // node: it starts paused and runs after simulator.subscriber_wait, its t = 0 state sent again then.
  hold_start_ = settings_.real_time_factor == 0.0 && !settings_.paused && settings_.subscriber_wait > 0.0;
  SimulatorSettings start = settings_;
  start.paused = start.paused || hold_start_;
  if (following_)
    sim_.emplace(config_, start, static_cast<LiveSink&>(*this), ros_clock_);
  else
    sim_.emplace(config_, start, static_cast<LiveSink&>(*this));

  pause_srv_ = private_nh_.advertiseService("pause", &GearSimulator::pause, this);
  unpause_srv_ = private_nh_.advertiseService("unpause", &GearSimulator::unpause, this);
  reset_srv_ = private_nh_.advertiseService("reset", &GearSimulator::reset, this);
  step_srv_ = private_nh_.advertiseService("step", &GearSimulator::step, this);

  // The first callback gets the values loaded from YAML, not the .cfg defaults.
  const LaneSpec& lane = sim_->realization().lane();
  dynamic_.mu = lane.mu;
  dynamic_.sigma = lane.sigma;
  dynamic_.lambda = lane.drift;
  dynamic_.real_time_factor = settings_.real_time_factor;
  dynamic_.publish_rate = settings_.publish_rate;
  reconfigure_server_.updateConfig(dynamic_);
  reconfigure_server_.setCallback(
      [this](RefusingConfig& config, uint32_t level) { reconfigure(config, level); });

  updater_.setHardwareID("none");
  updater_.add("simulation", this, &GearSimulator::diagnose);
  diagnostics_timer_ = nh_.createWallTimer(ros::WallDuration(1.0), [this](const ros::WallTimerEvent&) {
    updater_.force_update();
    if (settings_.publish_clock) check_clock_publishers();
    if (following_ && !ros::Time::isValid() && sim_ && sim_->real_time_factor() > 0.0)
      ROS_WARN_THROTTLE(10.0, "gear_simulator: no /clock yet: this node (publish_clock false) waits for the clock "
                              "owner's time; start a gear_simulator with publish_clock:=true, or run this one with "
                              "publish_clock:=true (or real_time_factor:=0)");
  });

  const std::string load = settings_.deterministic
                               ? "the deterministic load S1"
                               : "stochastic realization " + std::to_string(settings_.realization);
  const std::string end = settings_.t_end == 0.0 ? "run on forever"
                          : settings_.loop       ? "loop at t_end = " + seconds(settings_.t_end)
                                                 : "stop at t_end = " + seconds(settings_.t_end);
  const auto period = sim_->period_steps();
  ROS_INFO("gear_simulator: %s, seed %llu, mu %g, sigma %g m/s^2/sqrt(s), lambda %g m/s^3, h = %s, %s; "
           "publishing every %lld steps (%g Hz simulated), real_time_factor %g%s",
           load.c_str(), static_cast<unsigned long long>(config_.seed), lane.mu, lane.sigma, lane.drift,
           seconds(config_.run.time_step).c_str(), end.c_str(), static_cast<long long>(period),
           1.0 / (static_cast<double>(period) * config_.run.time_step), settings_.real_time_factor,
           settings_.paused ? ", paused" : "");
  if (spectrum.enabled()) {
    const double fs = spectrum.sample_rate;
    ROS_INFO("gear_simulator: spectrum every %g s of simulated time over the last %lld samples (%g s) of delta and "
             "the mesh force, taken every %lld steps (%g Hz, Nyquist %g Hz); Welch: Hann segments of %lld samples "
             "(resolution %g Hz), overlap %g; f_m = %g Hz",
             static_cast<double>(spectrum.update_steps) * config_.run.time_step,
             static_cast<long long>(spectrum.window_samples), static_cast<double>(spectrum.window_samples) / fs,
             static_cast<long long>(spectrum.sample_steps), fs, 0.5 * fs,
             static_cast<long long>(spectrum.segment_samples), fs / static_cast<double>(spectrum.segment_samples),
             spectrum.overlap, derive(config_.gear).mesh_frequency());
  }
  if (settings_.real_time_factor == 0.0) warn_full_speed();
  if (settings_.load_input != "sde")
    ROS_INFO("gear_simulator: load input '%s' from %s (std_msgs/Float64, m/s^2), applied at the next step",
             settings_.load_input.c_str(), load_sub_.getTopic().c_str());
  if (hold_start_) {
    ROS_INFO("gear_simulator: real_time_factor 0: holding at t = 0 for %g s (simulator.subscriber_wait) so that "
             "subscribers still discovering the node (rosbag record -a, started first) get the run from t = 0",
             settings_.subscriber_wait);
    waiting_ = true;
    subscriber_wait_timer_ = nh_.createWallTimer(
        ros::WallDuration(settings_.subscriber_wait),
        [this](const ros::WallTimerEvent&) {
          if (!waiting_.exchange(false)) return;  // a service call took over
          resend_start_ = true;
          Request r;
          r.paused = false;
          sim_->request(r);
        },
        /*oneshot=*/true);
  }
  sim_->start();
}

void GearSimulator::warn_full_speed() const {
  ROS_WARN("gear_simulator: real_time_factor 0: while %s, %s, joint_states or a Float64 topic has a subscriber, "
           "at most %g messages per wall second go out (rosbag record -a keeps up); a subscriber slower than that "
           "loses messages (roscpp drops its oldest; gaps in header.seq show it). Every state at full speed: subscribe "
           "to %s alone (up to %zu states per message), started before the node runs (paused:=true, then "
           "~unpause); or record:=true, the node's own bag",
           state_.topic.c_str(), state_batch_.topic.c_str(), kFullSpeedMessageRate, state_batch_.topic.c_str(),
           kBurst);
}

GearSimulator::~GearSimulator() {
  if (sim_) sim_->stop();
  if (sim_ && stop_signal() != 0)
    log_at_stop(StopLog::Info, std::string("gear_simulator: stopped by ") + stop_signal_name() + " at t = " +
                                   seconds(sim_->status().time));
  record_close();
}

// ---- recording ----

void GearSimulator::record_open() {
  if (record_prefix_.empty()) return;
  std::lock_guard<std::mutex> lock(record_mutex_);
  if (recorder_) return;
  char date[32];
  const std::time_t now = std::time(nullptr);
  std::strftime(date, sizeof date, "%Y-%m-%d-%H-%M-%S", std::localtime(&now));
  std::string path = record_prefix_ + "_" + date + ".bag";
  struct stat st {};
  for (int k = 2; ::stat(path.c_str(), &st) == 0 || ::stat((path + ".active").c_str(), &st) == 0; ++k)
    path = record_prefix_ + "_" + date + "_" + std::to_string(k) + ".bag";
  try {
    recorder_ = std::make_unique<LiveRecorder>(path);
  } catch (const std::exception& e) {
    throw ConfigError("record: cannot write " + path + ".active: " + e.what());
  }
  ROS_INFO("record: writing every published message into %s", path.c_str());
  // The frames of the bearing wrenches, so that the bag alone says where its forces point.
  if (!bearing_frames_msg_.transforms.empty()) recorder_->write("/tf_static", sim_stamp(0.0), bearing_frames_msg_);
}

void GearSimulator::record_close() {
  std::unique_ptr<LiveRecorder> r;
  {
    std::lock_guard<std::mutex> lock(record_mutex_);
    r = std::move(recorder_);
  }
  if (!r) return;
  r->close();
  std::lock_guard<std::mutex> lock(record_mutex_);
  bags_.push_back(r->path());
  recorded_ += r->written();
  lost_ += r->lost();
  if (record_error_.empty()) record_error_ = r->error();
}

template <class M>
void GearSimulator::record(const std::string& topic, const ros::Time& stamp, const M& msg) {
  if (record_prefix_.empty()) return;
  std::lock_guard<std::mutex> lock(record_mutex_);
  if (recorder_)
    recorder_->write(topic, stamp, msg);
  else
    ++lost_;  // the bag of this run could not be opened (logged)
}

void GearSimulator::load_command(const std_msgs::Float64ConstPtr& m) {
  const LiveSimulation::Status s = sim_->status();
  const ros::Time now = ros::Time::now();
  record(load_sub_.getTopic(), stamp_now(s.time), *m);  // received after the state at s.time
  ++commands_received_;
  last_command_ = std::chrono::steady_clock::now();
  silence_warned_ = false;
  if (!(std::abs(m->data) <= kMaxLoadMean)) {  // NaN and inf too
    ++commands_refused_;
    ROS_WARN_THROTTLE(1.0, "load command %g m/s^2 refused: outside [-%g, %g] m/s^2 (the range of load.initial_mean); "
                      "Phi keeps the command in effect (%llu refused so far)",
                      m->data, kMaxLoadMean, kMaxLoadMean, static_cast<unsigned long long>(commands_refused_));
    return;
  }
  sim_->command_load(m->data, now.toSec());
}

// ---- callbacks ----

void GearSimulator::reconfigure(RefusingConfig& config, uint32_t /*level*/) {
  for (const auto& [name, field] : double_parameters()) {
    if (!std::isnan(config.*field)) continue;
    const auto why = config.refused.find(name);
    ROS_WARN("dynamic_reconfigure: %s: refused, keeping %g",
             why != config.refused.end() ? why->second.c_str() : (name + " = nan").c_str(), dynamic_.*field);
    config.*field = dynamic_.*field;
  }
  Request r;
  if (config.mu != dynamic_.mu) r.mu = config.mu;
  if (config.sigma != dynamic_.sigma) r.sigma = config.sigma;
  if (config.lambda != dynamic_.lambda) r.drift = config.lambda;
  if (config.real_time_factor != dynamic_.real_time_factor) r.real_time_factor = config.real_time_factor;
  if (config.publish_rate != dynamic_.publish_rate) r.publish_rate = config.publish_rate;
  if (r.mu || r.sigma || r.drift || r.real_time_factor || r.publish_rate) {
    if (r.real_time_factor && *r.real_time_factor == 0.0) warn_full_speed();
    sim_->request(r);  // returns once applied; a refused value (e.g. sigma without noise) is not
    // The server answers with `config`: it shows what is in effect, as LiveSimulation decided.
    const LiveSimulation::Status in_effect = sim_->status();
    config.mu = in_effect.mu;
    config.sigma = in_effect.sigma;
    config.lambda = in_effect.drift;
  }
  dynamic_ = config;
}

bool GearSimulator::pause(std_srvs::Empty::Request&, std_srvs::Empty::Response&) {
  waiting_ = false;
  Request r;
  r.paused = true;
  return sim_->request(r).ok;
}

bool GearSimulator::unpause(std_srvs::Empty::Request&, std_srvs::Empty::Response&) {
  waiting_ = false;
  resend_start_ = true;
  Request r;
  r.paused = false;
  return sim_->request(r).ok;
}

bool GearSimulator::reset(std_srvs::Empty::Request&, std_srvs::Empty::Response&) {
  Request r;
  r.reset = true;
  return sim_->request(r).ok;
}

bool GearSimulator::step(std_srvs::Trigger::Request&, std_srvs::Trigger::Response& res) {
  waiting_ = false;
  resend_start_ = true;
  Request r;
  r.step = true;
  const LiveSimulation::Outcome o = sim_->request(r);
  res.success = o.ok;
  res.message = o.message;
  return true;
}

void GearSimulator::check_clock_publishers() {
  XmlRpc::XmlRpcValue request, response, payload;
  request[0] = ros::this_node::getName();
  if (!ros::master::execute("getSystemState", request, response, payload, false)) return;
  // payload: [publishers, subscribers, services], each a list of [topic, [node, ...]]
  XmlRpc::XmlRpcValue& publishers = payload[0];
  for (int i = 0; i < publishers.size(); ++i) {
    if (static_cast<std::string>(publishers[i][0]) != "/clock") continue;
    for (int k = 0; k < publishers[i][1].size(); ++k) {
      const std::string node = publishers[i][1][k];
      if (node == ros::this_node::getName() || !other_clocks_.insert(node).second) continue;
      ROS_WARN("gear_simulator: %s publishes /clock too: sim-time nodes then see two time lines, and /clock "
               "goes back and forth. Only one simulator may own the clock: start the others with "
               "publish_clock:=false", node.c_str());
    }
  }
}

void GearSimulator::diagnose(diagnostic_updater::DiagnosticStatusWrapper& stat) {
  const Status s = sim_->status();
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
  stat.add("load input", settings_.load_input);
  stat.add("load commands applied", s.load_commands);
  if (settings_.load_input != "sde") {
    // Commands faster than the integration steps are merged (the last one wins): received minus
    // refused minus applied.
    stat.add("load commands received", commands_received_);
    stat.add("load commands refused (out of range)", commands_refused_);
    const double silent = std::chrono::duration<double>(std::chrono::steady_clock::now() - last_command_).count();
    stat.add("wall s since the last load command", commands_received_ > 0 ? silent : -1.0);
    if (s.state == "running" && silent > kLoadCommandTimeout) {
      stat.mergeSummaryf(diagnostic_msgs::DiagnosticStatus::WARN, "no load command for %.1f s: Phi held", silent);
      if (!silence_warned_)
        ROS_WARN("gear_simulator: no load command on %s for %.1f wall s while running: Phi stays at the last "
                 "command (or load.initial_mean before the first)", load_sub_.getTopic().c_str(), silent);
      silence_warned_ = true;
    }
  }
  if (spectrum_) {
    const SpectrumPublisher::Stats st = spectrum_->stats();
    stat.add("spectrum: published", st.published);
    stat.add("spectrum: windows skipped (worker busy)", st.skipped);
    stat.add("spectrum: worker CPU per spectrum [ms]", 1e3 * st.cpu_per_update);
  }
  if (!record_prefix_.empty()) {
    std::lock_guard<std::mutex> lock(record_mutex_);
    const std::uint64_t written = recorded_ + (recorder_ ? recorder_->written() : 0);
    const std::uint64_t lost = lost_ + (recorder_ ? recorder_->lost() : 0);
    const std::string error = !record_error_.empty() ? record_error_ : recorder_ ? recorder_->error() : "";
    stat.add("record: bag", recorder_ ? recorder_->path() : (bags_.empty() ? "" : bags_.back()) + " (closed)");
    stat.add("record: messages written", written);
    stat.add("record: messages lost", lost);
    stat.add("record: wall s waited for the disk", recorder_ ? recorder_->waited_seconds() : 0.0);
    if (lost > 0)
      stat.mergeSummaryf(DiagnosticStatus::ERROR, "record: %llu messages not written (%s)",
                         static_cast<unsigned long long>(lost), error.c_str());
  }
}

// ---- LiveSink (stepping thread) ----

bool GearSimulator::wants_center_distance() const {
  return !record_prefix_.empty() || state_.wanted() || state_batch_.wanted() ||
         (settings_.publish_scalars && center_distance_.wanted());
}

void GearSimulator::publish(const LiveSample& s) {
  // One clock read per publish instant, for the /clock throttle and the burst's age.
  const auto now = std::chrono::steady_clock::now();
  publish_clock(now, s.t, false);
  if (held_.empty()) held_since_ = now;
  if (resend_start_.exchange(false) && unsent_start_ && s.step > 0) hold(*unsent_start_, false);
  unsent_start_.reset();
  hold(s, true);
  if (std::exchange(first_publish_, false) && (settings_.paused || hold_start_)) unsent_start_ = s;
  if (held_.size() >= kBurst || now - held_since_ >= kBurstWall) flush();
}

void GearSimulator::hold(const LiveSample& s, bool record_it) {
  ++instants_held_;
  const bool recording = record_it && !record_prefix_.empty();
  if (recording || state_.wanted() || state_batch_.wanted()) {
    held_.push_back(Held{&state_, make_state(s), {}, state_.wanted()});
    held_.back().state.header.stamp = stamp_of(s);
    const GearState& m = held_.back().state;
    if (recording) record(state_.topic, m.header.stamp, m);
  }
  const ros::Time stamp = stamp_of(s);
  if (joint_states_.wanted()) held_joints_.push_back(make_joint_state(s, gear_, stamp));
  if (settings_.publish_scalars) {
    const auto scalar = [&](const CountedPublisher& p, double value) {
      if (!recording && !p.wanted()) return;
      held_.push_back(Held{&p, {}, {}});
      held_.back().scalar.data = value;
      if (recording) record(p.topic, stamp, held_.back().scalar);
    };
    scalar(delta_, s.delta);
    scalar(delta_dot_, s.delta_dot);
    scalar(phi_, s.phi);
    scalar(center_distance_, s.center_distance);
  }
  if (s.bearings) hold_bearings(s, stamp, recording);
}

void GearSimulator::hold_bearings(const LiveSample& s, const ros::Time& stamp, bool recording) {
  if (!recording && !mesh_.wanted() && !pinion_wrench_.wanted() && !wheel_wrench_.wanted()) return;
  const BearingsOutputs& o = *s.bearings;
  // The batch bags' conversions (BagSink::recorded), stamped as this node's state.
  HeldBearings h{make_mesh_state(s.t, o, s.delta_t), make_bearing_wrench(s.t, kPinionBearingFrame, o.pinion_fx, o.pinion_fy),
                 make_bearing_wrench(s.t, kWheelBearingFrame, o.wheel_fx, o.wheel_fy)};
  h.mesh.header.stamp = h.pinion.header.stamp = h.wheel.header.stamp = stamp;
  if (recording) {
    record(mesh_.topic, stamp, h.mesh);
    record(pinion_wrench_.topic, stamp, h.pinion);
    record(wheel_wrench_.topic, stamp, h.wheel);
  }
  held_bearings_.push_back(std::move(h));
}

void GearSimulator::flush() {
  const bool batch = state_batch_.wanted();
  std::size_t sent = 0, states = 0, scalars = 0;
  for (const Held& h : held_) {
    if (h.pub == &state_) {
      if (h.send) h.pub->pub.publish(h.state);
      states += h.send;
      if (batch) batch_.states.push_back(h.state);
    } else if (h.pub->wanted()) {
      h.pub->pub.publish(h.scalar);
      ++scalars;
    }
  }
  held_.clear();  // keeps the capacity
  for (const sensor_msgs::JointState& j : held_joints_) joint_states_.pub.publish(j);
  scalars += held_joints_.size();  // one more topic with a message per instant
  held_joints_.clear();
  for (const HeldBearings& h : held_bearings_) {
    const auto send = [&](const CountedPublisher& p, const auto& m) {
      if (!p.wanted()) return;
      p.pub.publish(m);
      ++scalars;
    };
    send(mesh_, h.mesh);
    send(pinion_wrench_, h.pinion);
    send(wheel_wrench_, h.wheel);
  }
  held_bearings_.clear();
  sent = states + scalars;
  if (!batch_.states.empty()) {
    batch_.header.stamp = batch_.states.back().header.stamp;
    state_batch_.pub.publish(batch_);
    batch_.states.clear();
    ++sent;
  }
  // The busiest topic's count: state's, or a scalar topic's (one per instant held).
  const std::size_t busiest = std::max<std::size_t>({1, states, scalars > 0 ? instants_held_ : 0});
  instants_held_ = 0;
  if (sent > 0 && sim_ && sim_->real_time_factor() == 0.0) pace_messages(sent, busiest);
}

void GearSimulator::pace_messages(std::size_t sent, std::size_t busiest) {
  // A budget in wall time: what was sent moves it ahead; the loop sleeps while it is ahead of the
  // present, and a budget that fell behind (a pause, no subscriber) restarts at now.
  const auto now = std::chrono::steady_clock::now();
  if (message_budget_ < now - LiveSimulation::kMaxLag) message_budget_ = now;
  const double seconds = std::max(static_cast<double>(sent) / kFullSpeedMessageRate,
                                  static_cast<double>(busiest) / kFullSpeedTopicRate);
  message_budget_ += std::chrono::duration_cast<std::chrono::steady_clock::duration>(
      std::chrono::duration<double>(seconds));
  if (message_budget_ - now >= LiveSimulation::kMinWait) std::this_thread::sleep_until(message_budget_);
}

void GearSimulator::spectrum(const SpectrumSamples& window) {
  if (spectrum_) spectrum_->submit(window);
}

void GearSimulator::finished(const LiveSample& last) {
  flush();  // the run's states before its final state
  GearState m = make_state(last);
  m.header.stamp = stamp_of(last);
  final_state_pub_.publish(m);
  record(final_state_pub_.getTopic(), m.header.stamp, m);
  record_close();  // the bag of this run is complete; a ~reset opens the next one
  if (settings_.exit_at_end) {
    ROS_INFO("gear_simulator: t = %g s reached; ending (simulator.exit_at_end)", last.t);
    ros::requestShutdown();
  }
}

void GearSimulator::window_forces(const LiveWindowForces& w, const LiveSample& last) {
  flush();  // the run's states before its summary
  BearingSummary m = make_bearing_summary(w.run_name, w.t, w.window_start, w.forces);
  m.header.stamp = stamp_of(last);
  bearing_summary_pub_.publish(m);
  record(bearing_summary_pub_.getTopic(), m.header.stamp, m);
}

void GearSimulator::idle(const LiveSample& last) {
  flush();
  publish_clock(std::chrono::steady_clock::now(), last.t, true);  // where time stands, every idle period
}

LiveClock::time_point GearSimulator::RosClock::now() const {
  return time_point(std::chrono::nanoseconds(ros::Time::now().toNSec()));
}

ros::Time GearSimulator::stamp_of(const LiveSample& s) const {
  const bool owner_time = following_ && sim_ && sim_->real_time_factor() > 0.0 && ros::Time::isValid();
  return owner_time && s.clock_time > 0.0 ? ros::Time(s.clock_time) : sim_stamp(s.t);
}

ros::Time GearSimulator::stamp_now(double t) const {
  // Any thread: the factor in effect from the status, not the stepping loop's own member.
  const bool owner_time = following_ && sim_ && sim_->status().real_time_factor > 0.0 && ros::Time::isValid();
  return owner_time ? ros::Time::now() : sim_stamp(t);
}

void GearSimulator::publish_clock(std::chrono::steady_clock::time_point now, double t, bool always) {
  if (!settings_.publish_clock || (!always && now - last_clock_ < kClockInterval)) return;
  last_clock_ = now;
  rosgraph_msgs::Clock c;
  c.clock = sim_stamp(t);
  clock_pub_.publish(c);
}

void GearSimulator::run_info(const LiveRunInfo& i) {
  flush();  // the states before the change
  const bool deterministic = i.settings.deterministic;
  YAML::Node all = to_yaml(i.config);
  all["simulator"] = to_yaml(i.settings);
  YAML::Emitter out;
  out << all;
  RunInfo info = make_run_info(i.config, deterministic ? RunKind::S1 : RunKind::Stochastic,
                               static_cast<std::uint32_t>(i.lane.realization), i.lane.mu, i.lane.sigma,
                               i.settings.t_end, out.c_str());
  info.header.stamp = stamp_now(i.t);  // these values hold from here on
  run_info_pub_.publish(info);
  try {
    record_open();  // after t_end and a ~reset: the next bag
  } catch (const std::exception& e) {
    ROS_ERROR("%s: this run is not recorded (diagnostics count it)", e.what());
    std::lock_guard<std::mutex> lock(record_mutex_);
    if (record_error_.empty()) record_error_ = e.what();
  }
  record(run_info_pub_.getTopic(), info.header.stamp, info);
}

void GearSimulator::log(LiveLogLevel level, const std::string& line) {
  switch (level) {
    case LiveLogLevel::Debug: ROS_DEBUG("%s", line.c_str()); break;
    case LiveLogLevel::Info: ROS_INFO("%s", line.c_str()); break;
    case LiveLogLevel::Warn: ROS_WARN("%s", line.c_str()); break;
    case LiveLogLevel::Error: ROS_ERROR("%s", line.c_str()); break;
  }
}

}  // namespace gear_dynamics
