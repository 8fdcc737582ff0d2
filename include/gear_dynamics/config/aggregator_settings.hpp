// gear_aggregator's own private parameters (~folders, ~report_folder, ...) and its `analysis`
// section: what the node reads, declared like every other section (section.hpp), without ROS.
#pragma once

#include <yaml-cpp/yaml.h>

#include <string>
#include <vector>

#include "gear_dynamics/config/analysis_settings.hpp"
#include "gear_dynamics/config/section.hpp"

namespace gear_dynamics {

struct AggregatorSettings {
  std::vector<std::string> folders;        // batch folders (shards of one batch); required
  std::string report_folder;               // empty: FIRST_FOLDER/report
  bool wait_for_batch = false;             // wait until the batch is complete or its node has ended
  std::string batch_node = "/gear_monte_carlo";
  double wait_timeout = 0.0;               // [s] give up waiting after this long; 0 = no limit
  std::string plot_script;                 // scripts/plot_report.py, or empty: no figures
  double series_mu = 0.04;                 // mu whose S1, S2, S3 series go to series.csv
  bool exit_when_done = false;             // exit after the report instead of latching it
  AnalysisSettings analysis;

  // Where the report goes: report_folder, or FIRST_FOLDER/report.
  std::string report_dir() const;
};

// The declaration of the node's own keys (the section "aggregator", "~key" in messages).
const Section<AggregatorSettings>& aggregator_section();

// Validates the node's private parameters as one YAML map: its own keys and the map `analysis`.
// Unknown keys are refused. Throws ConfigError listing every problem.
AggregatorSettings parse_aggregator_settings(const YAML::Node& params);

}  // namespace gear_dynamics
