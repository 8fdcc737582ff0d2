// gear_simulator: one realization of the gear model (doc/model.md) stepped in simulated time on its own
// thread by LiveSimulation (the core, no ROS). This adapter owns /clock and the topics, and hands
// ROS callbacks (services, dynamic_reconfigure) to the simulation as requests, which it applies
// between two integration steps, at the next publish instant.
#pragma once

#include <dynamic_reconfigure/server.h>
#include <geometry_msgs/WrenchStamped.h>
#include <ros/ros.h>
#include <sensor_msgs/JointState.h>
#include <std_srvs/Empty.h>
#include <std_msgs/Float64.h>
#include <std_srvs/Trigger.h>
#include <tf2_msgs/TFMessage.h>
#include <tf2_ros/static_transform_broadcaster.h>

#include <boost/thread/recursive_mutex.hpp>
#include <chrono>
#include <diagnostic_updater/diagnostic_updater.h>
#include <atomic>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "gear_dynamics/GearState.h"
#include "gear_dynamics/GearStateBatch.h"
#include "gear_dynamics/MeshState.h"
#include "gear_dynamics/SimulatorConfig.h"
#include "gear_dynamics/config/config.hpp"
#include "gear_dynamics/config/simulator_settings.hpp"
#include "gear_dynamics/live/live_simulation.hpp"
#include "gear_dynamics/ros/live_recorder.hpp"
#include "gear_dynamics/ros/spectrum_publisher.hpp"

namespace gear_dynamics {

// The reconfigure server would clamp every request into Simulator.cfg's ranges, silently; with
// this Config a value out of range (or NaN) is refused with a warning instead, as at start:
// __clamp__ marks it NaN and says why in `refused`, and GearSimulator::reconfigure keeps the value
// in effect and logs one line per refused value.
struct RefusingConfig : SimulatorConfig {
  RefusingConfig() = default;
  RefusingConfig(const SimulatorConfig& c) : SimulatorConfig(c) {}  // the server converts its defaults
  void __clamp__();
  std::map<std::string, std::string> refused;  // name -> "mu = 5 is out of range [0, 0.2]"
};

// A publisher that counts its subscribers through roscpp's connect callbacks: the stepping thread
// asks at every publish instant, and Publisher::getNumSubscribers looks the topic up by name under a
// lock (at 10 kHz a noticeable share of a core).
struct CountedPublisher {
  ros::Publisher pub;
  std::string topic;  // absolute, as the bag stores it
  std::shared_ptr<std::atomic<int>> subscribers = std::make_shared<std::atomic<int>>(0);
  bool wanted() const { return subscribers->load(std::memory_order_relaxed) > 0; }
  template <class M>
  static CountedPublisher advertise(ros::NodeHandle& nh, const std::string& name, uint32_t queue) {
    CountedPublisher p;
    auto n = p.subscribers;
    p.pub = nh.advertise<M>(name, queue, [n](const ros::SingleSubscriberPublisher&) { ++*n; },
                            [n](const ros::SingleSubscriberPublisher&) { --*n; });
    p.topic = p.pub.getTopic();
    return p;
  }
};

// The ROS adapter of LiveSimulation (gear_dynamics/live/live_simulation.hpp): reads the parameters,
// publishes what the simulation reports, and turns services and dynamic_reconfigure into requests.
class GearSimulator : private LiveSink {
 public:
  // Reads and validates the private parameters (config/*.yaml); throws ConfigError naming the
  // bad keys before anything is advertised. Then starts stepping.
  GearSimulator(const ros::NodeHandle& nh, const ros::NodeHandle& private_nh);
  ~GearSimulator() override;  // stops and joins the stepping thread

  GearSimulator(const GearSimulator&) = delete;
  GearSimulator& operator=(const GearSimulator&) = delete;

 private:
  using Request = LiveSimulation::Request;
  using Status = LiveSimulation::Status;

  // ---- LiveSink (stepping thread) ----
  void publish(const LiveSample& s) override;
  void run_info(const LiveRunInfo& info) override;
  void log(LiveLogLevel level, const std::string& line) override;
  void idle(const LiveSample& last) override;
  void finished(const LiveSample& last) override;
  void window_forces(const LiveWindowForces& forces, const LiveSample& last) override;
  bool wants_center_distance() const override;
  void flush() override;  // publishes the held burst, and it as one state_batch (stepping thread)
  // Holds the messages of `s` for the topics that want them; into the bag with `record_it`.
  void hold(const LiveSample& s, bool record_it);
  // The same for the bearings model's outputs (mesh and the two bearing wrenches), stamped `stamp`.
  void hold_bearings(const LiveSample& s, const ros::Time& stamp, bool recording);
  // At real_time_factor 0: sleeps so that the messages sent stay within kFullSpeedMessageRate.
  void pace_messages(std::size_t sent, std::size_t busiest_topic);
  void spectrum(const SpectrumSamples& window) override;  // hands the window to spectrum_
  // /clock = t + 1 s at wall time `now`, if `always` or kClockInterval after the last one.
  void publish_clock(std::chrono::steady_clock::time_point now, double t, bool always);
  // The stamp of a state: t + 1 s on this node's own time line, or, while it follows the clock
  // owner's /clock (paced, with /clock received), the owner's time the state is due at.
  ros::Time stamp_of(const LiveSample& s) const;
  // The stamp of what happens now (a load command, a run-info change) at this node's time t.
  ros::Time stamp_now(double t) const;

