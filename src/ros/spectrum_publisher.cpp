#include "gear_dynamics/ros/spectrum_publisher.hpp"

#include <cmath>
#include <ctime>
#include <exception>
#include <utility>

#include "gear_dynamics/Spectrum.h"
#include "gear_dynamics/dynamics/spectrum.hpp"
#include "gear_dynamics/ros/conversions.hpp"

namespace gear_dynamics {

namespace {

double thread_cpu_seconds() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}

bool finite(const std::vector<double>& v) {
  for (double x : v)
    if (!std::isfinite(x)) return false;
  return true;
}

}  // namespace

SpectrumPublisher::SpectrumPublisher(ros::NodeHandle& nh, const SpectrumSampling& sampling) : sampling_(sampling) {
  pub_ = nh.advertise<Spectrum>("spectrum", 1, /*latch=*/true);
  worker_ = std::thread(&SpectrumPublisher::work, this);
}

SpectrumPublisher::~SpectrumPublisher() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stop_ = true;
  }
  wake_.notify_all();
  worker_.join();
}

void SpectrumPublisher::submit(const SpectrumSamples& window) {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if ((busy_ || has_pending_) && !window.last) {
      ++stats_.skipped;
      return;
    }
    if (has_pending_) ++stats_.skipped;  // replaced by the run's last window
    pending_.meta = window;
    pending_.meta.samples = nullptr;
    window.samples->copy_to(pending_.delta, pending_.force);  // reuses the vectors' capacity
    has_pending_ = true;
  }
  wake_.notify_one();
}

SpectrumPublisher::Stats SpectrumPublisher::stats() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return stats_;
}

void SpectrumPublisher::work() {
  Window w;
  const WelchOptions options{static_cast<std::size_t>(sampling_.segment_samples), sampling_.overlap};
  for (;;) {
    {
      std::unique_lock<std::mutex> lock(mutex_);
      wake_.wait(lock, [&] { return has_pending_ || stop_; });
      if (stop_) return;
      std::swap(w, pending_);
      has_pending_ = false;
      busy_ = true;
    }
    const double cpu0 = thread_cpu_seconds();
    Spectrum m;
    try {
      Psd d = welch_psd(w.delta, w.meta.sample_rate, options);
      Psd f = welch_psd(w.force, w.meta.sample_rate, options);
      m.header.stamp = sim_stamp(w.meta.t);
      m.t = w.meta.t;
      m.window_start = w.meta.window_start;
      m.samples = static_cast<std::uint32_t>(w.delta.size());
      m.sample_steps = static_cast<std::uint32_t>(sampling_.sample_steps);
      m.sample_rate = w.meta.sample_rate;
      m.window = "hann";
      m.segment = static_cast<std::uint32_t>(d.segment);
      m.overlap = d.overlap;
      m.segments = static_cast<std::uint32_t>(d.segments);
      m.resolution = d.resolution;
      m.enbw = d.enbw;
      m.mesh_frequency = w.meta.mesh_frequency;
      m.frequency = std::move(d.frequency);
      m.delta_psd = std::move(d.density);
      m.mesh_force_psd = std::move(f.density);
    } catch (const std::exception& e) {
      ROS_ERROR_THROTTLE(10.0, "spectrum: %s", e.what());
      m.frequency.clear();
    }
    // No NaN reaches a topic: a diverging run's last window is dropped (the node reports the divergence).
    const bool good = !m.frequency.empty() && finite(m.delta_psd) && finite(m.mesh_force_psd);
    if (good) pub_.publish(m);
    std::lock_guard<std::mutex> lock(mutex_);
    busy_ = false;
    if (!good) continue;
    ++stats_.published;
    stats_.cpu_per_update = thread_cpu_seconds() - cpu0;
  }
}

}  // namespace gear_dynamics
