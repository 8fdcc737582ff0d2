#include "gear_dynamics/config/simulator_settings.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "gear_dynamics/config/config.hpp"
#include "gear_dynamics/config/section_reader.hpp"

namespace gear_dynamics {

SimulatorSettings parse_simulator_settings(const YAML::Node& root, double time_step) {
  SimulatorSettings s;
  std::vector<std::string> errors;
  const YAML::Node section = root["simulator"];
  if (!section || !section.IsMap()) {
    throw ConfigError("invalid configuration: missing section 'simulator' (config/simulator.yaml), "
                      "a map with the keys deterministic, realization, publish_rate, publish_scalars, "
                      "publish_clock, real_time_factor, t_end, loop, paused, load_input");
  }
  SectionReader in(section, "simulator", errors);
  if (const auto v = in.flag("deterministic")) s.deterministic = *v;
  if (const auto v = in.number("realization", 0, std::numeric_limits<std::int32_t>::max(), true, "-"))
    s.realization = static_cast<std::uint32_t>(*v);
  const double max_rate = std::min(kMaxPublishRate, 1.0 / time_step);
  if (const auto v = in.number("publish_rate", kMinPublishRate, max_rate, false, "Hz (simulated time; at most 1/time_step)"))
    s.publish_rate = *v;
  if (const auto v = in.flag("publish_scalars")) s.publish_scalars = *v;
  if (const auto v = in.flag("publish_clock")) s.publish_clock = *v;
  if (const auto v = in.number("real_time_factor", 0, kMaxRealTimeFactor, false, "(0 = as fast as possible)"))
    s.real_time_factor = *v;
  const auto t_end = in.number("t_end", 0, 1e6, false, "s (0 = run on forever)");
  if (t_end) {
    s.t_end = *t_end;
    const double steps = s.t_end / time_step;
    if (std::abs(steps - std::round(steps)) > 1e-9 * steps)
      in.error("t_end", " = " + SectionReader::text_of(s.t_end) + " s is not a whole number of time steps (" +
                            SectionReader::text_of(steps) + " x " + SectionReader::text_of(time_step) + " s)");
  }
  if (const auto v = in.flag("loop")) {
    s.loop = *v;
    if (s.loop && t_end && s.t_end == 0.0) in.error("loop", " = true needs simulator.t_end > 0 (t_end = 0 runs on forever)");
  }
  if (const auto v = in.flag("paused")) s.paused = *v;
  if (const auto v = in.text("load_input")) {
    if (*v == "sde" || *v == "external" || *v == "external_plus_noise")
      s.load_input = *v;
    else
      in.error("load_input", " = '" + *v + "' is not one of sde, external, external_plus_noise");
  }
  in.finish();
  detail::throw_if_errors(errors);
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
  n["load_input"] = s.load_input;
  return n;
}

std::int64_t publish_period_steps(double publish_rate, double time_step) {
  return std::max<std::int64_t>(1, std::llround(1.0 / (publish_rate * time_step)));
}

}  // namespace gear_dynamics
