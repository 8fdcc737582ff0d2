// The live node's optional topic `spectrum` (doc/gear_simulator.md §3): Welch PSDs of delta and the
// mesh force over LiveSimulation's trailing window of grid samples. The stepping thread only copies
// the window (submit); a worker thread of its own computes the PSDs (dynamics/spectrum.hpp) and
// publishes them latched, so the stepping loop's per-step cost does not change and a late subscriber
// gets the latest spectrum.
#pragma once

#include <ros/ros.h>

#include <condition_variable>
#include <cstdint>
#include <mutex>
#include <thread>
#include <vector>

#include "gear_dynamics/config/simulator_settings.hpp"
#include "gear_dynamics/live/live_simulation.hpp"

namespace gear_dynamics {

class SpectrumPublisher {
 public:
  struct Stats {
    std::uint64_t published = 0;  // spectra published
    std::uint64_t skipped = 0;    // windows not computed: the worker was busy with an earlier one
    double cpu_per_update = 0.0;  // worker CPU per spectrum, the last one [s]
  };

  // Advertises `spectrum` (latched) under nh and starts the worker.
  SpectrumPublisher(ros::NodeHandle& nh, const SpectrumSampling& sampling);
  ~SpectrumPublisher();  // stops and joins the worker
  SpectrumPublisher(const SpectrumPublisher&) = delete;
  SpectrumPublisher& operator=(const SpectrumPublisher&) = delete;

  // Stepping thread: copies the window for the worker, unless the worker is still busy with an
  // earlier one (then the window is skipped without a copy, which would cost the stepping thread
  // more than the sampling itself at high update rates); the last window of a run is always taken
  // (it replaces one still waiting), so a finite run's latched spectrum is that of its end.
  void submit(const SpectrumSamples& window);
  Stats stats() const;

 private:
  struct Window {
    SpectrumSamples meta;  // meta.samples is not used here
    std::vector<double> delta, force;
  };
  void work();

  const SpectrumSampling sampling_;
  ros::Publisher pub_;
  mutable std::mutex mutex_;
  std::condition_variable wake_;
  Window pending_;  // under mutex_
  bool has_pending_ = false, busy_ = false, stop_ = false;
  Stats stats_;     // under mutex_
  std::thread worker_;
};

}  // namespace gear_dynamics
