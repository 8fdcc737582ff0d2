// gear_monitor: the condition monitor on a live gear (doc/monitor.md §5). Subscribes to the
// simulator's state_batch (gear_dynamics/GearStateBatch; or state, gear_dynamics/GearState, with
// ~input:=state) and run_info, and for a bearing-force signal to its bearing's wrench
// (geometry_msgs/WrenchStamped, paired with the state of the same stamp); cuts the signal into
// windows of whole revolutions by the state's shaft angle phi0 + Omega t, applies the healthy
// reference (gear_dynamics_monitor) and publishes each window's indicators
// (gear_dynamics/GearIndicators on `indicators`) and diagnostics (REP 107: OK, WARN, ERROR
// debounced; STALE when the input stops).
#include <diagnostic_msgs/DiagnosticStatus.h>
#include <diagnostic_updater/diagnostic_updater.h>
#include <geometry_msgs/WrenchStamped.h>
#include <message_filters/subscriber.h>
#include <message_filters/sync_policies/exact_time.h>
#include <message_filters/synchronizer.h>
#include <ros/ros.h>

#include <cmath>
#include <cstdio>
#include <memory>
#include <optional>

#include "gear_dynamics/GearIndicators.h"
#include "gear_dynamics/GearState.h"
#include "gear_dynamics/GearStateBatch.h"
#include "gear_dynamics/RunInfo.h"
#include "gear_dynamics/model/mesh_schedule.hpp"
#include "gear_dynamics/monitor/reference.hpp"

namespace gd = gear_dynamics;

namespace {

class GearMonitor {
 public:
  GearMonitor(ros::NodeHandle& nh, ros::NodeHandle& pnh) : nh_(nh), updater_(nh, pnh) {
    std::string input;
    pnh.param<std::string>("reference", reference_path_, "");
    pnh.param<std::string>("input", input, "state_batch");
    pnh.param("debounce", debounce_, 2);
    pnh.param("stale_timeout", stale_timeout_, 2.0);
    if (reference_path_.empty()) throw std::runtime_error("~reference is not set: the reference file (gear_monitor_reference)");
    if (input != "state_batch" && input != "state")
      throw std::runtime_error("~input = " + input + " is not allowed; allowed: state_batch, state");
    if (debounce_ < 1 || debounce_ > 1000)
      throw std::runtime_error("~debounce = " + std::to_string(debounce_) + " is out of range; allowed [1, 1000]");
    if (!(stale_timeout_ > 0.0 && stale_timeout_ <= 3600.0))
      throw std::runtime_error("~stale_timeout = " + std::to_string(stale_timeout_) + " is out of range; allowed (0, 3600] s");
    gd::Reference reference = gd::read_reference(reference_path_);
    spec_ = gd::signal_spec(reference.settings.monitor.signal);
    const gd::ModelConfig config = gd::parse_config(reference.config);
    gear_ = gd::derive(config.gear);
    schedule_ = std::make_unique<gd::MeshSchedule>(gear_, config.run.time_step);
    time_step_ = config.run.time_step;
    warmup_ = reference.settings.warmup;
    monitor_ = std::make_unique<gd::ConditionMonitor>(std::move(reference));
    const auto& m = monitor_->settings();
    windows_ = std::make_unique<gd::RevolutionWindows>(monitor_->revolution_angle(), m.revolutions_per_window,
                                                       m.samples_per_revolution);
    names_ = gd::indicator_names();

    publisher_ = nh_.advertise<gear_dynamics::GearIndicators>("indicators", 16);
    run_info_sub_ = nh_.subscribe("run_info", 4, &GearMonitor::run_info, this);
    if (input == "state_batch")
      state_sub_ = nh_.subscribe("state_batch", 1000, &GearMonitor::batch, this);
    else
      state_sub_ = nh_.subscribe("state", 65536, &GearMonitor::state, this);
    if (spec_.wrench_topic) {
      // The wrench and the state of one instant carry the same stamp (the simulator's and the
      // batch bags'): paired exactly; an instant missing on either side is dropped (a gap).
      wrench_sub_ = nh_.subscribe(spec_.wrench_topic, 65536, &GearMonitor::wrench, this);
      pairs_ = std::make_unique<Pairs>(PairPolicy(kPairQueue));
      pairs_->registerCallback(boost::bind(&GearMonitor::paired, this, boost::placeholders::_1, boost::placeholders::_2));
    }
    updater_.setHardwareID("gear:" + std::string(gd::to_string(m.signal)));
    updater_.add("condition", this, &GearMonitor::diagnose);
    // Wall time: under /use_sim_time the simulated clock stops with the input, STALE must not.
    timer_ = nh_.createWallTimer(ros::WallDuration(0.5), [this](const ros::WallTimerEvent&) { updater_.force_update(); });
    ROS_INFO("gear_monitor: reference %s (%s, %d revolution(s) of the %s per window), on %s%s%s",
             reference_path_.c_str(), gd::to_string(m.signal), m.revolutions_per_window,
             m.gear == gd::FaultyGear::kWheel ? "wheel" : "pinion", state_sub_.getTopic().c_str(),
             spec_.wrench_topic ? " and " : "", spec_.wrench_topic ? wrench_sub_.getTopic().c_str() : "");
  }

