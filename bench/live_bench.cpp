// gear_live_bench: the live node's costs (bench/live prints them).
//   gear_live_bench core [--rate HZ] [--t-end T] [--repeat K] [--no-center-distance]
//       LiveSimulation (the node's ROS-free core) at real_time_factor 0 with a sink that only
//       counts: simulated seconds per CPU second of the stepping thread (getrusage), best of K.
//   gear_live_bench subscribe TOPIC SECONDS
//       a roscpp subscriber (tcpNoDelay) that counts gear_dynamics/GearState messages on TOPIC for
//       SECONDS of wall time and prints the count and the sequence gaps (messages roscpp dropped).
#include <sys/resource.h>

#include <cstdio>
#include <cstdlib>
#include <string>

#include <ros/ros.h>

#include "gear_dynamics/GearState.h"
#include "gear_dynamics/config/config.hpp"
#include "gear_dynamics/config/simulator_settings.hpp"
#include "gear_dynamics/live/live_simulation.hpp"

namespace gd = gear_dynamics;

namespace {

double cpu_seconds() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return static_cast<double>(u.ru_utime.tv_sec + u.ru_stime.tv_sec) +
         1e-6 * static_cast<double>(u.ru_utime.tv_usec + u.ru_stime.tv_usec);
}

struct CountingSink : gd::LiveSink {
  bool center = true;
  long published = 0;
  double checksum = 0.0;
  void publish(const gd::LiveSample& s) override {
    ++published;
    checksum += s.delta + s.center_distance;
  }
  void run_info(const gd::LiveRunInfo&) override {}
  void log(gd::LiveLogLevel, const std::string&) override {}
  bool wants_center_distance() const override { return center; }
};

int core(int argc, char** argv) {
  double rate = 1000.0, t_end = 2.0;
  int repeat = 3;
  bool center = true;
  for (int i = 2; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--rate" && i + 1 < argc) rate = std::atof(argv[++i]);
    else if (a == "--t-end" && i + 1 < argc) t_end = std::atof(argv[++i]);
    else if (a == "--repeat" && i + 1 < argc) repeat = std::atoi(argv[++i]);
    else if (a == "--no-center-distance") center = false;
    else { std::fprintf(stderr, "gear_live_bench core: unknown option %s\n", a.c_str()); return 2; }
  }
  const std::string dir = GEAR_DYNAMICS_CONFIG_DIR;
  YAML::Node root = gd::read_yaml_files({dir + "/gear_pair.yaml", dir + "/load.yaml", dir + "/run.yaml",
                                         dir + "/simulator.yaml"});
  const gd::ModelConfig model = gd::parse_config(root);
  gd::SimulatorSettings settings = gd::parse_simulator_settings(root, model.run.time_step);
  settings.real_time_factor = 0.0;
  settings.publish_rate = rate;
  settings.t_end = t_end;
  settings.paused = false;
  double best = 1e300;
  long published = 0;
  double checksum = 0.0;
  for (int k = 0; k < repeat; ++k) {
    CountingSink sink;
    sink.center = center;
    gd::LiveSimulation sim(model, settings, sink);
    const double c0 = cpu_seconds();
    while (sim.iterate().running) {}
    const double c = cpu_seconds() - c0;
    if (c < best) best = c;
    published = sink.published;
    checksum = sink.checksum;
  }
  std::printf("{\"rate\": %g, \"t_end\": %g, \"cpu_s\": %.6f, \"sim_s_per_cpu_s\": %.3f, "
              "\"ns_per_step\": %.2f, \"published\": %ld, \"checksum\": %.17g}\n",
              rate, t_end, best, t_end / best, best / (t_end / model.run.time_step) * 1e9, published, checksum);
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
