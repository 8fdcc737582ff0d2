#include "gear_dynamics/live/live_spectrum.hpp"

#include <cmath>
#include <ctime>
#include <exception>
#include <utility>

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

SpectrumWorker::SpectrumWorker(const SpectrumSampling& sampling, Publish publish, Error error)
    : sampling_(sampling), publish_(std::move(publish)), error_(std::move(error)) {
  worker_ = std::thread(&SpectrumWorker::work, this);
}

SpectrumWorker::~SpectrumWorker() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stop_ = true;
  }
  wake_.notify_all();
  worker_.join();
}

void SpectrumWorker::submit(const SpectrumSamples& window) {
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

SpectrumWorker::Stats SpectrumWorker::stats() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return stats_;
}

bool SpectrumWorker::compute(const Window& w, LiveSpectrum& out) {
  const WelchOptions options{static_cast<std::size_t>(sampling_.segment_samples), sampling_.overlap};
  try {
    out.delta = welch_psd(w.delta, w.meta.sample_rate, options);
    out.force = welch_psd(w.force, w.meta.sample_rate, options);
  } catch (const std::exception& e) {
    error_(e.what());
    return false;
  }
  out.t = w.meta.t;
  out.window_start = w.meta.window_start;
  out.samples = static_cast<std::uint32_t>(w.delta.size());
  out.sample_steps = static_cast<std::uint32_t>(sampling_.sample_steps);
  out.sample_rate = w.meta.sample_rate;
  out.mesh_frequency = w.meta.mesh_frequency;
  return finite(out.delta.density) && finite(out.force.density);
}

void SpectrumWorker::work() {
  Window w;
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
    LiveSpectrum spectrum;
    const bool good = compute(w, spectrum);
    if (good) publish_(spectrum);
    std::lock_guard<std::mutex> lock(mutex_);
    busy_ = false;
    if (!good) continue;
    ++stats_.published;
    stats_.cpu_per_update = thread_cpu_seconds() - cpu0;
  }
}

}  // namespace gear_dynamics
