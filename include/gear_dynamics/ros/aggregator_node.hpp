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
  // Figures from the CSV files (scripts/plot_report.py --wait); a failure costs the figures, not the
  // report. The script is started before the wait and the reading, so that Python and matplotlib
  // are loaded by the time the CSV files are there; plot(true) lets it draw and waits
  // for it, plot(false) lets it end without drawing. Only the first call acts.
  void start_plot();
  void plot(bool draw);

  ros::NodeHandle private_nh_;
  AggregatorSettings settings_;
  std::string report_folder_;
  ros::Publisher publisher_;
  pid_t plot_pid_ = -1;  // the started plot script, -1: none
  int plot_go_ = -1;     // the write end of its stdin: a line there means draw, EOF means end
};

}  // namespace gear_dynamics
