// The shipped configuration the core tests are pinned on: config/gear_pair.yaml, load.yaml and
// run.yaml as the package reads them (the paper's gear, load and run).
#pragma once

#include <string>

#include "gear_dynamics/config/config.hpp"

inline gear_dynamics::ModelConfig paper_config() {
  const std::string dir = GEAR_DYNAMICS_CONFIG_DIR;
  return gear_dynamics::parse_config(
      gear_dynamics::read_yaml_files({dir + "/gear_pair.yaml", dir + "/load.yaml", dir + "/run.yaml"}));
}
