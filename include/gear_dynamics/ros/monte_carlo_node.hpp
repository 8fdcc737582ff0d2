// gear_monte_carlo as a class: runs a Monte Carlo batch (doc/model.md §4, §6) into a folder of
// bags (the batch folder contract of doc/batch-folder.md), resumable, shardable, interruptible, with
// progress on ~progress. The node's main (src/nodes/gear_monte_carlo.cpp) is a few lines.
#pragma once

#include <ros/ros.h>

#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <mutex>
#include <vector>

#include "gear_dynamics/BatchProgress.h"
#include "gear_dynamics/config/batch_settings.hpp"
#include "gear_dynamics/config/config.hpp"
#include "gear_dynamics/montecarlo/batch.hpp"

namespace gear_dynamics {

class BagSink;

class MonteCarloNode {
 public:
  explicit MonteCarloNode(ros::NodeHandle& private_nh) : pnh_(private_nh) {}

  // Loads and validates the configuration and prepares the folder: 0, or the process exit code
  // (logged): 2 if refused, 128 + signal if SIGINT or SIGTERM came during it (a signal interrupts
  // the parameter reads from the master, which must not pass for missing parameters).
  int init();
  // Runs the batch; the process exit code (0 complete, 1 failed, 128 + signal when interrupted).
  int run();

 private:
  double elapsed() const;
  // Turns a signal or a ROS shutdown into a stop, publishes progress every second, logs it every
  // few seconds.
  void watch(const BagSink& sink);
  BatchProgress publish(const BagSink& sink, bool finished);

  ros::NodeHandle& pnh_;
  ros::Publisher progress_pub_;
  ModelConfig model_;
  Study study_;  // the points of the batch (one per mu without a sweep)
  BatchSettings settings_;
  std::vector<RunSpec> runs_, todo_;
  BatchControl control_;
  std::int64_t total_steps_ = 0;
  std::chrono::steady_clock::time_point start_;
  std::mutex mutex_;
  std::condition_variable wake_;
  bool finished_ = false;
};

}  // namespace gear_dynamics
