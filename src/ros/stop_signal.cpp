#include "gear_dynamics/ros/stop_signal.hpp"

#include <ros/console.h>
#include <ros/init.h>

#include <csignal>
#include <cstdio>

namespace gear_dynamics {

namespace {
volatile std::sig_atomic_t g_signal = 0;

extern "C" void remember(int sig) { g_signal = sig; }

extern "C" void remember_and_shut_down(int sig) {
  g_signal = sig;
  ros::requestShutdown();  // what roscpp's handler does: sets a flag its threads poll
}
}  // namespace

void install_stop_handlers(OnSigint on_sigint) {
  if (on_sigint == OnSigint::RequestShutdown) {
    std::signal(SIGINT, remember_and_shut_down);
  } else if (on_sigint == OnSigint::RequestShutdownAlsoSigterm) {
    std::signal(SIGINT, remember_and_shut_down);
    std::signal(SIGTERM, remember_and_shut_down);
  } else {
    std::signal(SIGINT, remember);
    std::signal(SIGTERM, remember);
  }
}

void repeat_early_stop() {
  if (g_signal != 0) ros::requestShutdown();
}

int stop_signal() { return g_signal; }

const char* stop_signal_name() { return g_signal == SIGTERM ? "SIGTERM" : "SIGINT"; }

void log_at_stop(StopLog level, const std::string& line) {
  if (ros::isShuttingDown()) {
    const char* tag = level == StopLog::Info ? "[ INFO]" : level == StopLog::Warn ? "[ WARN]" : "[ERROR]";
    std::fprintf(stderr, "%s %s\n", tag, line.c_str());
    return;
  }
  switch (level) {
    case StopLog::Info: ROS_INFO("%s", line.c_str()); break;
    case StopLog::Warn: ROS_WARN("%s", line.c_str()); break;
    case StopLog::Error: ROS_ERROR("%s", line.c_str()); break;
  }
}

}  // namespace gear_dynamics
