// The live node's own bag (simulate.launch record:=true): every message gear_simulator publishes on
// its topics is written in-process through rosbag's C++ API, under the absolute topic names. The
// stepping thread hands messages to a writer thread through a bounded queue and waits when the
// queue is full, so the simulation slows down to the disk instead of losing a message (at any
// real_time_factor). A write error (disk full, unwritable folder) is never silent: it is logged at
// once, the messages not written are counted, and diagnostics turn ERROR (see written(), lost()).
#pragma once

#include <rosbag/bag.h>
#include <ros/time.h>

#include <condition_variable>
#include <cstdint>
#include <deque>
#include <functional>
#include <mutex>
#include <string>
#include <thread>

namespace gear_dynamics {

class LiveRecorder {
 public:
  // Writes `path` (as PATH.active until closed, as rosbag record does), LZ4-compressed.
  explicit LiveRecorder(const std::string& path);
  ~LiveRecorder();  // close()

  // Queues `msg` for `topic` (absolute) at bag time `stamp`; blocks while the queue is full.
  template <class M>
  void write(const std::string& topic, const ros::Time& stamp, const M& msg) {
    push([topic, stamp, msg](rosbag::Bag& bag) { bag.write(topic, stamp, msg); });
  }
  // Writes what is queued and closes the bag (renamed from .active). Idempotent.
  void close();

  const std::string& path() const { return path_; }
  std::uint64_t written() const;       // messages in the bag
  std::uint64_t lost() const;          // messages that could not be written (after an error)
  double waited_seconds() const;       // wall time the stepping thread waited for the writer
  std::string error() const;           // the first write error, empty if none

  static constexpr std::size_t kCapacity = 20000;  // queued messages before the producer waits

 private:
  void push(std::function<void(rosbag::Bag&)> item);
  void run();

  std::string path_;
  rosbag::Bag bag_;
  mutable std::mutex mutex_;
  std::condition_variable not_empty_, not_full_;
  std::deque<std::function<void(rosbag::Bag&)>> queue_;
  bool closing_ = false, closed_ = false;
  std::uint64_t written_ = 0, lost_ = 0;
  double waited_ = 0.0;
  std::string error_;
  std::thread writer_;
};

}  // namespace gear_dynamics