  int exit_code() const { return exit_code_; }

 private:
  void run_info(const gear_dynamics::RunInfo& info) {
    try {
      const gd::ModelConfig monitored = gd::parse_config(YAML::Load(info.parameters_yaml));
      gd::check_reference(monitor_->reference(), monitored, reference_path_);
    } catch (const std::exception& e) {
      ROS_FATAL("gear_monitor: %s", e.what());
      exit_code_ = 1;
      ros::shutdown();
      return;
    }
    checked_ = true;
    if (info.time_step > 0.0) time_step_ = info.time_step;
  }

  void batch(const gear_dynamics::GearStateBatch& b) {
    for (const auto& s : b.states) state(s);
  }

  void state(const gear_dynamics::GearState& s) {
    if (pairs_) {
      pairs_->add<0>(boost::make_shared<const gear_dynamics::GearState>(s));
      return;
    }
    const double t = s.t;
    sample(s, gd::state_signal(gear_, spec_.signal, s.mesh_stiffness, schedule_->transmission_error(t),
                               schedule_->transmission_error_rate(t), s.delta, s.delta_dot));
  }

  void wrench(const geometry_msgs::WrenchStamped::ConstPtr& w) { pairs_->add<1>(w); }

  void paired(const gear_dynamics::GearState::ConstPtr& s, const geometry_msgs::WrenchStamped::ConstPtr& w) {
    sample(*s, gd::wrench_component(spec_, w->wrench.force.x, w->wrench.force.y));
  }

  // One sample of the signal at the state's time, with its load.
  void sample(const gear_dynamics::GearState& s, double value) {
    last_input_ = ros::WallTime::now();
    ++states_;
    if (s.t < last_t_) {  // a reset or loop of the simulator: a new run
      windows_->restart();
      monitor_->reset();
      window_count_ = 0;
      spacing_ = 0.0;
    } else if (spacing_ > 0.0 && s.t - last_t_ > 1.5 * spacing_) {
      // States lost (a full queue): a window must not interpolate across them.
      windows_->restart();
      ++gaps_;
    } else if (spacing_ == 0.0 && last_t_ >= 0.0 && s.t > last_t_) {
      spacing_ = s.t - last_t_;
    }
    last_t_ = s.t;
    if (s.t < warmup_) return;
    // The state's t is the grid time rounded to whole nanoseconds; the engine's angle is at n h.
    const double grid_t = std::round(s.t / time_step_) * time_step_;
    const auto window = windows_->add(gd::shaft_angle(gear_, grid_t), value, s.phi);
    if (!window) return;
    const gd::Assessment a = monitor_->assess(*window);
    ++window_count_;
    outside_count_ += !a.in_reference;
    last_ = a;
    debounce(a.health);

    gear_dynamics::GearIndicators msg;
    msg.header = s.header;
    msg.t = s.t;
    msg.window = static_cast<std::uint32_t>(window_count_);
    msg.load = a.load;
    msg.band = static_cast<std::uint32_t>(a.band);
    msg.names = names_;
    msg.values = a.indicators;
    for (char x : a.exceeded) msg.exceeded.push_back(x != 0);
    msg.t2 = a.t2;
    msg.t2_threshold = monitor_->reference().bands[a.band].t2_threshold;
    msg.score = a.score;
    msg.cusum = a.cusum;
    msg.cusum_threshold = monitor_->reference().cusum_threshold;
    msg.in_reference = a.in_reference;
    msg.level = level_of(a.health);
    msg.reported_level = level_of(reported_);
    publisher_.publish(msg);
  }

  static std::uint8_t level_of(gd::Health h) {
    using diagnostic_msgs::DiagnosticStatus;
    return h == gd::Health::kOk ? DiagnosticStatus::OK : h == gd::Health::kWarn ? DiagnosticStatus::WARN : DiagnosticStatus::ERROR;
  }

