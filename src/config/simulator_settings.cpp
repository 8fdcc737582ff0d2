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
          .key("exit_at_end", GD_MEMBER(exit_at_end),
               "at t_end end the node (its bag complete) instead of waiting for ~reset, and a launch with "
               "required:=true with it; needs t_end > 0, not with loop")
          .key("paused", GD_MEMBER(paused), "start paused (then ~unpause or ~step)")
          .key("subscriber_wait", GD_MEMBER(subscriber_wait), closed(0, 60), "s",
               "at real_time_factor 0, wall time held at t = 0 before running, for subscribers still "
               "discovering the node (rosbag record -a); 0 = start at once")
          .key("load_input", GD_MEMBER(load_input),
               "where Phi comes from: sde (load.yaml's SDE), external (the load_command topic, held), "
               "external_plus_noise (the command plus the SDE's increments)")
          .one_of({"sde", "external", "external_plus_noise"})
          .key("spectrum_rate", GD_MEMBER(spectrum_rate), closed(0, 100), "Hz",
               "updates of the spectrum topic per simulated second; 0 = no spectrum topic")
          .key("spectrum_window", GD_MEMBER(spectrum_window), open_closed(0, 1000), "s",
               "trailing window of the spectrum; at most 1e6 samples")
          .key("spectrum_sample_rate", GD_MEMBER(spectrum_sample_rate), closed(1, 1e6), "Hz",
               "samples of delta and the mesh force taken on the integration grid, every round(1/(rate h)) steps; "
               "at most 1/run.time_step; above twice the highest frequency of interest (no anti-alias filter)")
          .key("spectrum_segment", GD_MEMBER(spectrum_segment), open_closed(0, 1000), "s",
               "Welch segment (frequency resolution 1/segment), at least 8 samples and at most the window")
          .key("spectrum_overlap", GD_MEMBER(spectrum_overlap), closed(0, 0.95), "-",
               "fraction of a Welch segment shared with the next");
  return section;
}

SimulatorSettings parse_simulator_settings(const YAML::Node& root, double time_step) {
  const YAML::Node section = root["simulator"];
  if (!section || !section.IsMap()) {
    throw ConfigError("invalid configuration: missing section 'simulator' (config/simulator.yaml), "
                      "a map with the keys deterministic, realization, publish_rate, publish_scalars, "
                      "publish_clock, real_time_factor, t_end, loop, exit_at_end, paused, load_input, spectrum_rate, "
                      "spectrum_window, spectrum_sample_rate, spectrum_segment, spectrum_overlap");
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
  if (in.ok("exit_at_end") && in.ok("t_end") && s.exit_at_end && s.t_end == 0.0)
    in.error("exit_at_end", " = true needs simulator.t_end > 0 (t_end = 0 runs on forever)");
  if (in.ok("exit_at_end") && in.ok("loop") && s.exit_at_end && s.loop)
    in.error("exit_at_end", " = true contradicts simulator.loop = true (a loop never ends); allowed: one of them");
  // The spectrum's keys against the grid and each other, only when the topic is on.
  const bool spectrum_ok = in.ok("spectrum_rate") && in.ok("spectrum_window") && in.ok("spectrum_sample_rate") &&
                           in.ok("spectrum_segment") && in.ok("spectrum_overlap");
  if (spectrum_ok && s.spectrum_rate > 0.0) {
    const auto text = SectionReader::text_of;
    if (s.spectrum_sample_rate > 1.0 / time_step) {
      in.error("spectrum_sample_rate", " = " + text(s.spectrum_sample_rate) + " is out of range; allowed [1, " +
                                           text(1.0 / time_step) + "] Hz (at most 1/time_step, one sample per step)");
    } else {
      const SpectrumSampling p = spectrum_sampling(s, time_step);
      const std::string rate = " at the sample rate " + text(p.sample_rate) + " Hz";
      if (p.window_samples > kMaxSpectrumSamples)
        in.error("spectrum_window", " = " + text(s.spectrum_window) + " s holds " + text(p.window_samples) +
                                        " samples" + rate + "; allowed at most " + text(kMaxSpectrumSamples));
      else if (p.segment_samples < 8 || p.segment_samples > p.window_samples)
        in.error("spectrum_segment", " = " + text(s.spectrum_segment) + " s holds " + text(p.segment_samples) +
                                         " samples" + rate + "; allowed [8, " + text(p.window_samples) +
                                         "] samples (the window, spectrum_window = " + text(s.spectrum_window) +
                                         " s)");
    }
  }
  in.finish();
  detail::throw_if_errors(errors);
  return s;
}

YAML::Node to_yaml(const SimulatorSettings& s) { return simulator_section().to_yaml(s); }

SpectrumSampling spectrum_sampling(const SimulatorSettings& s, double time_step) {
  SpectrumSampling p;
  p.sample_steps = publish_period_steps(s.spectrum_sample_rate, time_step);
  p.sample_rate = 1.0 / (static_cast<double>(p.sample_steps) * time_step);
  p.window_samples = std::max<std::int64_t>(1, std::llround(s.spectrum_window * p.sample_rate));
  p.segment_samples = std::llround(s.spectrum_segment * p.sample_rate);
  p.overlap = s.spectrum_overlap;
  if (s.spectrum_rate > 0.0)  // a whole number of sample periods, at least one
    p.update_steps = p.sample_steps * std::max<std::int64_t>(1, std::llround(p.sample_rate / s.spectrum_rate));
  return p;
}

std::int64_t publish_period_steps(double publish_rate, double time_step) {
  return std::max<std::int64_t>(1, std::llround(1.0 / (publish_rate * time_step)));
}

}  // namespace gear_dynamics
