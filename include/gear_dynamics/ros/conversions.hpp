// What every node of this package shares at the ROS boundary: reading the model configuration
// from the parameter server through the core's validator, the simulated-time clock offset, and
// the conversions from core results to this package's messages. The core library stays ROS-free.
#pragma once

#include <ros/node_handle.h>
#include <ros/time.h>

#include <string>

#include "gear_dynamics/GearState.h"
#include "gear_dynamics/PoincarePoint.h"
#include "gear_dynamics/RunInfo.h"
#include "gear_dynamics/RunSummary.h"
#include "gear_dynamics/batch/run_kind.hpp"
#include "gear_dynamics/config/config.hpp"
#include "gear_dynamics/engine/ensemble.hpp"
#include "gear_dynamics/engine/simulation.hpp"
#include "gear_dynamics/live/live_simulation.hpp"

namespace gear_dynamics {

// Simulated time t maps to ROS time t + kClockOffset: /clock never reads 0 (ROS takes 0 as "no
// time yet") and rosbag accepts every stamp (it refuses times before 1 ns).
constexpr double kClockOffset = 1.0;  // [s]
inline ros::Time sim_stamp(double t) { return ros::Time(kClockOffset + t); }

// The sections gear_pair, load and run of `nh`'s namespace (normally the private one, filled from
// config/*.yaml by the launch file) as YAML, then validated by parse_config. Throws ConfigError.
YAML::Node yaml_from_parameters(const ros::NodeHandle& nh, const std::vector<std::string>& sections);
// Every parameter of `nh`'s namespace as one YAML map (empty if it holds none).
YAML::Node yaml_from_namespace(const ros::NodeHandle& nh);
ModelConfig load_model_config(const ros::NodeHandle& nh);

// The topics of a run bag (doc/batch-folder.md §2, §5); the manifest is batch/manifest.hpp's.
constexpr const char* kRunInfoTopic = "/gear/run_info";
constexpr const char* kStateTopic = "/gear/state";
constexpr const char* kSummaryTopic = "/gear/summary";
// The Poincare section of a deterministic run (S1, phase): one PoincarePoint per mesh period.
constexpr const char* kPoincareTopic = "/gear/poincare";

RunInfo make_run_info(const ModelConfig& config, RunKind kind, std::uint32_t realization,
                      double mu, double sigma, double duration);
// The same with parameters_yaml given (config's YAML, emitted by the caller, who may share it).
RunInfo make_run_info(const ModelConfig& config, RunKind kind, std::uint32_t realization, double mu, double sigma,
                      double duration, std::string parameters_yaml);
// State of `lane` now; center_distance is the instantaneous d(t) (SI).
GearState make_state(const Ensemble& ensemble, int lane, double center_distance);
// The live simulation's sample as a message (the same numbers as make_state of its ensemble).
GearState make_state(const LiveSample& sample);
// A point of a run's Poincare section at mesh phase 0 (RunResult::section).
PoincarePoint make_poincare_point(const SectionPoint& point);
RunSummary make_summary(const std::string& run_name, RunKind kind,
                        std::uint32_t realization, double mu, double mesh_phase,
                        const RunSettings& run, const RunResult& result);

}  // namespace gear_dynamics
