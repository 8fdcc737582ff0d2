// gear_simulator: one realization of the gear model (doc/model.md) stepped in simulated time on its own
// thread. It owns /clock, paces itself by wall time and publishes a decimation of the integration
// grid. ROS callbacks (services, dynamic_reconfigure) only hand requests to the stepping thread,
// which applies them between two integration steps, at the next publish instant.
#pragma once

#include <dynamic_reconfigure/server.h>
#include <ros/ros.h>
#include <std_srvs/Empty.h>
#include <std_srvs/Trigger.h>

#include <atomic>
#include <boost/thread/recursive_mutex.hpp>
#include <chrono>
#include <condition_variable>
#include <diagnostic_updater/diagnostic_updater.h>
#include <mutex>
#include <optional>
#include <string>
#include <thread>

#include "gear_dynamics/SimulatorConfig.h"
#include "gear_dynamics/config/config.hpp"
#include "gear_dynamics/engine/ensemble.hpp"
#include "gear_dynamics/engine/observers.hpp"
#include "gear_dynamics/config/simulator_settings.hpp"

namespace gear_dynamics {

// The reconfigure server clamps every request into Simulator.cfg's ranges, silently; with this
// Config it logs each value the clamp changes. NaN passes the clamp (comparisons with NaN are
// false): GearSimulator::reconfigure keeps the value in effect instead.
struct ClampLoggedConfig : SimulatorConfig {
  ClampLoggedConfig() = default;
  ClampLoggedConfig(const SimulatorConfig& c) : SimulatorConfig(c) {}  // the server converts its defaults
  void __clamp__();
};

class GearSimulator {
 public:
  // Reads and validates the private parameters (config/*.yaml); throws ConfigError naming the
  // bad keys before anything is advertised. Then starts stepping.
  GearSimulator(const ros::NodeHandle& nh, const ros::NodeHandle& private_nh);
  ~GearSimulator();  // stops and joins the stepping thread

  GearSimulator(const GearSimulator&) = delete;
  GearSimulator& operator=(const GearSimulator&) = delete;

 private:
  // What callbacks ask of the stepping thread; merged until it takes them.
  struct Request {
    std::optional<double> mu, sigma, drift, real_time_factor, publish_rate;
    std::optional<bool> paused;
    bool reset = false;
    bool step = false;
  };
  // How the stepping thread answered a request: `ok` false with the reason when refused.
  struct Outcome {
    bool ok = true;
    std::string message;
  };
  // Shown in diagnostics; written by the stepping thread under mutex_.
  struct Status {
    double time = 0.0;
    std::string state = "starting";
    std::string divergence;
    double mu = 0.0, sigma = 0.0, drift = 0.0, real_time_factor = 0.0, publish_rate = 0.0;
    std::int64_t steps = 0;          // integration steps since start (monotonic, across resets)
    std::int64_t publications = 0;   // publish instants since start
    double running_wall = 0.0;       // wall seconds spent running (not paused) [s]
  };

  // ---- callbacks (spinner thread) ----
  Outcome request(const Request& r);  // hands `r` over and waits until it is applied
  void reconfigure(SimulatorConfig& config, uint32_t level);
  bool pause(std_srvs::Empty::Request&, std_srvs::Empty::Response&);
  bool unpause(std_srvs::Empty::Request&, std_srvs::Empty::Response&);
  bool reset(std_srvs::Empty::Request&, std_srvs::Empty::Response&);
  bool step(std_srvs::Trigger::Request&, std_srvs::Trigger::Response&);
  void diagnose(diagnostic_updater::DiagnosticStatusWrapper& stat);

  // ---- stepping thread ----
  void run();
  Outcome apply(const Request& r);
  void advance();       // integrates to the next publish instant (or t_end) and publishes
  void publish();       // state, scalars and /clock at the current grid point
  void publish_clock(bool always);  // else throttled to kClockInterval of wall time
  void publish_run_info();
  void restart();       // back to t = 0, the start of the random stream, published
  void diverge(const std::string& what);
  void pace();          // waits until wall time catches up with real_time_factor
  void idle();          // paused: waits for a request, republishing /clock
  bool running() const { return !paused_ && !finished_ && !diverged_; }
  std::string state_name() const;
  WindowRange make_window() const;

  // Fixed after construction.
  ros::NodeHandle nh_, private_nh_;
  ModelConfig config_;
  SimulatorSettings settings_;  // as loaded; the stepping thread owns the dynamic ones below
  std::int64_t end_step_;       // 0 = run on forever

  // Owned by the stepping thread.
  Ensemble ensemble_;
  double real_time_factor_, publish_rate_;
  std::int64_t period_;  // grid steps per publish period
  WindowRange window_;   // trailing-window ranges for the center distance d(t)
  bool paused_, finished_ = false, diverged_ = false;
  std::string divergence_;
  using WallClock = std::chrono::steady_clock;
  bool anchored_ = false;  // pacing restarts from (anchor_wall_, anchor_step_) when false
  WallClock::time_point anchor_wall_;
  std::int64_t anchor_step_ = 0;
  WallClock::time_point last_clock_;
  Status local_;  // the stepping thread's copy of the status, handed over under mutex_

  // Shared between the threads under mutex_.
  std::mutex mutex_;
  std::condition_variable wake_;  // the stepping thread waits here (pacing, paused)
  std::condition_variable done_;  // callbacks wait here for their request to be applied
  Request pending_;
  bool has_pending_ = false;
  std::uint64_t requested_ = 0, applied_ = 0;
  Outcome outcome_;
  Status status_;
  std::atomic<bool> stop_{false};

  // Spinner thread only.
  SimulatorConfig dynamic_;  // the last configuration handed over
  double last_diagnosis_wall_ = 0.0;
  Status last_diagnosis_;

  // ROS interfaces (publish() runs on the stepping thread; roscpp publishers are thread-safe).
  ros::Publisher state_pub_, delta_pub_, delta_dot_pub_, phi_pub_, center_distance_pub_, clock_pub_,
      run_info_pub_;
  ros::ServiceServer pause_srv_, unpause_srv_, reset_srv_, step_srv_;
  boost::recursive_mutex reconfigure_mutex_;
  dynamic_reconfigure::Server<ClampLoggedConfig> reconfigure_server_;
  diagnostic_updater::Updater updater_;
  ros::WallTimer diagnostics_timer_;

  std::thread thread_;  // last: starts once everything above exists
};

}  // namespace gear_dynamics
