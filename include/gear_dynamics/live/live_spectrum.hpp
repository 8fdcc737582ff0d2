// The live node's spectrum (doc/gear_simulator.md §3): Welch PSDs (maths/spectrum.hpp) of delta and
// the mesh force over LiveSimulation's trailing window of grid samples. The stepping thread only
// copies the window (submit); a worker thread of its own computes the PSDs and hands each finite
// spectrum to a callback (the ROS node publishes it, latched), so the stepping loop's per-step cost
// does not change. No ROS.
#pragma once

#include <condition_variable>
#include <cstdint>
#include <functional>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "gear_dynamics/config/simulator_settings.hpp"
#include "gear_dynamics/live/live_simulation.hpp"
#include "gear_dynamics/maths/spectrum.hpp"

namespace gear_dynamics {

// One spectrum of the window ending at t.
struct LiveSpectrum {
  double t = 0, window_start = 0;  // [s]
  std::uint32_t samples = 0, sample_steps = 0;
  double sample_rate = 0, mesh_frequency = 0;  // [Hz]
  Psd delta, force;  // delta [m^2/Hz], mesh force [N^2/Hz]
};

class SpectrumWorker {
 public:
  struct Stats {
    std::uint64_t published = 0;  // spectra handed to the callback
    std::uint64_t skipped = 0;    // windows not computed: the worker was busy with an earlier one
    double cpu_per_update = 0.0;  // worker CPU per spectrum, the last one [s]
  };
  // Both called on the worker thread: `publish` with every finite spectrum (a diverging run's
  // window is dropped: the node reports the divergence), `error` with why a window gave none.
  using Publish = std::function<void(LiveSpectrum& spectrum)>;
  using Error = std::function<void(const std::string& what)>;

  SpectrumWorker(const SpectrumSampling& sampling, Publish publish, Error error);
  ~SpectrumWorker();  // stops and joins the worker
  SpectrumWorker(const SpectrumWorker&) = delete;
  SpectrumWorker& operator=(const SpectrumWorker&) = delete;

  // Stepping thread: copies the window for the worker, unless the worker is still busy with an
  // earlier one (then the window is skipped without a copy, which would cost the stepping thread
  // more than the sampling itself at high update rates); the last window of a run is always taken
  // (it replaces one still waiting), so a finite run's last spectrum is that of its end.
  void submit(const SpectrumSamples& window);
  Stats stats() const;

 private:
  struct Window {
    SpectrumSamples meta;  // meta.samples is not used here
    std::vector<double> delta, force;
  };
  void work();
  bool compute(const Window& w, LiveSpectrum& out);

  const SpectrumSampling sampling_;
  const Publish publish_;
  const Error error_;
  mutable std::mutex mutex_;
  std::condition_variable wake_;
  Window pending_;  // under mutex_
  bool has_pending_ = false, busy_ = false, stop_ = false;
  Stats stats_;     // under mutex_
  std::thread worker_;
};

}  // namespace gear_dynamics
