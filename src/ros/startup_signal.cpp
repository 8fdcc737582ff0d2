#include "gear_dynamics/ros/startup_signal.hpp"

#include <ros/console.h>
#include <ros/init.h>

#include <csignal>
#include <cstdio>

namespace gear_dynamics {

namespace {
volatile std::sig_atomic_t g_sigint = 0;

extern "C" void on_sigint(int) {
  g_sigint = 1;
  ros::requestShutdown();  // what roscpp's handler does: sets a flag its threads poll
}
}  // namespace

void install_sigint_handler() { std::signal(SIGINT, on_sigint); }

bool sigint_received() { return g_sigint != 0; }

void warn_at_stop(const std::string& line) {
  if (ros::isShuttingDown())
    std::fprintf(stderr, "[ WARN] %s\n", line.c_str());
  else
    ROS_WARN("%s", line.c_str());
}

}  // namespace gear_dynamics
