// The analysis of a study (doc/studies.md): every statistic of batch_analysis per grid point, and
// along each swept axis with the other axes fixed, whether the axis matters (Friedman blocked by
// realization, which matches the common random numbers, and Kruskal-Wallis beside it). The mu
// sweep is the study with one axis: its per-mu analysis and report stay as they were. No ROS.
#pragma once

#include <string>
#include <vector>

#include "gear_dynamics/analysis/batch_analysis.hpp"

namespace gear_dynamics {

struct PointAnalysis {
  std::size_t point = 0;
  std::vector<double> values;          // one per axis
  MuAnalysis stats;                    // everything a mu gets in the mu sweep
  Proportion both_in_interval;         // P(delta(T) in I and delta_dot(T) in I), stochastic runs
  double final_phi_mean = 0, final_phi_sd = 0;  // Phi(T) of the stochastic runs [m/s^2]
};

// One line of the grid: `axis` varies over `points` (in the axis' order), the others are fixed.
struct AxisSlice {
  std::size_t axis = 0;
  std::vector<std::size_t> points;
  std::vector<double> fixed;  // every axis' value on the line (the varying axis' entry is NaN)
  RankTest kruskal_wallis, friedman;  // on d of the stochastic runs
};

struct StudyAnalysis {
  std::vector<SweepAxis> axes;
  std::vector<PointAnalysis> points;  // by point index
  std::vector<AxisSlice> slices;      // for every axis with more than one value
  bool swept() const { return axes.size() > 1; }
};

StudyAnalysis analyse_study(const BatchInputs& inputs, const AnalysisSettings& settings);

// The per-mu analysis a report is written from: for the mu sweep exactly analyse(); for a study
// with more axes one entry per point (in point order, labelled by the point in every CSV) and the
// rank tests across all points.
BatchAnalysis analyse_batch(const BatchInputs& inputs, const AnalysisSettings& settings, StudyAnalysis& study);

}  // namespace gear_dynamics
