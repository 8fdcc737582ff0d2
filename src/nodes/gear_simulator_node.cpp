// gear_simulator: the live simulator node (see gear_dynamics/ros/gear_simulator.hpp and doc/gear_simulator.md).
#include <ros/ros.h>

#include "gear_dynamics/ros/gear_simulator.hpp"
#include "gear_dynamics/ros/stop_signal.hpp"
#include "gear_dynamics/ros/utf8_console.hpp"

int main(int argc, char** argv) {
  gear_dynamics::use_utf8_console();
  ros::init(argc, argv, "gear_simulator", ros::init_options::NoSigintHandler);
  // SIGTERM too: roslaunch's second signal, or `kill`, still closes the node's bag.
  gear_dynamics::install_stop_handlers(gear_dynamics::OnSigint::RequestShutdownAlsoSigterm);
  // Outlive the simulator: when the last NodeHandle goes, roscpp shuts down, logging included.
  ros::NodeHandle nh, private_nh("~");
  gear_dynamics::repeat_early_stop();
  try {
    gear_dynamics::GearSimulator simulator(nh, private_nh);
    ros::spin();
  } catch (const gear_dynamics::ConfigError& e) {
    if (gear_dynamics::stop_signal() != 0) {  // the parameter reads were cut short, not wrong
      gear_dynamics::warn_at_stop(std::string("gear_simulator: stopped by ") + gear_dynamics::stop_signal_name() +
                                  " while starting");
      return 0;
    }
    ROS_FATAL("%s", e.what());
    return 1;
  }
  return 0;
}