  // A level is reported once it held for `debounce` consecutive windows.
  void debounce(gd::Health h) {
    if (h == pending_) {
      ++pending_count_;
    } else {
      pending_ = h;
      pending_count_ = 1;
    }
    if (pending_count_ >= debounce_) reported_ = pending_;
  }

  void diagnose(diagnostic_updater::DiagnosticStatusWrapper& stat) {
    using diagnostic_msgs::DiagnosticStatus;
    const double silent = states_ ? (ros::WallTime::now() - last_input_).toSec() : -1.0;
    if (states_ == 0) {
      stat.summary(DiagnosticStatus::STALE, "no input yet on " + state_sub_.getTopic());
    } else if (silent > stale_timeout_) {
      stat.summaryf(DiagnosticStatus::STALE, "no input for %.1f s", silent);
    } else if (window_count_ == 0) {
      stat.summary(DiagnosticStatus::OK, "collecting the first window");
    } else {
      const gd::Reference& ref = monitor_->reference();
      if (reported_ == gd::Health::kWarn && !last_->in_reference)
        stat.summaryf(DiagnosticStatus::WARN, "not judged: load %.4g m/s^2 outside the reference's [%.4g, %.4g]",
                      last_->load, ref.bands.front().load_low, ref.bands.back().load_high);
      else
        stat.summary(level_of(reported_), reported_ == gd::Health::kError  ? "fault: the CUSUM of T2 is above its threshold"
                                          : reported_ == gd::Health::kWarn ? "T2 above its threshold"
                                                                           : "healthy");
    }
    stat.add("reference", reference_path_);
    stat.add("reference checked against run_info", checked_);
    stat.add("windows", window_count_);
    stat.add("states received", states_);
    stat.add("gaps in the input (windows restarted)", gaps_);
    stat.add("wall s since the last state", silent);
    if (last_) {
      stat.add("load [m/s^2]", last_->load);
      stat.add("load band", last_->band);
      stat.add("load within the reference's", last_->in_reference);
      stat.add("windows not judged (load outside the reference's)", outside_count_);
      stat.add("T2", last_->t2);
      stat.add("T2 threshold", monitor_->reference().bands[last_->band].t2_threshold);
      stat.add("CUSUM", last_->cusum);
      stat.add("CUSUM threshold", monitor_->reference().cusum_threshold);
      std::string above;
      for (std::size_t i = 0; i < names_.size(); ++i)
        if (last_->exceeded[i]) above += (above.empty() ? "" : ", ") + names_[i];
      stat.add("indicators above their thresholds", above.empty() ? "none" : above);
    }
  }

  using PairPolicy = message_filters::sync_policies::ExactTime<gear_dynamics::GearState, geometry_msgs::WrenchStamped>;
  using Pairs = message_filters::Synchronizer<PairPolicy>;
  // Instants awaiting their other half: many state batches' worth (the simulator's hold up to 64).
  static constexpr std::uint32_t kPairQueue = 20000;

  ros::NodeHandle nh_;
  diagnostic_updater::Updater updater_;
  gd::MonitoredSignalSpec spec_{};
  std::unique_ptr<Pairs> pairs_;
  ros::Subscriber wrench_sub_;
  std::string reference_path_;
  int debounce_ = 2;
  double stale_timeout_ = 2.0, warmup_ = 0.0, last_t_ = -1.0, time_step_ = 0.0;
  gd::GearPair gear_;
  std::unique_ptr<gd::MeshSchedule> schedule_;
  std::unique_ptr<gd::ConditionMonitor> monitor_;
  std::unique_ptr<gd::RevolutionWindows> windows_;
  std::vector<std::string> names_;
  ros::Publisher publisher_;
  ros::Subscriber run_info_sub_, state_sub_;
  ros::WallTimer timer_;
  ros::WallTime last_input_;
  long states_ = 0, window_count_ = 0, gaps_ = 0, outside_count_ = 0;
  double spacing_ = 0.0;  // of the input's first two states [s]
  std::optional<gd::Assessment> last_;
  gd::Health pending_ = gd::Health::kOk, reported_ = gd::Health::kOk;
  int pending_count_ = 0;
  bool checked_ = false;
  int exit_code_ = 0;
};

}  // namespace

int main(int argc, char** argv) {
  ros::init(argc, argv, "gear_monitor");
  ros::NodeHandle nh, pnh("~");
  std::unique_ptr<GearMonitor> monitor;
  try {
    monitor = std::make_unique<GearMonitor>(nh, pnh);
  } catch (const std::exception& e) {
    ROS_FATAL("gear_monitor: %s", e.what());
    return 1;
  }
  ros::spin();
  return monitor->exit_code();
}
