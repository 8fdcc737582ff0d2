// gear_aggregator: the batch report node (see gear_dynamics/ros/aggregator_node.hpp).
#include <ros/ros.h>

#include "gear_dynamics/ros/aggregator_node.hpp"

int main(int argc, char** argv) {
  ros::init(argc, argv, "gear_aggregator");
  ros::NodeHandle private_nh("~");
  try {
    gear_dynamics::AggregatorNode aggregator(private_nh);
    if (!aggregator.run()) return 1;
    if (!aggregator.settings().exit_when_done) ros::spin();
  } catch (const gear_dynamics::ConfigError& e) {
    ROS_FATAL("%s", e.what());
    return 1;
  }
  return 0;
}
