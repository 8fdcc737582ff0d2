// SIGINT and SIGTERM as a node's stop request, remembered. A signal while a node starts interrupts
// its parameter reads (XML-RPC calls to the master), which then look like missing parameters: a
// node that fails to start asks stop_signal() before it reports bad input.
#pragma once

#include <string>

namespace gear_dynamics {

// How a node stops on SIGINT.
enum class OnSigint {
  RequestShutdown,  // roscpp's own behaviour (ros::spin returns); SIGTERM keeps its default action
  // The same for SIGTERM (roslaunch's second signal, `kill`): a node whose destructors must run
  // (the live node closes its bag and states its count).
  RequestShutdownAlsoSigterm,
  OnlyRemember,     // the node polls stop_signal() and stops its work cleanly; SIGTERM the same
};

// Call right after ros::init(..., ros::init_options::NoSigintHandler).
void install_stop_handlers(OnSigint on_sigint);

// ros::start() (the first NodeHandle) clears a shutdown request made before it: with
// RequestShutdown, call after the first NodeHandle, so that a SIGINT that came earlier still stops
// the node instead of leaving it running.
void repeat_early_stop();

int stop_signal();                // 0, or the last SIGINT or SIGTERM received
const char* stop_signal_name();  // "SIGINT" or "SIGTERM"

// ROS_INFO / ROS_WARN / ROS_ERROR, or straight to stderr once roscpp has begun to shut down: its
// shutdown turns rosconsole off, and a node's last words (why it stops without its product, what
// its bag holds) would be lost.
enum class StopLog { Info, Warn, Error };
void log_at_stop(StopLog level, const std::string& line);
inline void warn_at_stop(const std::string& line) { log_at_stop(StopLog::Warn, line); }

}  // namespace gear_dynamics
