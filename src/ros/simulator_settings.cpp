#include "gear_dynamics/ros/simulator_settings.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "gear_dynamics/config.hpp"

namespace gear_dynamics {

namespace {

std::string text(double x) {
  std::ostringstream s;
  s.precision(12);
  s << x;
  return s.str();
}

std::string show(const YAML::Node& n) {
  YAML::Emitter e;
  e << YAML::Flow << n;
  return e.c_str();
}

// Reads the keys of one section, collecting every problem; keys never read are typos.
class SectionReader {
 public:
  SectionReader(const YAML::Node& section, std::vector<std::string>& errors)
      : section_(section), errors_(errors) {}

  bool flag(const char* key, bool& out) {
    const YAML::Node v = get(key);
    if (!v) return false;
    if (v.IsScalar() && YAML::convert<bool>::decode(v, out)) return true;
    error(key, " = " + show(v) + " has the wrong type: expected true or false");
    return false;
  }

  // A number in [lo, hi], a whole one if `integer`.
  bool number(const char* key, double lo, double hi, bool integer, const char* unit, double& out) {
    const YAML::Node v = get(key);
    if (!v) return false;
    const std::string range = "[" + text(lo) + ", " + text(hi) + "]" +
                              (integer ? " (integer) " : " ") + unit;
    double x;
    bool is_bool;
    if (!v.IsScalar() || YAML::convert<bool>::decode(v, is_bool) || !YAML::convert<double>::decode(v, x)) {
      error(key, " = " + show(v) + " has the wrong type: expected a number in " + range);
      return false;
    }
    if (!std::isfinite(x) || x < lo || x > hi) {
      error(key, " = " + text(x) + " is out of range; allowed " + range);
      return false;
    }
    if (integer && x != std::floor(x)) {
      error(key, " = " + text(x) + " is not an integer; allowed " + range);
      return false;
    }
    out = x;
    return true;
  }

  void error(const char* key, const std::string& what) {
    errors_.push_back(std::string("simulator.") + key + what);
  }

  void reject_unknown_keys() {
    for (const auto& kv : section_) {
      const std::string key = kv.first.as<std::string>();
      if (read_.count(key)) continue;
      std::string valid;
      for (const std::string& k : read_) valid += (valid.empty() ? "" : ", ") + k;
      error(key.c_str(), " is not a known key (a typo?); valid keys: " + valid);
    }
  }

 private:
  YAML::Node get(const char* key) {
    read_.insert(key);
    const YAML::Node v = section_[key];
    if (!v || v.IsNull()) {
      error(key, " is missing");
      return YAML::Node();
    }
    return v;
  }

  YAML::Node section_;
  std::vector<std::string>& errors_;
  std::set<std::string> read_;
};

}  // namespace

SimulatorSettings parse_simulator_settings(const YAML::Node& root, double time_step) {
  SimulatorSettings s;
  std::vector<std::string> errors;
  const YAML::Node section = root["simulator"];
  if (!section || !section.IsMap()) {
    throw ConfigError("invalid configuration: missing section 'simulator' (config/simulator.yaml), "
                      "a map with the keys deterministic, realization, publish_rate, publish_scalars, "
                      "publish_clock, real_time_factor, t_end, loop, paused");
  }
  SectionReader in(section, errors);
  double realization = 0.0;
  in.flag("deterministic", s.deterministic);
  if (in.number("realization", 0, std::numeric_limits<std::int32_t>::max(), true, "-", realization))
    s.realization = static_cast<std::uint32_t>(realization);
  const double max_rate = std::min(kMaxPublishRate, 1.0 / time_step);
  in.number("publish_rate", kMinPublishRate, max_rate, false, "Hz (simulated time; at most 1/time_step)",
            s.publish_rate);
  in.flag("publish_scalars", s.publish_scalars);
  in.flag("publish_clock", s.publish_clock);
  in.number("real_time_factor", 0, kMaxRealTimeFactor, false, "(0 = as fast as possible)",
            s.real_time_factor);
  if (in.number("t_end", 0, 1e6, false, "s (0 = run on forever)", s.t_end)) {
    const double steps = s.t_end / time_step;
    if (std::abs(steps - std::round(steps)) > 1e-9 * steps)
      in.error("t_end", " = " + text(s.t_end) + " s is not a whole number of time steps (" +
                            text(steps) + " x " + text(time_step) + " s)");
  }
  if (in.flag("loop", s.loop) && s.loop && s.t_end == 0.0)
    in.error("loop", " = true needs simulator.t_end > 0 (t_end = 0 runs on forever)");
  in.flag("paused", s.paused);
  in.reject_unknown_keys();
  if (!errors.empty()) {
    std::string all = "invalid configuration:";
    for (const auto& m : errors) all += "\n  " + m;
    throw ConfigError(all);
  }
  return s;
}

YAML::Node to_yaml(const SimulatorSettings& s) {
  YAML::Node n;
  n["deterministic"] = s.deterministic;
  n["realization"] = s.realization;
  n["publish_rate"] = s.publish_rate;
  n["publish_scalars"] = s.publish_scalars;
  n["publish_clock"] = s.publish_clock;
  n["real_time_factor"] = s.real_time_factor;
  n["t_end"] = s.t_end;
  n["loop"] = s.loop;
  n["paused"] = s.paused;
  return n;
}

std::int64_t publish_period_steps(double publish_rate, double time_step) {
  return std::max<std::int64_t>(1, std::llround(1.0 / (publish_rate * time_step)));
}

}  // namespace gear_dynamics
