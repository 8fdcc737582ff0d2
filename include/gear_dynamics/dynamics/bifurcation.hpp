// Bifurcation scans of the deterministic gear model (doc/nonlinear-dynamics.md §5): for each value
// of one parameter a run of `duration`, the transient before `transient` discarded, and the
// Poincare points (delta, delta_dot) once per mesh period at the initial mesh phase. Values that
// share the mesh schedule (mean load, mu) run as lanes of one production Ensemble block; values that
// change it (pinion speed, damping ratio, which sets alpha for every lane of an Ensemble) run as
// GearLanes blocks (a schedule and a sampling period per lane). Blocks run in parallel (TBB). The
// bearings model (gear_pair.model) runs each value as a lane of its own with its whole state
// sampled: its period is tested on all ten components, its points are (delta_m, delta_m_dot).
#pragma once

#include <string>
#include <vector>

#include "gear_dynamics/config/config.hpp"
#include "gear_dynamics/dynamics/poincare.hpp"

namespace gear_dynamics {

enum class ScanParameter { Speed, Load, Friction, Damping };
// "speed" (pinion speed [rpm]), "load" (Phi0 [m/s^2]), "mu", "damping" (zeta_ref); throws otherwise.
ScanParameter parse_scan_parameter(const std::string& name);
std::string scan_parameter_name(ScanParameter p);

struct ScanOptions {
  double duration = 2.0;        // [s]
  double transient = 1.0;       // [s] discarded
  int block_lanes = 8;          // lanes (parameter values) per block
  int max_period = 16;          // periods tested for periodicity, raised to the mesh schedule's period
  double tolerance = 1e-3;      // periodicity: |x_{k+p} - x_k| <= tolerance * (b, v_ref) per component
};

struct ScanValue {
  double value = 0;
  std::vector<SectionState> points;  // lane is 0
  int period = 0;              // smallest p <= period_search_limit with x_{k+p} = x_k (tolerance); 0 = none
  double min_gap = 0;          // min over the kept window of delta - b [m]; > 0: the teeth never separate
  double min_delta = 0;        // min delta over the kept window [m]; < -b: back-flank contact
  // "<motion>, <contact>": motion "period-p" or "aperiodic"; contact "no separation" (delta > b
  // throughout), "single-sided impacts" (contact lost, never delta < -b) or "double-sided impacts".
  std::string regime;
};

std::vector<ScanValue> bifurcation_scan(const ModelConfig& base, ScanParameter parameter,
                                        const std::vector<double>& values, const ScanOptions& options = {});

// The configuration with one parameter set (speed in rpm); validated by the config layer's rules.
ModelConfig with_parameter(const ModelConfig& base, ScanParameter parameter, double value);

// The periods to test of a gear's Poincare points (one per mesh period): at least `at_least`, and
// at least the mesh schedule's period (schedule_mesh_periods: e.g. Z1 with a cracked pinion tooth),
// since a motion locked to the forcing repeats only after it.
int period_search_limit(const GearInputs& gear, int at_least);

// Smallest period p <= max_period of a sequence of Poincare points (scaled tolerance), 0 if none.
int detect_period(const std::vector<SectionState>& points, int max_period, const std::vector<double>& tolerance);

}  // namespace gear_dynamics
