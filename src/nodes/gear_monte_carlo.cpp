// gear_monte_carlo: the Monte Carlo batch node (gear_dynamics/ros/monte_carlo_node.hpp).
#include <ros/ros.h>

#include "gear_dynamics/ros/monte_carlo_node.hpp"
#include "gear_dynamics/ros/stop_signal.hpp"
#include "gear_dynamics/ros/utf8_console.hpp"

int main(int argc, char** argv) {
  gear_dynamics::use_utf8_console();
  ros::init(argc, argv, "gear_monte_carlo", ros::init_options::NoSigintHandler);
  // SIGINT and SIGTERM stop the batch cleanly (finished bags kept) instead of shutting ROS down at once.
  gear_dynamics::install_stop_handlers(gear_dynamics::OnSigint::OnlyRemember);
  ros::NodeHandle pnh("~");
  // A waiting aggregator tells this run's batch node from an earlier one by it (the launch clears
  // the private namespace, so an older value is left only where no launch started a batch since).
  pnh.setParam("start_time", ros::WallTime::now().toSec());
  gear_dynamics::MonteCarloNode node(pnh);
  int code = node.init();
  if (code == 0) code = node.run();
  return code;
}
