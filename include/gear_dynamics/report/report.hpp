// The batch report, the top of the pipeline read -> analyse -> report: report.md with the paper's
// tables beside ours, and every number as CSV, in the paper's units (mm, mm/s, mm s^-1/2,
// mm/s^2). The figures are drawn from these CSVs by scripts/plot_report.py. No ROS.
#pragma once

#include <string>
#include <vector>

#include "gear_dynamics/analysis/batch_analysis.hpp"
#include "gear_dynamics/analysis/over_time.hpp"
#include "gear_dynamics/analysis/study_analysis.hpp"

namespace gear_dynamics {

// SI -> the paper's units: m -> mm, m/s -> mm/s, m s^-1/2 -> mm s^-1/2 (sqrt(1e3 * 1e3)),
// m/s^2 -> mm/s^2 (doc/model.md §1).
constexpr double kToPaperUnits = 1e3;

// Writes the batch report into `folder` (created if needed): the CSV files of the analysis, with
// `study` (analyse_batch) points.csv and axis_tests.csv, with `over_time` (analyse_over_time) the
// files over time, and report.md with the paper's tables beside ours (a study with more axes than
// mu gets its report.md organised by axis instead) and the sections over time before its figure
// table. series.csv is FigureSeries' (report/series_csv.hpp). Throws std::runtime_error if a file
// cannot be written. The names of the files written are returned.
std::vector<std::string> write_report(const std::string& folder, const BatchInputs& inputs,
                                      const BatchAnalysis& analysis, const StudyAnalysis* study = nullptr,
                                      const BatchOverTime* over_time = nullptr);

}  // namespace gear_dynamics