  // The bag of record:=true (~record_prefix not empty): opened at the start and after a reset that
  // follows t_end, closed at t_end and at shutdown. Under record_mutex_.
  void record_open();
  void record_close();
  template <class M>
  void record(const std::string& topic, const ros::Time& stamp, const M& msg);

  // At real_time_factor 0: which subscribers can lose messages, and how to get every state.
  void warn_full_speed() const;

  // ---- callbacks (spinner thread) ----
  void load_command(const std_msgs::Float64ConstPtr& m);
  void reconfigure(RefusingConfig& config, uint32_t level);
  bool pause(std_srvs::Empty::Request&, std_srvs::Empty::Response&);
  bool unpause(std_srvs::Empty::Request&, std_srvs::Empty::Response&);
  bool reset(std_srvs::Empty::Request&, std_srvs::Empty::Response&);
  bool step(std_srvs::Trigger::Request&, std_srvs::Trigger::Response&);
  void diagnose(diagnostic_updater::DiagnosticStatusWrapper& stat);
  // With publish_clock: warns once per other node that publishes /clock (the master's state).
  void check_clock_publishers();

  // ROS time (under /use_sim_time the clock owner's /clock) as the pacing clock of a node that does
  // not own the clock.
  class RosClock : public LiveClock {
   public:
    time_point now() const override;
    bool steady() const override { return false; }
  };

  // Fixed after construction.
  ros::NodeHandle nh_, private_nh_;
  ModelConfig config_;
  GearPair gear_;  // derived from config_.gear (joint_states)
  SimulatorSettings settings_;

  std::string record_prefix_;  // empty: no recording
  // publish_clock false under /use_sim_time: paced by the owner's /clock, stamped in its time.
  bool following_ = false;
  RosClock ros_clock_;

  // Stepping thread only.
  std::chrono::steady_clock::time_point last_clock_;
  // The burst of messages publish() built and flush() publishes, in order, back to back (at most
  // kBurst or kBurstWall old: at real_time_factor 0 the loop never waits). Reused: no allocation
  // per message once warm.
  struct Held {
    const CountedPublisher* pub;
    GearState state;  // pub == &state_
    std_msgs::Float64 scalar;
    bool send = true;  // false: a state held for state_batch only
  };
  std::vector<Held> held_;
  std::chrono::steady_clock::time_point held_since_;
  GearStateBatch batch_;  // reused: its vector keeps its capacity
  std::vector<sensor_msgs::JointState> held_joints_;  // joint_states of the burst
  struct HeldBearings {  // the bearings model's messages of one publish instant
    MeshState mesh;
    geometry_msgs::WrenchStamped pinion, wheel;
  };
  std::vector<HeldBearings> held_bearings_;
  std::chrono::steady_clock::time_point message_budget_;  // pace_messages
  std::size_t instants_held_ = 0;  // publish instants in held_
  // A run started paused publishes t = 0 before anyone can have subscribed: that sample goes out
  // again at the first ~unpause or ~step (resend_start_, set by them), so that a recorder started
  // first gets every state from t = 0.
  std::optional<LiveSample> unsent_start_;
  bool first_publish_ = true;
  bool hold_start_ = false;               // paused for simulator.subscriber_wait at real_time_factor 0
  ros::WallTimer subscriber_wait_timer_;  // ends that wait
  std::atomic<bool> waiting_{false};      // still in it: no ~pause, ~unpause or ~step since
  std::atomic<bool> resend_start_{false};

  // The recording (stepping thread; diagnostics read it).
  std::mutex record_mutex_;
  std::unique_ptr<LiveRecorder> recorder_;
  std::vector<std::string> bags_;           // closed, in order
  std::uint64_t recorded_ = 0, lost_ = 0;   // over the closed bags
  std::string record_error_;

  // Spinner thread only.
  SimulatorConfig dynamic_;  // the last configuration handed over
  std::uint64_t commands_received_ = 0, commands_refused_ = 0;  // load_command
  std::chrono::steady_clock::time_point last_command_ = std::chrono::steady_clock::now();
  bool silence_warned_ = false;
  Status last_diagnosis_;

  // ROS interfaces (the sink runs on the stepping thread; roscpp publishers are thread-safe).
  CountedPublisher state_, state_batch_, joint_states_, delta_, delta_dot_, phi_, center_distance_;
  // The bearings model's (gear_pair.model: bearings): the batch bags' topics, and its frames on /tf_static.
  CountedPublisher mesh_, pinion_wrench_, wheel_wrench_;
  std::unique_ptr<tf2_ros::StaticTransformBroadcaster> bearing_frames_;
  tf2_msgs::TFMessage bearing_frames_msg_;  // what it sent, for the head of every bag
  ros::Publisher clock_pub_, run_info_pub_, final_state_pub_;
  ros::Publisher bearing_summary_pub_;  // bearings model with t_end > 0: latched, at every t_end
  ros::Subscriber load_sub_;
  ros::ServiceServer pause_srv_, unpause_srv_, reset_srv_, step_srv_;
  boost::recursive_mutex reconfigure_mutex_;
  dynamic_reconfigure::Server<RefusingConfig> reconfigure_server_;
  diagnostic_updater::Updater updater_;
  ros::WallTimer diagnostics_timer_;
  std::set<std::string> other_clocks_;  // publishers of /clock already warned about

  std::unique_ptr<SpectrumPublisher> spectrum_;  // with simulator.spectrum_rate > 0
  std::optional<LiveSimulation> sim_;  // last: publishes through the members above
};

}  // namespace gear_dynamics
