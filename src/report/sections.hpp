// The report's parts that write_report (report/report.hpp) puts together; internal to the report
// layer.
#pragma once

#include <string>
#include <vector>

#include "gear_dynamics/analysis/over_time.hpp"
#include "gear_dynamics/analysis/study_analysis.hpp"
#include "gear_dynamics/report/report.hpp"

namespace gear_dynamics {

// Writes safety_over_time.csv, first_passage.csv, survival.csv, spectrum_band.csv,
// spectrum_peaks.csv, spectrum_info.csv, poincare.csv and (with analysis.kde) kde.csv, in the paper's units;
// returns the report.md section. Throws std::runtime_error if a file cannot be written.
std::string write_over_time(const std::string& folder, const BatchInputs& inputs, const BatchAnalysis& analysis,
                            const BatchOverTime& over_time, std::vector<std::string>& written);

// Writes points.csv (one row per point, one column per axis, every statistic) and axis_tests.csv
// (one row per line of the grid); for a study with more axes also report.md organised by axis,
// with `sections` (markdown, the analyses over time) before its figure list.
void write_study_files(const std::string& folder, const BatchInputs& inputs, const StudyAnalysis& study,
                       const AnalysisSettings& settings, std::vector<std::string>& written,
                       const std::string& sections);

}  // namespace gear_dynamics
