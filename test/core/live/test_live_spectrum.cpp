// The live spectrum worker: a window's PSD handed on off the loop thread, a diverged window dropped.
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "gear_dynamics/live/live_simulation.hpp"
#include "gear_dynamics/live/live_spectrum.hpp"

namespace gd = gear_dynamics;

// The spectrum worker (the live layer's, under the node's `spectrum` topic): a window holding a
// sine of a bin's frequency gives its line there in delta's PSD, Parseval's variance, and the
// window's metadata; a non-finite window is dropped, not handed on.
TEST(LiveSpectrum, WorkerHandsOnTheWindowsPsd) {
  gd::SpectrumSampling sampling;
  sampling.sample_steps = 4;
  sampling.update_steps = 4;
  sampling.window_samples = 4096;
  sampling.segment_samples = 1024;
  sampling.sample_rate = 8000.0;
  sampling.overlap = 0.5;
  const double f0 = 250.0, amplitude = 2e-5;  // bin 32 of 1024 at 8 kHz
  std::mutex mutex;
  std::condition_variable done;
  std::vector<gd::LiveSpectrum> got;
  std::vector<std::string> errors;
  gd::SpectrumWorker worker(
      sampling,
      [&](gd::LiveSpectrum& s) {
        std::lock_guard<std::mutex> lock(mutex);
        got.push_back(s);
        done.notify_all();
      },
      [&](const std::string& what) {
        std::lock_guard<std::mutex> lock(mutex);
        errors.push_back(what);
        done.notify_all();
      });
  gd::SampleRing ring(4096);
  for (int i = 0; i < 4096; ++i)
    ring.push(amplitude * std::sin(2 * M_PI * f0 * i / sampling.sample_rate), 100.0 + std::cos(2 * M_PI * f0 * i / 8000.0));
  gd::SpectrumSamples window;
  window.t = 0.5;
  window.window_start = 0.5 - 4095 / 8000.0;
  window.sample_rate = 8000.0;
  window.mesh_frequency = 500.0;
  window.last = true;
  window.samples = &ring;
  worker.submit(window);
  {
    std::unique_lock<std::mutex> lock(mutex);
    ASSERT_TRUE(done.wait_for(lock, std::chrono::seconds(20), [&] { return !got.empty(); }));
  }
  const gd::LiveSpectrum& s = got.front();
  EXPECT_EQ(s.samples, 4096u);
  EXPECT_EQ(s.sample_steps, 4u);
  EXPECT_EQ(s.t, 0.5);
  EXPECT_EQ(s.mesh_frequency, 500.0);
  ASSERT_EQ(s.delta.frequency.size(), 513u);
  const auto peak = std::max_element(s.delta.density.begin(), s.delta.density.end()) - s.delta.density.begin();
  EXPECT_EQ(s.delta.frequency[static_cast<std::size_t>(peak)], f0);
  double variance = 0;  // Parseval: sum(P) df = the variance of the sine, A^2 / 2
  for (double p : s.delta.density) variance += p * s.delta.resolution;
  EXPECT_NEAR(variance, amplitude * amplitude / 2, 1e-3 * amplitude * amplitude / 2);

  // A diverged window (NaN) is dropped: nothing more is handed on.
  ring.push(std::nan(""), 0.0);
  worker.submit(window);
  std::this_thread::sleep_for(std::chrono::milliseconds(200));
  const gd::SpectrumWorker::Stats stats = worker.stats();
  std::lock_guard<std::mutex> lock(mutex);
  EXPECT_EQ(got.size(), 1u);
  EXPECT_EQ(stats.published, 1u);
}
