// Configuration: the YAML sections gear_pair, load and run (config/*.yaml), each declared once as a
// table of keys (section.hpp) that drives its reader, its defaults, its YAML form and the docs.
// Every problem is reported with the key, the value and the allowed range; unknown keys inside
// these sections are errors (a typo must not silently fall back).
#pragma once

#include <yaml-cpp/yaml.h>

#include <cstdint>
#include <string>
#include <vector>

#include "gear_dynamics/config/section.hpp"
#include "gear_dynamics/engine/ensemble.hpp"
#include "gear_dynamics/model/gear_pair.hpp"
#include "gear_dynamics/engine/simulation.hpp"

namespace gear_dynamics {

struct LoadSettings {
  double initial_mean = 20.0;  // E[Phi(0)] [m/s^2]
  double initial_sd = 5.0;     // sd of Phi(0) [m/s^2]
  double drift = 0.0;          // lambda [m/s^3]
  double sigma = 5.0;          // [m/s^2/sqrt(s)]
};

// Profile errors as set (doc/model.md §3): per-tooth lists plus, if sd > 0, a normal error per
// tooth drawn from the seed; parse_config puts their sum into GearInputs::profile_errors.
struct ProfileErrorSettings {
  std::vector<double> pinion, wheel;  // [m]
  double sd = 0.0;                    // [m]
};

struct ModelConfig {
  GearInputs gear;
  ProfileErrorSettings profile_errors;
  double friction_coefficient = 0.04;  // mu [-]
  InitialState initial;
  LoadSettings load;
  RunSettings run;
  std::uint64_t seed = 20180529;
};

// The random stream of the per-tooth profile errors: the last realization index a stream key holds,
// one no run uses (realizations stay below 1e6).
constexpr std::uint64_t kProfileErrorStream = 4294967295ULL;

// Largest friction coefficient accepted anywhere (config and dynamic_reconfigure).
constexpr double kMaxFrictionCoefficient = 0.2;
// Largest load noise intensity accepted: 20x the paper's 5 m/s^2/sqrt(s).
constexpr double kMaxLoadSigma = 100.0;
// Largest |Phi| accepted as load.initial_mean and as a live load command [m/s^2].
constexpr double kMaxLoadMean = 1.0e4;
// Largest |E[Phi(0)]| a configuration accepts: 5x the load whose static mesh force is near 1 kN
// (Phi = 2e4 m/s^2), at which the teeth of the default pair stay in contact.
constexpr double kMaxConfigLoadMean = 1.0e5;
// Largest |lambda| accepted [m/s^3].
constexpr double kMaxLoadDrift = 1.0e6;
// RK4 is stable for an undamped oscillator while omega h < 2 sqrt(2) (doc/model.md §5).
constexpr double kMaxOmegaTimesStep = 2.8284271247461903;

// The declarations of the sections gear_pair, load and run, in this order.
const std::vector<Section<ModelConfig>>& model_sections();

// Validates the sections gear_pair, load and run of `root`. Other top-level keys are left alone
// (a node's namespace holds more than the model). Throws ConfigError listing every problem.
ModelConfig parse_config(const YAML::Node& root);

// Reads the files in order, later ones overriding earlier ones key by key, then parses.
YAML::Node read_yaml_files(const std::vector<std::string>& files);
// Overlays `overlay` onto `base` key by key (maps recursively, everything else replaced).
void merge_yaml(YAML::Node& base, const YAML::Node& overlay);

// The configuration in effect, as YAML in the files' layout (for run_info and manifests).
YAML::Node to_yaml(const ModelConfig& config);

// The lane of stochastic realization `realization`, or the deterministic lane (Phi = initial_mean,
// no random stream), at friction `mu` with the load settings of `config`.
LaneSpec stochastic_lane(const ModelConfig& config, double mu, std::uint64_t realization);
LaneSpec deterministic_lane(const ModelConfig& config, double mu);

// Checks that hold between parameters, e.g. for values changed at run time: throws ConfigError.
void validate_consistency(const ModelConfig& config);

}  // namespace gear_dynamics
