// gear_monitor_reference: makes the condition monitor's healthy reference by Monte Carlo, or applies
// one to simulated runs of a (faulty) gear and counts the alarms (doc/monitor.md §5). No ROS master.
#include <chrono>
#include <cstdio>
#include <iostream>

#include "cli.hpp"
#include "gear_dynamics/monitor/reference.hpp"

namespace gd = gear_dynamics;

int main(int argc, char** argv) {
  CLI::App app{"Makes the condition monitor's healthy reference (--output), or applies one (--assess) to "
               "stochastic runs of the configured gear and prints the alarm rates and detection delays.",
               "gear_monitor_reference"};
  gd::tools::ModelOptions model;
  gd::tools::add_model_options(app, model);
  gd::ReferenceSettings s;
  std::string output, assess, csv, signal = "delta", gear = "pinion";
  app.add_option("--output", output, "write the reference to FILE")->type_name("FILE");
  app.add_option("--assess", assess, "apply the reference FILE to runs of this configuration")->type_name("FILE");
  app.add_option("--csv", csv, "with --assess: every window's indicators, T2, score and CUSUM into FILE")
      ->type_name("FILE");
  std::string signals;
  for (const gd::MonitoredSignalSpec& m : gd::monitored_signals()) signals += (signals.empty() ? "" : ", ") + std::string(m.name);
  app.add_option("--signal", signal, "the monitored signal: " + signals +
                                         " (a bearing force needs gear_pair.model: bearings; default delta)");
  app.add_option("--gear", gear, "whose revolutions the TSA follows: pinion or wheel (default pinion)");
  app.add_option("--revolutions", s.monitor.revolutions_per_window, "revolutions per window (default 1)");
  app.add_option("--samples", s.monitor.samples_per_revolution, "TSA points per revolution (default 640)");
  app.add_option("--decimation", s.monitor.decimation, "one sample every N grid steps (default 10)");
  app.add_option("--realizations", s.realizations, "realizations (default 256)");
  app.add_option("--first", s.first_realization, "first random stream (default 0)");
  app.add_option("--windows", s.windows, "windows per realization after the warm-up (default 1)");
  app.add_option("--warmup", s.warmup, "warm-up discarded [s] (default 0.1)");
  app.add_option("--false-alarm", s.false_alarm, "false-alarm probability per window (default 0.05)");
  app.add_option("--arl", s.average_run_length, "the CUSUM's in-control average run length [windows] (default 200)");
  app.add_option("--load", s.load_means, "mean load of a band [m/s^2] (repeatable; default load.initial_mean)")
      ->type_size(1)
      ->allow_extra_args(false)
      ->take_all()
      ->type_name("PHI");
  gd::tools::parse_or_exit(app, argc, argv);
  try {
    if (output.empty() == assess.empty()) throw std::invalid_argument("give exactly one of --output and --assess");
    s.monitor.signal = gd::parse_monitored_signal(signal, "--signal");
    if (gear != "pinion" && gear != "wheel")
      throw std::invalid_argument("--gear = " + gear + " is not allowed; allowed: pinion, wheel");
    s.monitor.gear = gear == "wheel" ? gd::FaultyGear::kWheel : gd::FaultyGear::kPinion;
    const gd::ModelConfig config = gd::parse_config(gd::tools::model_yaml(model));
    const auto start = std::chrono::steady_clock::now();
    const auto seconds = [&] {
      return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    };
    if (!output.empty()) {
      const gd::Reference ref = gd::build_reference(config, s);
      gd::write_reference(output, ref);
      std::printf("reference %s: %s, %d revolution(s) per window, %zu band(s), CUSUM h = %.4f (ARL %.0f), %.1f s\n",
                  output.c_str(), gd::to_string(s.monitor.signal), s.monitor.revolutions_per_window, ref.bands.size(),
                  ref.cusum_threshold, s.average_run_length, seconds());
      for (const auto& b : ref.bands)
        std::printf("  load %g m/s^2: %zu windows, T2 threshold %.3f (F: %.3f, rank %d)\n", b.load, b.windows,
                    b.t2_threshold, b.t2_threshold_f, b.rank);
      return 0;
    }
    gd::Reference ref = gd::read_reference(assess);
    gd::check_reference(ref, config, assess);
    const auto& m = ref.settings.monitor;
    const auto runs = gd::simulate_windows(config, m, s.first_realization, s.realizations, ref.settings.warmup, s.windows);
    const double simulated = seconds();
    gd::ConditionMonitor monitor(ref);
    double assessing = 0;  // [s] in ConditionMonitor::assess: the per-window cost of the monitor
    std::vector<int> exceeded(ref.indicators.size(), 0);
    int windows = 0, warn = 0, detected = 0, outside = 0;
    std::FILE* table = nullptr;
    if (!csv.empty()) {
      table = std::fopen(csv.c_str(), "w");
      if (!table) throw std::runtime_error("cannot write --csv " + csv);
      std::fprintf(table, "realization,window,load,band");
      for (const auto& n : ref.indicators) std::fprintf(table, ",%s", n.c_str());
      std::fprintf(table, ",t2,score,cusum,level\n");
    }
    std::uint64_t realization = s.first_realization;
    double delay = 0;
    for (const auto& run : runs) {
      monitor.reset();
      int first_error = -1;
      for (std::size_t w = 0; w < run.size(); ++w) {
        const auto t0 = std::chrono::steady_clock::now();
        const auto a = monitor.assess(run[w]);
        assessing += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
        ++windows;
        warn += a.t2_alarm;
        outside += !a.in_reference;
        for (std::size_t i = 0; i < exceeded.size(); ++i) exceeded[i] += a.exceeded[i];
        if (a.cusum_alarm && first_error < 0) first_error = static_cast<int>(w) + 1;
        if (table) {
          std::fprintf(table, "%llu,%zu,%.17g,%zu", static_cast<unsigned long long>(realization), w + 1, a.load, a.band);
          for (double v : a.indicators) std::fprintf(table, ",%.17g", v);
          std::fprintf(table, ",%.17g,%.17g,%.17g,%s\n", a.t2, a.score, a.cusum, gd::to_string(a.health));
        }
      }
      ++realization;
      if (first_error > 0) {
        ++detected;
        delay += first_error;
      }
    }
    if (table) std::fclose(table);
    std::printf("%d runs x %d windows: T2 above its threshold in %.3f of the windows (nominal %.3f); the CUSUM "
                "alarmed in %d runs, after %.1f windows on average; simulated in %.2f s, assessed in %.1f us per "
                "window\n",
                s.realizations, s.windows, static_cast<double>(warn) / windows, ref.settings.false_alarm, detected,
                detected ? delay / detected : 0.0, simulated, 1e6 * assessing / windows);
    if (outside)
      std::printf("%d windows not judged: their load outside the reference's [%.6g, %.6g] m/s^2\n", outside,
                  ref.bands.front().load_low, ref.bands.back().load_high);
    for (std::size_t i = 0; i < exceeded.size(); ++i)
      std::printf("  %-15s %.3f\n", ref.indicators[i].c_str(), static_cast<double>(exceeded[i]) / windows);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "gear_monitor_reference: %s\n", e.what());
    return 1;
  }
  return 0;
}
