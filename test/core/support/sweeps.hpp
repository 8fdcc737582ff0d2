// Sweep axes from YAML text and the refusal of a call, for the sweep and study tests.
#pragma once

#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include <functional>
#include <string>
#include <vector>

#include "gear_dynamics/config/config.hpp"
#include "gear_dynamics/config/sweep.hpp"

namespace gear_dynamics::test {

// The axes of a `monte_carlo.sweep` map; its errors into *errors_out, or none expected.
inline std::vector<SweepAxis> sweep_of(const std::string& yaml, std::vector<std::string>* errors_out = nullptr) {
  std::vector<std::string> errors;
  auto axes = parse_sweep(YAML::Load(yaml), errors);
  if (errors_out) *errors_out = errors;
  else EXPECT_TRUE(errors.empty()) << (errors.empty() ? "" : errors.front());
  return axes;
}

// The ConfigError message `f` throws; empty when it throws none.
inline std::string refusal(const std::function<void()>& f) {
  try {
    f();
  } catch (const ConfigError& e) {
    return e.what();
  }
  return "";
}

}  // namespace gear_dynamics::test
