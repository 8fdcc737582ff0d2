// gear_aggregator: the batch report node (see gear_dynamics/ros/aggregator_node.hpp).
#include <ros/ros.h>

#include "gear_dynamics/ros/aggregator_node.hpp"
#include "gear_dynamics/ros/stop_signal.hpp"
#include "gear_dynamics/ros/utf8_console.hpp"

int main(int argc, char** argv) {
  gear_dynamics::use_utf8_console();
  ros::init(argc, argv, "gear_aggregator", ros::init_options::NoSigintHandler);
  gear_dynamics::install_stop_handlers(gear_dynamics::OnSigint::RequestShutdown);
  ros::NodeHandle private_nh("~");
  gear_dynamics::repeat_early_stop();
  try {
    gear_dynamics::AggregatorNode aggregator(private_nh);
    if (!aggregator.run()) return 1;
    if (!aggregator.settings().exit_when_done) ros::spin();
  } catch (const gear_dynamics::ConfigError& e) {
    if (gear_dynamics::stop_signal() != 0) {  // the parameter reads were cut short, not wrong
      gear_dynamics::warn_at_stop("gear_aggregator: stopped by SIGINT while starting; no report");
      return 1;  // as a shutdown while waiting for the batch: the report a caller expects is not there
    }
    ROS_FATAL("%s", e.what());
    return 1;
  }
  return 0;
}
