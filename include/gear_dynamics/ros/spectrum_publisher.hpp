// The live node's optional topic `spectrum` (doc/gear_simulator.md §3): the live layer's
// SpectrumWorker computes the PSDs on its own thread; this publishes each as a gear_dynamics/Spectrum,
// latched, so a late subscriber gets the latest spectrum.
#pragma once

#include <ros/ros.h>

#include "gear_dynamics/live/live_spectrum.hpp"

namespace gear_dynamics {

class SpectrumPublisher {
 public:
  using Stats = SpectrumWorker::Stats;

  // Advertises `spectrum` (latched) under nh and starts the worker.
  SpectrumPublisher(ros::NodeHandle& nh, const SpectrumSampling& sampling);

  // Stepping thread: SpectrumWorker::submit.
  void submit(const SpectrumSamples& window) { worker_.submit(window); }
  Stats stats() const { return worker_.stats(); }

 private:
  void publish(LiveSpectrum& spectrum);

  ros::Publisher pub_;
  SpectrumWorker worker_;  // last: stopped before the publisher goes
};

}  // namespace gear_dynamics
