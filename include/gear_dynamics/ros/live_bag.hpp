// A run of the live node read back from a bag (doc/nonlinear-dynamics.md §12): the node's own
// record:=true bag, or `rosbag record` of its state or state_batch topic. gear_analyze analyses it.
#pragma once

#include <map>
#include <string>
#include <vector>

namespace gear_dynamics {

struct LiveBagRun {
  std::string topic;            // the topic the states came from
  std::string parameters_yaml;  // the run's configuration (RunInfo), empty if the bag has none
  std::string note;             // what was left out (an earlier run before a reset), or empty
  std::vector<double> t, delta, delta_dot, phi, stiffness;  // SI, one entry per state
  // The bearings model's bearing forces [N] (doc/model.md §11): per topic that ends in
  // kBearingWrenchTopics (geometry_msgs/WrenchStamped), keyed by that ending, the force of the
  // wrench at each state's stamp, x across the line of action and y along it.
  struct Forces {
    std::vector<double> x, y;
  };
  std::map<std::string, Forces> wrenches;
};
inline const char* const kBearingWrenchTopics[] = {"pinion_bearing/wrench", "wheel_bearing/wrench"};

// Reads the states of one run, in time order. Throws std::runtime_error with the reason when the
// bag cannot be read, is still being written (.bag.active: `rosbag reindex` it), holds no
// gear_dynamics/GearState or GearStateBatch states, lost states (a gap in header.seq, or in the
// time grid), or states at uneven times, or a bearing wrench topic without a wrench at a state's
// stamp. After a ~reset (t back to 0) the last run is read.
LiveBagRun read_live_bag(const std::string& path);

}  // namespace gear_dynamics
