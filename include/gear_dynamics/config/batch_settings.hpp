// The `monte_carlo` section (config/monte_carlo.yaml): what a batch holds and how it runs.
#pragma once

#include <yaml-cpp/yaml.h>

#include <cstdint>
#include <string>
#include <vector>

#include "gear_dynamics/config/config.hpp"
#include "gear_dynamics/config/sweep.hpp"

namespace gear_dynamics {

struct BatchSettings {
  // What the batch holds: the manifest records these and resume compares them.
  std::vector<double> mu{0.0, 0.01, 0.02, 0.03, 0.04, 0.05};  // friction coefficients [-]
  std::uint32_t realizations = 100;     // R: stochastic realizations 0..R-1 per mu
  bool phase_ensemble = true;           // S1 repeated over phi0 = j phi_n / 64, j = 0..63
  double record_rate = 1.0e5;           // [Hz] series of S1 and realizations < record_realizations
  std::uint32_t record_realizations = 2;  // S2 = realization 0, S3 = realization 1
  double sparse_record_rate = 100.0;    // [Hz] series of every other run; 0 = none
  std::vector<SweepAxis> sweep;         // further axes beside mu (config/sweep.hpp); empty: the mu sweep
  // How it runs: no effect on any bag's content.
  std::string output_dir = "batch";
  bool overwrite = false;               // replace a folder that holds another batch
  int shard_index = 0, shard_count = 1;
  int block_lanes = 32;                 // realizations stepped together
  int threads = 0;                      // 0 = all cores
};

// The declaration of the `monte_carlo` section.
const Section<BatchSettings>& batch_section();

// Validates the `monte_carlo` map against `model` (the record rates must divide its grid).
// Throws ConfigError naming every bad key, its value and the allowed range.
BatchSettings parse_batch_settings(const YAML::Node& section, const ModelConfig& model);
// The settings that define the batch's content, as a `monte_carlo` map (for the manifest).
YAML::Node content_yaml(const BatchSettings& settings);

// "mu0.0400": the friction coefficient as it starts every run name of a batch (4 decimals).
std::string mu_label(double mu);
// A run's name in a batch folder after a study point's prefix: the mu label, then _S1, _phaseNN or
// _rNNNNN (the batch's bags, and the live node's bearing_summary of the same run).
std::string s1_run_label(double mu);
std::string phase_run_label(double mu, std::uint64_t phase);
std::string realization_run_label(double mu, std::uint64_t realization);

}  // namespace gear_dynamics
