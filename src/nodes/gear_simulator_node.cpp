// gear_simulator: the live simulator node (see gear_dynamics/ros/gear_simulator.hpp and doc/gear_simulator.md).
#include <ros/ros.h>

#include "gear_dynamics/ros/gear_simulator.hpp"

int main(int argc, char** argv) {
  ros::init(argc, argv, "gear_simulator");
  // Outlive the simulator: when the last NodeHandle goes, roscpp shuts down, logging included.
  ros::NodeHandle nh, private_nh("~");
  try {
    gear_dynamics::GearSimulator simulator(nh, private_nh);
    ros::spin();
  } catch (const gear_dynamics::ConfigError& e) {
    ROS_FATAL("%s", e.what());
    return 1;
  }
  return 0;
}
