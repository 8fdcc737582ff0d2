// series.csv of the batch report (Figs. 5-7): the whole /gear/state series of S1, S2 and S3
// (realizations 0 and 1) at one friction coefficient, in the paper's units, one row per state and
// the runs in the batch's listed order. Each run's rows wait in a file of their own until write(),
// so memory does not grow with the series. No ROS.
#pragma once

#include <string>
#include <vector>

#include "gear_dynamics/batch/run_record.hpp"

namespace gear_dynamics {

class FigureSeries {
 public:
  // Into `folder` (which must exist), the runs at friction `mu` (to 1e-12 relative).
  FigureSeries(std::string folder, double mu);
  ~FigureSeries();  // removes the rows of runs not written
  FigureSeries(const FigureSeries&) = delete;
  FigureSeries& operator=(const FigureSeries&) = delete;

  // Whether a run of this kind, friction and realization (or phase index) is one of the figures'.
  bool wants(RunKind kind, double mu, std::uint32_t index) const;
  // Keeps one run's rows (one call at a time). Throws std::runtime_error if they cannot be kept.
  void add(const RunRecord& run, const RunSeries& series);
  // Writes series.csv: the rows of the runs added, in the order of `runs` (the batch's runs used,
  // BatchInputs::runs). Returns its path; throws std::runtime_error if it cannot be written.
  std::string write(const std::vector<RunRecord>& runs);

 private:
  std::string part(const std::string& run) const;

  std::string folder_;
  double mu_;
  std::vector<std::string> parts_;  // names of the runs whose rows wait in a part file
};

}  // namespace gear_dynamics
