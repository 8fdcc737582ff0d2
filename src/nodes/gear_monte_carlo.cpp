// gear_monte_carlo: the Monte Carlo batch node (gear_dynamics/ros/monte_carlo_node.hpp).
#include <ros/ros.h>

#include "gear_dynamics/ros/monte_carlo_node.hpp"

int main(int argc, char** argv) {
  // Our own handlers: a signal stops the batch cleanly instead of shutting ROS down at once.
  ros::init(argc, argv, "gear_monte_carlo", ros::init_options::NoSigintHandler);
  gear_dynamics::MonteCarloNode::install_signal_handlers();
  ros::NodeHandle pnh("~");
  gear_dynamics::MonteCarloNode node(pnh);
  if (const int code = node.init()) return code;
  return node.run();
}
