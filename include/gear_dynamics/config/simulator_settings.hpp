// The section `simulator` (config/simulator.yaml): how the live node gear_simulator runs one
// realization. Parsed from YAML without ROS, so the validator is unit-tested without a master.
#pragma once

#include <yaml-cpp/yaml.h>

#include <cstdint>
#include <string>

#include "gear_dynamics/config/section.hpp"

namespace gear_dynamics {

// Limits shared by the validator and config/Simulator.cfg (test_simulator_settings keeps them equal).
constexpr double kMaxRealTimeFactor = 1000.0;
// Requests are applied at publish instants; below 1 Hz one publish period takes about a wall
// second to integrate and the node would answer that slowly.
constexpr double kMinPublishRate = 1.0;     // [Hz]
constexpr double kMaxPublishRate = 1.0e6;   // [Hz], and at most one message per grid step
// The spectrum topic's trailing window holds at most this many samples of each series (16 MB for
// delta and the force): 10 s at the default 100 kHz.
constexpr double kMaxSpectrumSamples = 1.0e6;

struct SimulatorSettings {
  bool deterministic = false;     // the deterministic load S1 instead of a stochastic realization
  std::uint32_t realization = 0;  // random stream of the stochastic load
  double publish_rate = 1000.0;   // [Hz of simulated time]
  bool publish_scalars = true;    // the std_msgs/Float64 topics too
  bool publish_clock = true;      // own /clock
  double real_time_factor = 1.0;  // simulated s per wall s; 0 = as fast as possible
  double t_end = 0.0;             // [s]; 0 = run until stopped
  bool loop = false;              // start over at t_end instead of stopping
  bool exit_at_end = false;       // end the node at t_end (scripts, a launch that should end)
  bool paused = false;            // start paused
  // [wall s] at real_time_factor 0 (not paused): held at t = 0 this long first, so that a recorder
  // started before the node (rosbag record -a polls the master once a second) connects in time.
  double subscriber_wait = 2.0;
  // Where Phi comes from: "sde" (load.yaml's SDE), "external" (the load_command topic, held), or
  // "external_plus_noise" (the command plus the SDE's increments); see gear_dynamics/live/.
  std::string load_input = "sde";
  // The optional topic `spectrum` (doc/gear_simulator.md §3): Welch PSDs of delta and the mesh force
  // over a trailing window of samples taken on the integration grid.
  double spectrum_rate = 0.0;            // updates per simulated second; 0 = no spectrum topic
  double spectrum_window = 1.0;          // trailing window [s]
  double spectrum_sample_rate = 1.0e5;   // [Hz]: every round(1/(rate h)) grid steps
  double spectrum_segment = 0.09;        // Welch segment [s]; 0.09 = 30 mesh periods at 1000 rpm
  double spectrum_overlap = 0.5;         // fraction of a segment shared with the next
};

// The spectrum topic's settings on the grid of step h.
struct SpectrumSampling {
  std::int64_t sample_steps = 0;  // grid steps between two samples (D)
  std::int64_t update_steps = 0;  // grid steps between two updates, a multiple of D; 0 = no topic
  std::int64_t window_samples = 0, segment_samples = 0;
  double sample_rate = 0.0;       // effective: 1 / (D h) [Hz]
  double overlap = 0.0;
  bool enabled() const { return update_steps > 0; }
};
SpectrumSampling spectrum_sampling(const SimulatorSettings& settings, double time_step);

// The declaration of the `simulator` section.
const Section<SimulatorSettings>& simulator_section();

// Validates root["simulator"] for the model's time step h (t_end on the grid, publish_rate at
// most one message per step). Throws ConfigError listing every problem with key, value and range;
// unknown keys are errors.
SimulatorSettings parse_simulator_settings(const YAML::Node& root, double time_step);

// The settings as the section `simulator` (for run_info).
YAML::Node to_yaml(const SimulatorSettings& settings);

// Grid steps per publish period: 1/(rate h) rounded, at least 1 (the same rule as gear_run --rate).
std::int64_t publish_period_steps(double publish_rate, double time_step);

}  // namespace gear_dynamics
