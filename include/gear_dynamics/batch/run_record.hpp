// What reading a batch folder gives (doc/batch-folder.md §10): one fixed-size record per run, the
// bags left out and the runs missing, with the batch's configuration and study grid. The reader
// (the ROS side, which decodes the bags) fills it; the analysis and the report take it. No ROS.
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "gear_dynamics/batch/run_kind.hpp"
#include "gear_dynamics/config/config.hpp"
#include "gear_dynamics/config/sweep.hpp"
#include "gear_dynamics/engine/simulation.hpp"

namespace gear_dynamics {

// What a batch folder holds of one run (from its bag's RunSummary and Poincare points). SI units.
struct RunRecord {
  std::string name;
  RunKind kind = RunKind::Stochastic;
  double mu = 0;
  std::uint32_t index = 0;  // realization (stochastic) or phase index j (phase)
  std::size_t point = 0;    // study point (BatchInputs::points); for a mu sweep, mu's rank
  double center_distance = 0;         // d over the window [m s^-1/2]
  double steady_state_time = 0;       // t_ss [s]
  double steady_state_time_fine = 0;  // t_ss at the finer threshold [s]
  bool reached_steady_state = false;  // t_ss < T
  double final_delta = 0, final_delta_dot = 0, final_phi = 0;  // at T [m], [m/s], [m/s^2]
  std::vector<double> snapshot_times, snapshot_delta, snapshot_delta_dot;  // [s], [m], [m/s]
  // The /gear/poincare section of a deterministic run (S1, phase): (delta, delta_dot) at mesh
  // phase 0 once per mesh period; empty for stochastic runs and in bags written before it was
  // recorded (doc/batch-folder.md §5). [s], [m], [m/s]
  std::vector<double> section_times, section_delta, section_delta_dot;
  // gear_pair.model = bearings: the forces' mean and RMS over the window (/gear/bearing_summary) [N].
  std::optional<BearingForces> bearings;
};

// Whether two values written by a batch are the same (mu, time step, duration): equal to 1e-12
// relative, the text round trip of the manifest and the bags' messages set aside.
bool same_value(double a, double b);

// A run's /gear/state series, SI units: [s], [m], [m/s], [m/s^2].
struct RunSeries {
  std::vector<double> t, delta, delta_dot, phi;
};

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

}  // namespace gear_dynamics
