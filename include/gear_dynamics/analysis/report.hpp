// The batch report: report.md with the paper's tables beside ours, and every number as CSV, in
// the paper's units (mm, mm/s, mm s^-1/2, mm/s^2). The figures are drawn from these CSVs by
// scripts/plot_report.py. No ROS.
#pragma once

#include <string>
#include <vector>

#include "gear_dynamics/analysis/batch_analysis.hpp"
#include "gear_dynamics/config/config.hpp"
#include "gear_dynamics/config/sweep.hpp"

namespace gear_dynamics {

// SI -> the paper's units: m -> mm, m/s -> mm/s, m s^-1/2 -> mm s^-1/2 (sqrt(1e3 * 1e3)),
// m/s^2 -> mm/s^2 (doc/model.md §1).
constexpr double kToPaperUnits = 1e3;

// A bag the reader did not use, and why.
struct SkippedFile {
  std::string file, reason;
};

// What reading one or more batch folders gave: the runs and everything left out.
struct BatchInputs {
  std::vector<std::string> folders;
  ModelConfig config;                 // the batch's model configuration (from its manifests)
  std::size_t expected_runs = 0;      // distinct runs listed in the manifests
  std::vector<RunRecord> runs;        // one per usable bag
  std::vector<SkippedFile> skipped;   // bags left out, with the reason
  std::vector<std::string> missing;   // listed runs without a usable bag (or notes on missing shards)
  // The study grid: axis 0 is gear_pair.friction_coefficient; points[i] holds point i's value on
  // every axis (RunRecord::point). A format-1 folder is the mu sweep: one point per mu, ascending.
  std::vector<SweepAxis> axes;
  std::vector<std::vector<double>> points;
};

// Writes report.md and the CSV files into `folder` (created if needed). Throws std::runtime_error
// if a file cannot be written. The names of the files written are returned.
// With `study` (analyse_batch), also points.csv and axis_tests.csv; a study with more axes than mu
// gets its report.md organised by axis (study_analysis.hpp) instead of the paper's tables.
// `sections` (markdown, from a layer above: the analyses over time) go into report.md before its
// figure table.
struct StudyAnalysis;
std::vector<std::string> write_report(const std::string& folder, const BatchInputs& inputs,
                                      const BatchAnalysis& analysis, const StudyAnalysis* study = nullptr,
                                      const std::string& sections = "");

}  // namespace gear_dynamics
