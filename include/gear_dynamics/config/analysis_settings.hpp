// The `analysis` section of config/aggregator.yaml: the safety intervals, histogram bins and
// confidence level of the batch analysis (doc/model.md §8). SI units.
#pragma once

#include <yaml-cpp/yaml.h>

#include <cstddef>
#include <string>
#include <vector>

#include "gear_dynamics/config/section.hpp"
#include "gear_dynamics/maths/statistics.hpp"  // BinSpec, Interval, kConfidence

namespace gear_dynamics {

// The analysis parameters (the `analysis` section of config/aggregator.yaml), SI units.
struct AnalysisSettings {
  double confidence = kConfidence;
  Interval delta_interval{4.0e-5, 5.5e-5};       // Table 4 [m]
  Interval delta_dot_interval{-0.016, 0.016};    // Table 4 [m/s]
  BinSpec delta_bins{3.0e-5, 6.0e-5, 5.0e-7};    // Fig. 11 [m]
  BinSpec delta_dot_bins{-0.040, 0.040, 0.002};  // Fig. 12 [m/s]
  BinSpec joint_delta_bins{3.0e-5, 6.0e-5, 1.0e-6};     // Fig. 10 [m]
  BinSpec joint_delta_dot_bins{-0.040, 0.040, 0.004};   // Fig. 10 [m/s]
  std::vector<double> joint_times{0.30, 0.33, 0.36, 0.40};  // Fig. 10 [s], among the snapshot times
  // Over time (doc/gear_aggregator.md §5): first passage counts exits from this time on [s]; the
  // spectrum drops the start-up before this time [s], the Poincare section before poincare_transient; KDEs beside the histograms of Figs. 11, 12.
  double first_passage_settle = 0.30;
  double spectrum_transient = 0.10;
  double poincare_transient = 0.20;  // the phase ensemble's Poincare section starts here [s]
  bool kde = true;
};

// The declaration of the `analysis` section.
const Section<AnalysisSettings>& analysis_section();

// Reads and validates the `analysis` section of `root` (every key required; unknown keys, wrong
// types and bad values are errors naming the key, the value and the allowed range). Throws
// ConfigError.
AnalysisSettings parse_analysis_settings(const YAML::Node& root);
// The same, adding its messages to `errors` instead of throwing (for a node that reads more).
AnalysisSettings read_analysis_settings(const YAML::Node& root, std::vector<std::string>& errors);
YAML::Node to_yaml(const AnalysisSettings& settings);

}  // namespace gear_dynamics
