// gear_live_bench: the live node's costs (bench/live prints them).
//   gear_live_bench core [--rate HZ] [--t-end T] [--repeat K] [--no-center-distance] [--spectrum HZ]
//                        [--model torsional|bearings]
//       LiveSimulation (the node's ROS-free core) at real_time_factor 0 with a sink that only
//       counts: simulated seconds per CPU second of the stepping thread (getrusage), best of K.
//       --spectrum: the spectrum topic on at HZ updates per simulated second (config/simulator.yaml's
//       window and sampling otherwise); the sink copies each window as the node's stepping thread
//       does, then computes the two Welch PSDs as the node's worker does, timed apart (thread CPU):
//       ns_per_step counts the stepping thread's share only.
//   gear_live_bench subscribe TOPIC SECONDS
//       a roscpp subscriber (tcpNoDelay) that counts gear_dynamics/GearState messages on TOPIC for
//       SECONDS of wall time and prints the count and the sequence gaps (messages roscpp dropped).
#include <sys/resource.h>
#include <ctime>
#include <vector>

#include <cstdio>
#include <cstdlib>
#include <string>

#include <ros/ros.h>

#include "gear_dynamics/GearState.h"
#include "gear_dynamics/config/config.hpp"
#include "gear_dynamics/config/simulator_settings.hpp"
#include "gear_dynamics/maths/spectrum.hpp"
#include "gear_dynamics/live/live_simulation.hpp"

namespace gd = gear_dynamics;

namespace {

double cpu_seconds() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return static_cast<double>(u.ru_utime.tv_sec + u.ru_stime.tv_sec) +
         1e-6 * static_cast<double>(u.ru_utime.tv_usec + u.ru_stime.tv_usec);
}

double thread_cpu_seconds() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}

struct CountingSink : gd::LiveSink {
  bool center = true;
  long published = 0;
  double checksum = 0.0;
  gd::WelchOptions welch;
  long spectra = 0;
  double copy_cpu = 0.0, psd_cpu = 0.0;  // [s]
  std::vector<double> delta, force;
  void spectrum(const gd::SpectrumSamples& w) override {
    const double c0 = thread_cpu_seconds();
    w.samples->copy_to(delta, force);  // what GearSimulator's stepping thread does
    const double c1 = thread_cpu_seconds();
    const gd::Psd d = gd::welch_psd(delta, w.sample_rate, welch);  // what its worker thread does
    const gd::Psd f = gd::welch_psd(force, w.sample_rate, welch);
    checksum += d.density[1] + f.density[1];
    copy_cpu += c1 - c0;
    psd_cpu += thread_cpu_seconds() - c1;
    ++spectra;
  }
  void publish(const gd::LiveSample& s) override {
    ++published;
    checksum += s.delta + s.center_distance;
  }
  void run_info(const gd::LiveRunInfo&) override {}
  void log(gd::LiveLogLevel, const std::string&) override {}
  bool wants_center_distance() const override { return center; }
};

