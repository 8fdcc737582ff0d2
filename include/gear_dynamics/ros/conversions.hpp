// What every node of this package shares at the ROS boundary: reading the model configuration
// from the parameter server through the core's validator, the simulated-time clock offset, and
// the conversions from core results to this package's messages. The core library stays ROS-free.
#pragma once

#include <ros/node_handle.h>
#include <ros/time.h>

#include <string>
#include <vector>

#include <geometry_msgs/TransformStamped.h>
#include <geometry_msgs/WrenchStamped.h>

#include "gear_dynamics/BearingSummary.h"
#include "gear_dynamics/GearState.h"
#include "gear_dynamics/MeshState.h"
#include "gear_dynamics/PoincarePoint.h"
#include "gear_dynamics/RunInfo.h"
#include "gear_dynamics/RunSummary.h"
#include "gear_dynamics/batch/run_kind.hpp"
#include "gear_dynamics/config/config.hpp"
#include "gear_dynamics/engine/bearings.hpp"
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
// gear_pair.model = bearings adds, at each recorded state, the mesh and the force each body puts on
// its bearing (a wrench in the bearing's frame, make_bearing_frames), and the window's statistics
// of those forces at the end (batch only). gear_simulator publishes the first three.
constexpr const char* kMeshTopic = "/gear/mesh";
constexpr const char* kPinionBearingTopic = "/gear/pinion_bearing/wrench";
constexpr const char* kWheelBearingTopic = "/gear/wheel_bearing/wrench";
constexpr const char* kBearingSummaryTopic = "/gear/bearing_summary";
constexpr const char* kGearPairFrame = "gear_pair";
constexpr const char* kPinionBearingFrame = "pinion_bearing";
constexpr const char* kWheelBearingFrame = "wheel_bearing";

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

// The bearings model's outputs at time t as messages: the mesh, and the force a body puts on its
// bearing as a wrench (force only) in `frame`.
MeshState make_mesh_state(double t, const BearingsOutputs& outputs, double delta_t);
geometry_msgs::WrenchStamped make_bearing_wrench(double t, const char* frame, double fx, double fy);
// The frames the bearing forces are given in, as static transforms from the frame gear_pair of
// the URDF (model/gear_urdf.hpp: the pinion's axis, x towards the wheel's): pinion_bearing at the pinion's axis,
// wheel_bearing at the wheel's, the working centre distance a_w = (Rb1 + Rb2)/cos(alpha_w) away,
// both turned about z by -alpha_w, the working pressure angle, so that y runs along the line of
// action from the pinion's base-circle tangent point towards the wheel's (doc/model.md §11).
std::vector<geometry_msgs::TransformStamped> make_bearing_frames(const GearPair& gear, const ros::Time& stamp);
// The window's statistics of a bearings run (RunResult::bearings), over [T - W, T].
BearingSummary make_bearing_summary(const std::string& run_name, const RunSettings& run, const BearingForces& forces);
// The same for the window from window_start to t, stamped at t (the live node's, LiveWindowForces).
BearingSummary make_bearing_summary(const std::string& run_name, double t, double window_start,
                                    const BearingForces& forces);

}  // namespace gear_dynamics
