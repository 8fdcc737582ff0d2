#include "gear_dynamics/config/simulator_settings.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "gear_dynamics/config/config.hpp"

namespace gear_dynamics {

const Section<SimulatorSettings>& simulator_section() {
  static const Section<SimulatorSettings> section =
      Section<SimulatorSettings>("simulator", "simulator.")
          .key("deterministic", GD_MEMBER(deterministic),
               "true: the deterministic load S1 (Phi = load.initial_mean, sigma = lambda = 0); false: a stochastic realization")
          .key("realization", GD_MEMBER(realization), closed(0, std::numeric_limits<std::int32_t>::max()), "-",
               "random stream of the stochastic load (S2 = 0, S3 = 1)")
          .key("publish_rate", GD_MEMBER(publish_rate), closed(kMinPublishRate, kMaxPublishRate), "Hz",
               "rate of state and the Float64 topics in simulated time; at most 1/run.time_step")
          .key("publish_scalars", GD_MEMBER(publish_scalars), "also publish delta, delta_dot, phi, center_distance as Float64")
          .key("publish_clock", GD_MEMBER(publish_clock), "publish /clock = simulated time + 1 s")
          .key("real_time_factor", GD_MEMBER(real_time_factor), closed(0, kMaxRealTimeFactor), "-",
               "simulated seconds per wall second; 0 = as fast as possible")
          .key("t_end", GD_MEMBER(t_end), closed(0, 1e6), "s",
               "where the run stops, a whole number of time steps; 0 = run on forever")
          .key("loop", GD_MEMBER(loop), "at t_end start over (as ~reset) instead of stopping; needs t_end > 0")
          .key("paused", GD_MEMBER(paused), "start paused (then ~unpause or ~step)")
          .key("load_input", GD_MEMBER(load_input),
               "where Phi comes from: sde (load.yaml's SDE), external (the load_command topic, held), "
               "external_plus_noise (the command plus the SDE's increments)")
          .one_of({"sde", "external", "external_plus_noise"});
  return section;
}

SimulatorSettings parse_simulator_settings(const YAML::Node& root, double time_step) {
  const YAML::Node section = root["simulator"];
  if (!section || !section.IsMap()) {
    throw ConfigError("invalid configuration: missing section 'simulator' (config/simulator.yaml), "
                      "a map with the keys deterministic, realization, publish_rate, publish_scalars, "
                      "publish_clock, real_time_factor, t_end, loop, paused, load_input");
  }
  std::vector<std::string> errors;
  SectionReader in(section, "simulator.", errors);
  SimulatorSettings s;
  simulator_section().read(in, s);
  // Checks against the model's grid and between keys, each only when its keys are good.
  const double max_rate = std::min(kMaxPublishRate, 1.0 / time_step);
  if (in.ok("publish_rate") && s.publish_rate > max_rate)
    in.error("publish_rate", " = " + SectionReader::text_of(s.publish_rate) + " is out of range; allowed [" +
                                 SectionReader::text_of(kMinPublishRate) + ", " + SectionReader::text_of(max_rate) +
                                 "] Hz (at most 1/time_step, one message per step)");
  if (in.ok("t_end")) {
    const double steps = s.t_end / time_step;
    if (std::abs(steps - std::round(steps)) > 1e-9 * steps)
      in.error("t_end", " = " + SectionReader::text_of(s.t_end) + " s is not a whole number of time steps (" +
                            SectionReader::text_of(steps) + " x " + SectionReader::text_of(time_step) + " s)");
  }
  if (in.ok("loop") && in.ok("t_end") && s.loop && s.t_end == 0.0)
    in.error("loop", " = true needs simulator.t_end > 0 (t_end = 0 runs on forever)");
  in.finish();
  detail::throw_if_errors(errors);
  return s;
}

YAML::Node to_yaml(const SimulatorSettings& s) { return simulator_section().to_yaml(s); }

std::int64_t publish_period_steps(double publish_rate, double time_step) {
  return std::max<std::int64_t>(1, std::llround(1.0 / (publish_rate * time_step)));
}

}  // namespace gear_dynamics
