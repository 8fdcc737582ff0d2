// Studies (doc/studies.md): a grid over any scalar model key. `monte_carlo.sweep` maps keys such as
// load.sigma or gear_pair.pinion_speed to a list of values or to a range {from, to, count[, scale:
// log]}; `monte_carlo.mu` stays the friction axis (gear_pair.friction_coefficient), so the paper's
// batch is the study with that one axis. The batch is the Cartesian product of the axes; every
// point's whole configuration is validated (parse_config with its cross checks) before anything runs.
#pragma once

#include <yaml-cpp/yaml.h>

#include <cstddef>
#include <string>
#include <vector>

#include "gear_dynamics/config/config.hpp"

namespace gear_dynamics {

constexpr const char* kFrictionKey = "gear_pair.friction_coefficient";

// One axis of the grid: "section.key" and its values, in the order given (distinct). An axis over a
// text key (gear_pair.friction_model, ...) keeps its values in `labels` and their positions
// 0, 1, ... in `values`, so the grid, the points and the manifest stay numeric.
struct SweepAxis {
  std::string key;
  std::vector<double> values;
  std::vector<std::string> labels;  // empty for a number key
  bool text() const { return !labels.empty(); }
  // The value as reports write it: the label of a text axis, else the number (`digits` significant).
  std::string value_text(double value, int digits = 12) const;
};

// The keys a sweep may name: every number key and every text key with a list of choices
// (friction_model, friction_direction, model) of the sections gear_pair and load (model_sections()), in their order.
// Not run.*: every point shares one grid, T, window and seed (the seed would break common random
// numbers; T, h and the window must be common for the points to be compared).
std::vector<std::string> sweepable_keys();

// Parses the `sweep` map (keys "section.key", or nested {section: {key: ...}}; values a list or a
// range). Axes come out in schema order, whatever order the map had (the parameter server does not
// keep it). Problems are appended to `errors` as "monte_carlo.sweep.<key> ...".
std::vector<SweepAxis> parse_sweep(const YAML::Node& sweep, std::vector<std::string>& errors);

// The values of a range {from, to, count[, scale: linear|log]}: count >= 1 values from `from` to
// `to`, both exact; log spacing needs from, to > 0.
std::vector<double> range_values(double from, double to, int count, bool log_scale);

struct StudyPoint {
  std::size_t index = 0;        // position in the grid (plan order: the first axis varies slowest)
  std::vector<double> values;   // one per axis of the study
  ModelConfig config;           // the base configuration with this point's values, validated
  std::size_t schedule = 0;     // points with the same schedule share everything but lane parameters
};

// The grid of a batch: axis 0 is always the friction axis (monte_carlo.mu), then the sweep's axes.
struct Study {
  ModelConfig base;
  std::vector<SweepAxis> axes;
  std::vector<StudyPoint> points;
  // True when the sweep names more than the friction axis: runs are named p<iiii>_mu..., the
  // manifest is format 2 and the report is organised by point and axis.
  bool swept() const { return axes.size() > 1; }
  std::vector<std::string> keys() const;
};

// Expands mu x sweep into points and validates each: throws ConfigError listing every bad point
// with the key, the value, the point and the allowed range.
Study make_study(const ModelConfig& base, const std::vector<double>& mu, const std::vector<SweepAxis>& sweep);

// The base configuration with `values` set at `keys` (through YAML and parse_config, so a bad value
// throws the validator's message).
ModelConfig apply_point(const ModelConfig& base, const std::vector<SweepAxis>& axes,
                        const std::vector<double>& values);
// The same over number keys only (a manifest's keys and values).
ModelConfig apply_point(const ModelConfig& base, const std::vector<std::string>& keys,
                        const std::vector<double>& values);

// "gear_pair.friction_coefficient = 0.04, gear_pair.friction_model = xu" (numbers with 12 significant digits).
std::string point_text(const std::vector<SweepAxis>& axes, const std::vector<double>& values);
std::string point_text(const std::vector<std::string>& keys, const std::vector<double>& values);

// The short column name of a key in reports: "mu" for the friction axis, else the key itself.
std::string column_name(const std::string& key);

// Reads `section["sweep"]` (absent: no sweep) for parse_batch_settings. A friction axis in it
// replaces `mu` (whose 4th-decimal rule it then follows); the other axes go to `sweep`.
void read_sweep(const YAML::Node& section, std::vector<double>& mu, std::vector<SweepAxis>& sweep,
                std::vector<std::string>& errors);

// "--sweep load.sigma=0,2.5,5" or "--sweep load.sigma=1:20:5" (from:to:count) or "...:log".
SweepAxis parse_sweep_argument(const std::string& text);

}  // namespace gear_dynamics
