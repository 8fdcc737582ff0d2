// What the source files of gear_dynamics._core share: the configuration as gear_run reads it, and
// the functions that add each part's bindings to the module.
#pragma once

#include <pybind11/pybind11.h>
#include <yaml-cpp/yaml.h>

#include <optional>
#include <string>
#include <vector>

namespace gear_dynamics::python {

// The defaults, `files`, the --set overrides, mu and seed, snapshot times after run.duration dropped
// with a Python UserWarning (gear_run's notice).
YAML::Node model_root(const std::vector<std::string>& files, const std::vector<std::string>& sets,
                      std::optional<double> mu, std::optional<long long> seed);

void bind_ensemble(pybind11::module_& m);  // ensemble.cpp: streaming statistics over a study grid
void bind_monitor(pybind11::module_& m);   // monitor.cpp: condition indicators, bifurcation scans

}  // namespace gear_dynamics::python
