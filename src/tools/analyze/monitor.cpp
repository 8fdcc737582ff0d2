// gear_analyze monitor: the condition monitor (doc/monitor.md) over a live node's recorded run,
// offline: the windows, indicators, T² and CUSUM that gear_monitor computes from the same states.
#include <cmath>
#include <cstdio>

#include "common.hpp"
#include "gear_dynamics/monitor/study.hpp"

namespace gear_dynamics::tools::analyze {
namespace {

class Monitor : public Subcommand {
 public:
  std::string name() const override { return "monitor"; }
  std::string description() const override {
    return "the condition monitor over a recorded run (--bag) against a healthy reference";
  }

  void add_options(CLI::App& app) override {
    app.add_option("--reference", reference_, "the healthy reference (gear_monitor_reference --output FILE)")
        ->required()
        ->check(CLI::ExistingFile)
        ->type_name("FILE");
    add_bag_option(app, bag_);
    app.get_option("--bag")->required();
  }

  int run(const Common& c) override {
    const BagRun b = load_bag(bag_, c);
    const Reference ref = read_reference(reference_);
    check_reference(ref, b.config, reference_);
    const GearPair gear = derive(b.config.gear);
    const MeshSchedule mesh(gear, b.config.run.time_step);
    const MonitorSettings& m = ref.settings.monitor;
    const double h = b.config.run.time_step, sampling = m.decimation * h;
    if (std::abs(b.period - sampling) > 1e-6 * sampling) {
      char text[256];
      std::snprintf(text, sizeof text,
                    "--bag: its states are %g s apart; the reference's windows sample every decimation x h = %g s "
                    "(simulate.launch publish_rate:=%g)",
                    b.period, sampling, 1.0 / sampling);
      throw std::runtime_error(text);
    }
    const MonitoredSignalSpec& spec = signal_spec(m.signal);
    const auto wrench = spec.wrench_topic ? b.run.wrenches.find(spec.wrench_topic) : b.run.wrenches.end();
    if (spec.wrench_topic && wrench == b.run.wrenches.end())
      throw std::runtime_error("--bag: the reference monitors " + std::string(spec.name) + ", and " + bag_ +
                               " has no geometry_msgs/WrenchStamped on " + spec.wrench_topic +
                               " (the bearings model's simulator records it with record:=true)");
    std::vector<double> angle, value, load;
    for (std::size_t i = first_after(b, ref.settings.warmup); i < b.run.t.size(); ++i) {
      const double t = b.run.t[i];
      // The state's t is the grid time rounded to whole nanoseconds; the engine's angle is at n h.
      angle.push_back(shaft_angle(gear, std::round(t / h) * h));
      value.push_back(spec.wrench_topic ? wrench_component(spec, wrench->second.x[i], wrench->second.y[i])
                                         : state_signal(gear, m.signal, b.run.stiffness[i], mesh.transmission_error(t),
                                                        mesh.transmission_error_rate(t), b.run.delta[i],
                                                        b.run.delta_dot[i]));
      load.push_back(b.run.phi[i]);
    }
    const std::vector<MonitoredWindow> windows = monitor_series(ref, angle, value, load);

    auto csv = open_csv(c, "monitor");
    csv->out() << "window,start_angle,load,band,in_reference";
    for (const auto& n : ref.indicators) csv->out() << ',' << n;
    csv->out() << ",t2,t2_threshold,score,cusum,cusum_threshold,level\n";
    int warn = 0, error = 0, outside = 0;
    long first_error = -1;
    for (const MonitoredWindow& w : windows) {
      const Assessment& a = w.assessment;
      csv->out() << w.index + 1 << ',' << w.start_angle << ',' << a.load << ',' << a.band << ',' << a.in_reference;
      for (double v : a.indicators) csv->out() << ',' << v;
      csv->out() << ',' << a.t2 << ',' << ref.bands[a.band].t2_threshold << ',' << a.score << ',' << a.cusum << ','
                 << ref.cusum_threshold << ',' << to_string(a.health) << '\n';
      warn += a.health == Health::kWarn;
      error += a.health == Health::kError;
      outside += !a.in_reference;
      if (a.health == Health::kError && first_error < 0) first_error = w.index + 1;
    }
    csv.reset();  // closed and checked before the summary
    std::printf("%zu windows: %d WARN (%d of them not judged: load outside the reference's), %d ERROR", windows.size(),
                warn, outside, error);
    if (first_error > 0) std::printf(", the first at window %ld", first_error);
    std::printf("\n");
    return 0;
  }

 private:
  std::string reference_, bag_;
};

}  // namespace

std::unique_ptr<Subcommand> make_monitor() { return std::make_unique<Monitor>(); }

}  // namespace gear_dynamics::tools::analyze
