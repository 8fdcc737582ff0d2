// gear_aggregator: reads Monte Carlo batch folders, computes the paper's statistics with their
// uncertainty (core: batch_analysis, report), writes the report folder, draws the figures and
// latches a BatchReport on ~report. A thin wrapper: every number comes from the core library, every
// parameter from AggregatorSettings (config/aggregator_settings.hpp).
#pragma once

#include <ros/ros.h>

#include "gear_dynamics/config/aggregator_settings.hpp"

namespace gear_dynamics {

class AggregatorNode {
 public:
  // Reads and validates the private parameters; throws ConfigError naming every bad key before
  // anything is advertised.
  explicit AggregatorNode(const ros::NodeHandle& private_nh);

  // Waits for the batch if asked, then reads, analyses, writes and publishes. False (logged) on
  // failure.
  bool run();

  const AggregatorSettings& settings() const { return settings_; }

 private:
  // Until every folder's manifest lists only finished bags, or the batch node has come and gone
  // (it failed or was stopped: what it left is aggregated, the rest reported missing).
  bool wait();
  // Figures from the CSV files (scripts/plot_report.py); a failure costs the figures, not the report.
  void plot() const;

  ros::NodeHandle private_nh_;
  AggregatorSettings settings_;
  std::string report_folder_;
  ros::Publisher publisher_;
};

}  // namespace gear_dynamics
