// The healthy reference of the condition monitor (doc/monitor.md §4): the indicators of a healthy
// gear per window over independent realizations of the stochastic load, per load band; thresholds
// for a stated false-alarm probability per window (per-indicator quantiles and Hotelling's T² on
// the standardised indicator vector); a CUSUM on T²'s normal scores for persistence with a stated
// in-control average run length; the versioned file that holds them, refused with the reason when
// it does not match the monitored gear; and the monitor that applies them window by window. No ROS.
#pragma once

#include <yaml-cpp/yaml.h>

#include <Eigen/Core>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

#include "gear_dynamics/config/config.hpp"
#include "gear_dynamics/engine/bearings.hpp"
#include "gear_dynamics/model/mesh_schedule.hpp"
#include "gear_dynamics/monitor/indicators.hpp"

namespace gear_dynamics {

constexpr const char* kReferenceFormat = "gear_dynamics_monitor_reference/1";

// A reference file that cannot be read, breaks the schema, or does not fit the monitored gear:
// the message names the file and the reason.
class ReferenceError : public std::runtime_error {
 public:
  explicit ReferenceError(const std::string& what) : std::runtime_error(what) {}
};

// The signals the monitor takes, one row each of monitored_signals() in this order.
enum class MonitoredSignal { kDelta, kMeshForce, kPinionFx, kPinionFy, kWheelFx, kWheelFy };

// One monitored signal (doc/architecture.md, "A monitored signal"). delta and the mesh force come
// from a state, in every model; a bearing force is the bearings model's output of the same name
// (kBearingsOutputs), and on ROS the force.x (across the line of action) or force.y (along it) of
// its body's bearing wrench, `wrench_topic` (geometry_msgs/WrenchStamped, the batch bags' message).
struct MonitoredSignalSpec {
  MonitoredSignal signal;
  const char* name;  // the value of --signal, monitor_study.signal and the reference file
  const char* unit;  // SI
  const char* description;
  double BearingsOutputs::*bearing_force;  // the bearings model's output; null: from the state
  const char* wrench_topic;                // relative to the simulator's namespace; null: from the state
  bool across;                             // the wrench's force.x; else force.y
};
const std::vector<MonitoredSignalSpec>& monitored_signals();
const MonitoredSignalSpec& signal_spec(MonitoredSignal signal);
const char* to_string(MonitoredSignal signal);
// Throws std::invalid_argument naming the key, the value and the allowed names.
MonitoredSignal parse_monitored_signal(const std::string& text, const std::string& key = "monitor.signal");
// Throws std::invalid_argument naming the signal and the model when `model` does not produce it
// (a bearing force of the torsional model).
void require_signal(MonitoredSignal signal, GearModel model);
// A bearing force's component of its wrench's force (x, y) [N].
inline double wrench_component(const MonitoredSignalSpec& spec, double force_x, double force_y) {
  return spec.across ? force_x : force_y;
}

// What is monitored and how it is cut into windows.
struct MonitorSettings {
  MonitoredSignal signal = MonitoredSignal::kDelta;
  FaultyGear gear = FaultyGear::kPinion;  // whose revolutions the TSA follows (not kNone)
  int revolutions_per_window = 1;
  int samples_per_revolution = 640;
  int shaft_orders = 2, sideband_orders = 1, envelope_band = 0;  // IndicatorSettings
  int decimation = 10;  // one sample every this many grid steps (simulated signals)
};

// How the reference is made.
struct ReferenceSettings {
  MonitorSettings monitor;
  std::uint64_t first_realization = 0;  // streams first .. first + realizations - 1
  int realizations = 256;
  int windows = 1;                    // per realization, after the warm-up
  double warmup = 0.1;                // [s] discarded from rest
  double false_alarm = 0.05;          // per window, of each threshold
  double average_run_length = 200.0;  // the CUSUM's in-control ARL [windows]
  double cusum_reference = 0.5;       // k, in standard deviations of the score
  std::vector<double> load_means;     // one band per mean load [m/s^2]; empty: load.initial_mean
};
// Throws std::invalid_argument naming the key, its value and the allowed range.
void validate(const ReferenceSettings& settings);

// The gear's geometry the windows need.
double revolution_angle(const GearPair& gear, FaultyGear which);  // [rad] of theta1
int monitored_teeth(const GearPair& gear, FaultyGear which);
double shaft_angle(const GearPair& gear, double t);  // theta1 = phi0 + Omega t [rad]
IndicatorSettings indicator_settings(const GearPair& gear, const MonitorSettings& settings);
// A signal taken from a state: delta [m], or the mesh force the kernel integrates
// (gear_pair.hpp's mesh_force) [N] from the state's K, delta and delta_dot and the schedule's e and
// its rate at the state's time. Throws std::invalid_argument for a bearing force (its model's
// outputs or its wrench hold it).
double state_signal(const GearPair& gear, MonitoredSignal signal, double stiffness, double error, double error_rate,
                    double delta, double delta_dot);

// Runs stochastic realizations first .. first + count - 1 of `config` and returns each one's first
// `windows` windows that start after `warmup`.
std::vector<std::vector<RevolutionWindow>> simulate_windows(const ModelConfig& config, const MonitorSettings& settings,
                                                            std::uint64_t first, int count, double warmup, int windows);

// The reference of one load band: windows whose mean load is in [load_low, load_high); the lowest
// band starts and the highest ends at the extreme mean load of the reference's own windows.
struct ReferenceBand {
  double load = 0.0, load_low = 0.0, load_high = 0.0;  // nominal mean and edges [m/s^2]
  std::size_t windows = 0;
  std::vector<double> mean, sd, threshold;  // per indicator; threshold: upper (1 - alpha) quantile
  Eigen::MatrixXd inverse_correlation;      // pseudo-inverse of the indicators' correlation
  int rank = 0;
  double t2_threshold = 0.0;    // (1 - alpha) quantile of the reference windows' T²
  double t2_threshold_f = 0.0;  // the same from the F distribution, were the indicators normal
  std::vector<double> t2;       // every reference window's T², sorted: the CUSUM's scores
  double baseline_residual_variance = 0.0;  // NA4*'s denominator
};

struct Reference {
  std::string package_version;
  int numbers = 0;
  YAML::Node config;  // the model it was made from (to_yaml)
  ReferenceSettings settings;
  std::vector<std::string> indicators;  // indicator_names() when made
  double cusum_threshold = 0.0;         // h, for settings.average_run_length by Siegmund
  std::vector<ReferenceBand> bands;
  // Whether a mean load lies within the reference's windows' loads (bands' outer edges included).
  bool covers(double load) const;
  // The band of a window's mean load (the nearest one outside the reference's loads).
  std::size_t band_of(double load) const;
};

// Makes the reference for `healthy` (its faults are ignored: the reference is of the healthy gear).
Reference build_reference(const ModelConfig& healthy, const ReferenceSettings& settings);

void write_reference(const std::string& path, const Reference& reference);
std::string reference_text(const Reference& reference);
// Reads and checks the schema, its format, numbers generation and indicator names. Throws ReferenceError.
Reference read_reference(const std::string& path);
// Refuses (ReferenceError naming `path`, the key and both values) a reference made for another
// gear: any gear_pair key differs other than the faults (crack_*, spall_*), which are what is monitored.
void check_reference(const Reference& reference, const ModelConfig& monitored, const std::string& path);

// Hotelling's T² of an indicator vector in a band (standardised, pseudo-inverse).
double hotelling_t2(const ReferenceBand& band, const std::vector<double>& indicators);
// The normal score Phi^-1 of T²'s mid-rank among the band's reference windows.
double t2_score(const ReferenceBand& band, double t2);

// Siegmund's approximation of a one-sided CUSUM's average run length on N(mu, 1) increments with
// reference k and threshold h: (exp(-2 D b) + 2 D b - 1) / (2 D^2), D = mu - k, b = h + 1.166.
double siegmund_arl(double k, double h, double mu = 0.0);
// The h whose in-control (mu = 0) Siegmund ARL is `arl`.
double cusum_threshold_for(double k, double arl);

enum class Health { kOk, kWarn, kError };
const char* to_string(Health health);

struct Assessment {
  std::vector<double> indicators;
  double load = 0.0;
  std::size_t band = 0;
  double t2 = 0.0, score = 0.0, cusum = 0.0;
  std::vector<char> exceeded;  // per indicator: above its threshold
  bool t2_alarm = false;       // this window: T² above its threshold (WARN)
  bool cusum_alarm = false;    // persistence: the CUSUM above h (ERROR)
  bool in_reference = true;    // the load within the reference's (Reference::covers); if not: WARN, CUSUM held
  Health health = Health::kOk;
};

// Applies a reference to a run's windows: indicators (with the run's NA4/NB4 trends), T², the
// CUSUM, and the health: ERROR while the CUSUM is above h, else WARN if this window's T² is above
// its threshold or its load outside the reference's (not judged, the CUSUM held), else OK.
class ConditionMonitor {
 public:
  explicit ConditionMonitor(Reference reference);
  Assessment assess(const RevolutionWindow& window);
  void reset();  // a new run: trends and CUSUM from zero
  const Reference& reference() const { return reference_; }
  const MonitorSettings& settings() const { return reference_.settings.monitor; }
  double revolution_angle() const { return revolution_; }

 private:
  Reference reference_;
  double revolution_;
  IndicatorTracker tracker_;
  double cusum_ = 0.0;
};

}  // namespace gear_dynamics
