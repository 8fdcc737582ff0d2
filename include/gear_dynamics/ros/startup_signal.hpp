// Ctrl-C while a node starts or waits. A SIGINT during the parameter reads interrupts their
// XML-RPC calls to the master, which then look like missing parameters; a node that fails to start
// asks sigint_received() before it reports bad input.
#pragma once

#include <string>

namespace gear_dynamics {

// roscpp's own SIGINT handling (a shutdown request) that also remembers the signal. Call right
// after ros::init(..., ros::init_options::NoSigintHandler).
void install_sigint_handler();

bool sigint_received();

// ROS_WARN, or straight to stderr once roscpp has begun to shut down: its shutdown turns rosconsole
// off, and a node's last words (why it stops without its product) would be lost.
void warn_at_stop(const std::string& line);

}  // namespace gear_dynamics