int core(int argc, char** argv) {
  double rate = 1000.0, t_end = 2.0, spectrum = 0.0;
  int repeat = 3;
  bool center = true;
  std::string model_name;  // empty: config/gear_pair.yaml's
  for (int i = 2; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--rate" && i + 1 < argc) rate = std::atof(argv[++i]);
    else if (a == "--t-end" && i + 1 < argc) t_end = std::atof(argv[++i]);
    else if (a == "--repeat" && i + 1 < argc) repeat = std::atoi(argv[++i]);
    else if (a == "--no-center-distance") center = false;
    else if (a == "--spectrum" && i + 1 < argc) spectrum = std::atof(argv[++i]);
    else if (a == "--model" && i + 1 < argc) model_name = argv[++i];
    else { std::fprintf(stderr, "gear_live_bench core: unknown option %s\n", a.c_str()); return 2; }
  }
  const std::string dir = GEAR_DYNAMICS_CONFIG_DIR;
  YAML::Node root = gd::read_yaml_files({dir + "/gear_pair.yaml", dir + "/load.yaml", dir + "/run.yaml",
                                         dir + "/simulator.yaml"});
  if (!model_name.empty()) root["gear_pair"]["model"] = model_name;
  const gd::ModelConfig model = gd::parse_config(root);
  gd::SimulatorSettings settings = gd::parse_simulator_settings(root, model.run.time_step);
  settings.real_time_factor = 0.0;
  settings.publish_rate = rate;
  settings.t_end = t_end;
  settings.paused = false;
  settings.spectrum_rate = spectrum;
  const gd::SpectrumSampling sampling = gd::spectrum_sampling(settings, model.run.time_step);
  double best = 1e300, copy_us = 0.0, psd_ms = 0.0;
  long published = 0, spectra = 0;
  double checksum = 0.0;
  for (int k = 0; k < repeat; ++k) {
    CountingSink sink;
    sink.center = center;
    sink.welch = gd::WelchOptions{static_cast<std::size_t>(sampling.segment_samples), sampling.overlap};
    gd::LiveSimulation sim(model, settings, sink);
    const double c0 = cpu_seconds();
    while (sim.iterate().running) {}
    const double c = cpu_seconds() - c0 - sink.psd_cpu;  // the stepping thread's share
    if (c < best) best = c;
    published = sink.published;
    checksum = sink.checksum;
    spectra = sink.spectra;
    if (spectra > 0) {
      copy_us = sink.copy_cpu / static_cast<double>(spectra) * 1e6;
      psd_ms = sink.psd_cpu / static_cast<double>(spectra) * 1e3;
    }
  }
  std::printf("{\"rate\": %g, \"t_end\": %g, \"cpu_s\": %.6f, \"sim_s_per_cpu_s\": %.3f, "
              "\"ns_per_step\": %.2f, \"published\": %ld, \"checksum\": %.17g, \"spectra\": %ld, "
              "\"spectrum_window_samples\": %lld, \"copy_us_per_spectrum\": %.1f, \"psd_ms_per_spectrum\": %.2f}\n",
              rate, t_end, best, t_end / best, best / (t_end / model.run.time_step) * 1e9, published, checksum,
              spectra, static_cast<long long>(sampling.window_samples), copy_us, psd_ms);
  return 0;
}

int subscribe(int argc, char** argv) {
  if (argc < 4) { std::fprintf(stderr, "usage: gear_live_bench subscribe TOPIC SECONDS\n"); return 2; }
  ros::init(argc, argv, "gear_live_bench_subscriber", ros::init_options::AnonymousName);
  ros::NodeHandle nh;
  long count = 0, gaps = 0;
  std::uint32_t last_seq = 0;
  ros::Subscriber sub = nh.subscribe<gd::GearState>(
      argv[2], 10000,
      [&](const gd::GearState::ConstPtr& m) {
        if (count > 0 && m->header.seq != last_seq + 1) gaps += m->header.seq - last_seq - 1;
        last_seq = m->header.seq;
        ++count;
      },
      ros::VoidConstPtr(), ros::TransportHints().tcpNoDelay());
  const ros::WallTime end = ros::WallTime::now() + ros::WallDuration(std::atof(argv[3]));
  while (ros::ok() && ros::WallTime::now() < end) ros::spinOnce(), ros::WallDuration(0.0005).sleep();
  std::printf("{\"received\": %ld, \"dropped\": %ld, \"cpu_s\": %.3f}\n", count, gaps, cpu_seconds());
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  const std::string mode = argc > 1 ? argv[1] : "";
  if (mode == "core") return core(argc, argv);
  if (mode == "subscribe") return subscribe(argc, argv);
  std::fprintf(stderr, "usage: gear_live_bench core [--rate HZ] [--t-end T] [--repeat K] | subscribe TOPIC SECONDS\n");
  return 2;
}
