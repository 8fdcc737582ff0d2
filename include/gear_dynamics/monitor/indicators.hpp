// Gear condition indicators (doc/monitor.md): the time-synchronous average (TSA) of a signal over
// the revolutions of the monitored gear, resampled by the shaft angle, its regular, residual,
// difference and envelope signals, and the indicators of the practice (RMS, kurtosis, crest
// factor, FM0, FM4, M6A, M8A, NA4, NA4*, NB4, energy ratio, sideband level and index), all
// declared in one table (indicator_table). Works on any sampled signal with its angle. No ROS.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <limits>
#include <optional>
#include <string>
#include <vector>

namespace gear_dynamics {

// How a TSA of one revolution of the monitored gear is split into orders (multiples of its shaft
// frequency): its mesh order is its number of teeth.
struct IndicatorSettings {
  int teeth = 20;                     // teeth of the monitored gear = its mesh order
  int samples_per_revolution = 640;   // TSA points per revolution
  int shaft_orders = 2;               // shaft orders 1..n taken out of the residual signal
  int sideband_orders = 1;            // sidebands m*teeth +- 1..n taken out of the difference signal
  int envelope_band = 0;              // NB4's band: mesh order +- this many orders; 0: teeth / 2
  int band() const { return envelope_band > 0 ? envelope_band : teeth / 2; }
};
// Throws std::invalid_argument naming the setting, its value and the allowed range.
void validate(const IndicatorSettings& settings);

// The signals of one TSA (each samples_per_revolution long) and its amplitude spectrum by order.
struct GearSignals {
  int mesh_order = 0;          // the monitored gear's teeth
  Eigen::VectorXd tsa;         // the average itself
  Eigen::VectorXd regular;     // mesh order and its harmonics only (zero mean)
  Eigen::VectorXd residual;    // tsa - mean - shaft orders - mesh harmonics
  Eigen::VectorXd difference;  // residual - the sidebands of every mesh harmonic
  Eigen::VectorXd envelope;    // |analytic signal| of the band mesh order +- band()
  Eigen::VectorXd amplitude;   // single-sided amplitude of order k = 0 .. N/2 (signal's unit)
};
GearSignals decompose(const Eigen::VectorXd& tsa, const IndicatorSettings& settings);

// What an indicator sees besides its window's signals: the run's trend of the variances (NA4,
// NB4: the mean over this run's windows so far, this one included) and a healthy baseline.
struct IndicatorContext {
  double residual_variance_trend = 0.0;
  double envelope_variance_trend = 0.0;
  double baseline_residual_variance = 0.0;  // NA4*: from a healthy reference; NaN if none
};

// One indicator: the table below is the one place to declare one (doc/architecture.md).
struct IndicatorSpec {
  const char* name;
  const char* unit;  // "-" dimensionless, "signal" the monitored signal's unit
  const char* description;
  double (*compute)(const GearSignals&, const IndicatorContext&);
};
const std::vector<IndicatorSpec>& indicator_table();
std::vector<std::string> indicator_names();
// Index of `name` in indicator_table(); throws std::invalid_argument listing the names.
std::size_t indicator_index(const std::string& name);

// Normalised moments N^(k/2-1) sum (x - mean)^k / (sum (x - mean)^2)^(k/2): 3 for k = 4 is a
// Gaussian's kurtosis. FM4, M6A and M8A are these of the difference signal.
double normalized_moment(const Eigen::VectorXd& x, int k);
double variance(const Eigen::VectorXd& x);  // population variance (divides by N)

// The indicators of a run's successive windows: keeps the NA4 and NB4 trends.
class IndicatorTracker {
 public:
  explicit IndicatorTracker(const IndicatorSettings& settings,
                            double baseline_residual_variance = std::numeric_limits<double>::quiet_NaN());
  // Every indicator of indicator_table(), in its order, for the next window's TSA.
  std::vector<double> window(const Eigen::VectorXd& tsa);
  // Same, also returning the window's signals.
  std::vector<double> window(const Eigen::VectorXd& tsa, GearSignals& signals);
  void reset();
  // NA4*'s healthy residual variance from the next window on (a reference per load band).
  void set_baseline(double baseline_residual_variance) { baseline_ = baseline_residual_variance; }
  int windows() const { return windows_; }
  const IndicatorSettings& settings() const { return settings_; }

 private:
  IndicatorSettings settings_;
  double baseline_;
  double residual_sum_ = 0.0, envelope_sum_ = 0.0;
  int windows_ = 0;
};

// One window of whole revolutions: the TSA and the mean of the load samples inside it.
struct RevolutionWindow {
  Eigen::VectorXd tsa;
  double mean_load = 0.0;
  double start_angle = 0.0;  // [rad] of the tachometer's angle
  std::int64_t index = 0;    // windows since the last restart
};

// Streams samples (angle, value, load) into TSAs of `revolutions` whole revolutions each, aligned
// to angle 0 (mod one revolution), so a tooth keeps its place in every window. Each TSA point is
// the linear interpolation between the samples around its angle. A sample whose angle does not
// increase, or jumps by more than a revolution, restarts the collection (a gap in the input).
class RevolutionWindows {
 public:
  RevolutionWindows(double revolution_angle, int revolutions, int samples_per_revolution);
  // The window this sample completed, if it completed one.
  std::optional<RevolutionWindow> add(double angle, double value, double load = 0.0);
  void restart();
  std::int64_t restarts() const { return restarts_; }

 private:
  double revolution_, step_;
  int revolutions_, samples_;
  bool have_previous_ = false, started_ = false;
  double angle0_ = 0.0, value0_ = 0.0;
  double window_start_ = 0.0;
  std::int64_t next_ = 0;  // grid points done in this window
  Eigen::VectorXd sum_;
  double load_sum_ = 0.0;
  std::int64_t load_count_ = 0, index_ = 0, restarts_ = 0;
};

// The TSA over every whole revolution (aligned to angle 0) that the samples cover; revolutions
// set to their number. Throws std::invalid_argument if they cover none.
Eigen::VectorXd time_synchronous_average(const std::vector<double>& value, const std::vector<double>& angle,
                                         double revolution_angle, int samples_per_revolution,
                                         int* revolutions = nullptr);

}  // namespace gear_dynamics
