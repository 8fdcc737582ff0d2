// The Monte Carlo analysis of a batch (doc/model.md §6, §8): from one fixed-size record per run to
// the statistics per friction coefficient and the tests across them. SI units throughout; the
// report converts to the paper's units. No ROS.
#pragma once

#include <yaml-cpp/yaml.h>

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "gear_dynamics/batch/run_record.hpp"
#include "gear_dynamics/maths/statistics.hpp"
#include "gear_dynamics/config/analysis_settings.hpp"

namespace gear_dynamics {

// Statistics of one friction coefficient.
struct MuAnalysis {
  double mu = 0;
  std::optional<RunRecord> s1;  // the deterministic run at the configured phase
  std::size_t stochastic_runs = 0, phase_runs = 0;
  // Stochastic realizations.
  BoxStats center_distance, steady_state_time, steady_state_time_fine, final_delta, final_delta_dot;
  std::optional<double> s2_center_distance, s3_center_distance;  // realizations 0 and 1 (Fig. 8)
  Proportion d_exceeds_s1;           // P(d > d_S1), strict (the paper's 93 % statement)
  Proportion d_exceeds_phase_median; // P(d > median of the phase ensemble's d) (doc/model.md §6)
  Proportion reached_steady_state;   // P(t_ss < T)
  Proportion delta_in_interval, delta_dot_in_interval;  // Table 4
  Histogram delta_pdf, delta_dot_pdf;                   // Figs. 11, 12 (at T)
  std::vector<Histogram2D> joint_pdf;                   // Fig. 10, one per joint time
  // Deterministic phase ensemble (doc/model.md §6).
  BoxStats phase_center_distance, phase_steady_state_time, phase_final_delta, phase_final_delta_dot;
};

struct BatchAnalysis {
  AnalysisSettings settings;
  std::vector<MuAnalysis> mu;  // ascending mu
  // Does d of the stochastic realizations differ across mu? Kruskal-Wallis treats the groups as
  // independent; the batch uses common random numbers (realization r shares its load path across
  // mu), so Friedman's test, blocked by realization, is the one that matches the design.
  RankTest kruskal_wallis, friedman;
  // How the CSV rows are keyed: empty for the mu sweep (a column `mu`); for a study with more axes
  // "point,mu,<key>..." and one such text per entry of `mu` (analyse_batch, study_analysis.hpp).
  std::string key_header;
  std::vector<std::string> keys;
};

// The statistics of one group of runs (one mu, or one study point); `mu` labels it.
MuAnalysis analyse_group(double mu, const std::vector<const RunRecord*>& runs, const AnalysisSettings& settings);

// Groups the records by mu (exact value, as written by the batch) and computes everything.
// Throws std::invalid_argument if a joint time is not among a stochastic run's snapshot times.
BatchAnalysis analyse(const std::vector<RunRecord>& runs, const AnalysisSettings& settings);

}  // namespace gear_dynamics
