// The condition monitor's detection study (doc/monitor_study.md): a healthy reference per load band,
// then held-out realizations (other random streams) of the gear with a root crack of increasing
// depth at each load, assessed window by window; from them each indicator's ROC and its area, the
// probability of detection against depth with Clopper-Pearson intervals and the a90/95 depth, and
// the detection delay of the per-window threshold and of the CUSUM. Also the monitor applied to a
// recorded series (a bag's or a batch's signal with its shaft angle). No ROS.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "gear_dynamics/monitor/reference.hpp"

namespace gear_dynamics {

// ---- statistics of a detector ----

// The area under the ROC of "positive if the score is above a threshold": the Mann-Whitney
// P(positive > negative) + P(tie)/2. Throws std::invalid_argument if either sample is empty.
double area_under_roc(const std::vector<double>& negatives, const std::vector<double>& positives);

struct RocPoint {
  double threshold = 0.0, false_positive = 0.0, true_positive = 0.0;
};
// The empirical ROC: one point per distinct score, from (0, 0) (threshold +inf) to (1, 1).
std::vector<RocPoint> roc_curve(const std::vector<double>& negatives, const std::vector<double>& positives);

struct ProportionInterval {
  double estimate = 0.0, low = 0.0, high = 0.0;
};
// The exact (Clopper-Pearson) two-sided interval of a binomial proportion, `successes` of `trials`.
ProportionInterval clopper_pearson(long successes, long trials, double confidence = 0.95);
// Its one-sided lower bound at `confidence`: MIL-HDBK-1823A's a90/95 is the depth where this
// bound of the probability of detection reaches 0.9.
double clopper_pearson_lower(long successes, long trials, double confidence = 0.95);

// ---- the study ----

struct StudySettings {
  ReferenceSettings reference;       // its load_means are the study's loads, one band each
  std::vector<double> crack_depths;  // [m] of the configured crack (gear, tooth, angle); 0 is healthy
  std::uint64_t first_test = 1000000;  // held-out streams first_test .. first_test + test_realizations - 1
  int test_realizations = 100;
};
// Throws std::invalid_argument naming the key, its value and the allowed range (the test streams
// must not overlap the reference's).
void validate(const StudySettings& settings);

// One (load, depth) case: every held-out run's assessed windows.
struct StudyCase {
  double load = 0.0, depth = 0.0;
  std::vector<std::vector<Assessment>> runs;
};

struct StudyResult {
  Reference reference;
  std::vector<StudyCase> cases;  // load-major, depths in the settings' order
  double window_seconds = 0.0;   // duration of one window [s]
  double cpu_reference = 0.0, cpu_simulation = 0.0, cpu_assessment = 0.0;  // [s] of this process
  long windows_assessed = 0;
};

// Runs the study for `config` (its crack's gear, tooth and angle; its depth set per case). The
// detectors: each indicator of indicator_table() and, after them, Hotelling's T² ("t2").
StudyResult run_study(const ModelConfig& config, const StudySettings& settings);
std::vector<std::string> detector_names(const Reference& reference);  // indicators, then "t2"

// A detector's per-window value and whether it was above its threshold.
double detector_value(const Assessment& a, std::size_t detector);
bool detector_alarm(const Assessment& a, std::size_t detector);

struct DetectionSummary {
  double load = 0.0, depth = 0.0;
  std::string detector;
  double auc = 0.5;            // against the healthy case at the same load (0.5 for it)
  long windows = 0, alarms = 0;
  ProportionInterval pod;      // two-sided 95 %; at depth 0 the measured false-alarm rate
  double pod_lower95 = 0.0;    // one-sided 95 % lower bound
  int runs = 0, runs_detected = 0;  // runs with an alarm within their windows
  double mean_delay_windows = 0.0;  // to the first alarm, over the runs detected (1 = the first window)
};
// One row per (case, detector), plus the CUSUM as the detector "cusum" (its alarm: S > h; no AUC).
std::vector<DetectionSummary> summarize(const StudyResult& result);
// The a90/95 depth of a detector at a load: the smallest depth of the grid from which on the
// one-sided 95 % lower bound of the PoD stays at or above 0.9; NaN if none.
double a90_95(const std::vector<DetectionSummary>& rows, double load, const std::string& detector);

// Writes <prefix>_summary.csv (the rows), <prefix>_roc.csv (every detector's ROC per case) and
// <prefix>_a9095.csv. Throws std::runtime_error naming a file it cannot write.
void write_study_csv(const std::string& prefix, const StudyResult& result);

// ---- the monitor over a recorded series ----

struct MonitoredWindow {
  std::int64_t index = 0;     // window number since the series' start (restarts included)
  double start_angle = 0.0;   // [rad] of the shaft angle
  Assessment assessment;
};
// Runs the monitor over a recorded signal: sample i is value[i] (the reference's signal) at shaft
// angle angle[i] (theta1 = phi0 + Omega t, rad) with the measured load load[i] (empty: all at the
// reference's first band). Cuts windows as RevolutionWindows (a gap restarts the window, not the
// run) and assesses them in order with one run's trends and CUSUM. Throws std::invalid_argument
// if the lengths differ.
std::vector<MonitoredWindow> monitor_series(const Reference& reference, const std::vector<double>& angle,
                                            const std::vector<double>& value, const std::vector<double>& load = {});

}  // namespace gear_dynamics
