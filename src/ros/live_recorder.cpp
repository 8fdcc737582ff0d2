#include "gear_dynamics/ros/live_recorder.hpp"

#include <ros/console.h>

#include <chrono>
#include <cstdio>
#include <string>

#include "gear_dynamics/ros/stop_signal.hpp"

namespace gear_dynamics {

LiveRecorder::LiveRecorder(const std::string& path) : path_(path) {
  bag_.open(path_ + ".active", rosbag::bagmode::Write);  // throws rosbag::BagException
  bag_.setCompression(rosbag::compression::LZ4);
  writer_ = std::thread(&LiveRecorder::run, this);
}

LiveRecorder::~LiveRecorder() { close(); }

void LiveRecorder::push(std::function<void(rosbag::Bag&)> item) {
  std::unique_lock<std::mutex> lock(mutex_);
  if (closing_) {
    ++lost_;
    return;
  }
  if (queue_.size() >= kCapacity) {
    const auto start = std::chrono::steady_clock::now();
    not_full_.wait(lock, [&] { return queue_.size() < kCapacity || closing_; });
    waited_ += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    if (closing_) {
      ++lost_;
      return;
    }
  }
  queue_.push_back(std::move(item));
  not_empty_.notify_one();
}

void LiveRecorder::run() {
  std::unique_lock<std::mutex> lock(mutex_);
  for (;;) {
    not_empty_.wait(lock, [&] { return !queue_.empty() || closing_; });
    if (queue_.empty() && closing_) break;
    std::deque<std::function<void(rosbag::Bag&)>> items;
    items.swap(queue_);
    not_full_.notify_all();
    const bool failed = !error_.empty();
    lock.unlock();
    std::uint64_t ok = 0, bad = 0;
    std::string what;
    for (auto& item : items) {
      if (failed || !what.empty()) {
        ++bad;
        continue;
      }
      try {
        item(bag_);
        ++ok;
      } catch (const std::exception& e) {
        what = e.what();
        ++bad;
      }
    }
    lock.lock();
    written_ += ok;
    lost_ += bad;
    if (!what.empty() && error_.empty()) {
      error_ = what;
      ROS_ERROR("record: writing %s failed (%s): from here on the bag misses every message (counted in "
                "diagnostics)", path_.c_str(), what.c_str());
    }
  }
}

void LiveRecorder::close() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (closed_) return;
    closing_ = true;
    closed_ = true;
  }
  not_empty_.notify_all();
  not_full_.notify_all();
  if (writer_.joinable()) writer_.join();
  // At a stop by signal this runs after roscpp's shutdown: log_at_stop still reaches the terminal.
  try {
    bag_.close();
    if (std::rename((path_ + ".active").c_str(), path_.c_str()) != 0)
      log_at_stop(StopLog::Error, "record: could not rename " + path_ + ".active to " + path_);
  } catch (const std::exception& e) {
    log_at_stop(StopLog::Error, "record: closing " + path_ + " failed: " + e.what());
  }
  char line[256];
  if (lost_ > 0) {
    std::snprintf(line, sizeof line, "%llu messages; %llu could not be written (",
                  static_cast<unsigned long long>(written_), static_cast<unsigned long long>(lost_));
    log_at_stop(StopLog::Error, "record: " + path_ + " holds " + line + error_ + ")");
  } else {
    std::snprintf(line, sizeof line, "all %llu messages published (the stepping thread waited %.3f s for the disk)",
                  static_cast<unsigned long long>(written_), waited_);
    log_at_stop(StopLog::Info, "record: " + path_ + " holds " + line);
  }
}

std::uint64_t LiveRecorder::written() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return written_;
}

std::uint64_t LiveRecorder::lost() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return lost_;
}

double LiveRecorder::waited_seconds() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return waited_;
}

std::string LiveRecorder::error() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return error_;
}

}  // namespace gear_dynamics
