// A topic of the live node whose messages leave in bursts (doc/gear_simulator.md §2, "Publishing"):
// the stepping thread holds the messages of a few publish instants and hands them to roscpp together.
//
// Why not ros::Publisher::publish per message: roscpp serializes the message, queues it for its poll
// thread and writes a byte into that thread's wake-up pipe, every time; the poll thread then reads
// the byte, moves the message into each subscriber link's queue and sends it with one send() per
// subscriber. At 10 kHz those syscalls and thread hand-offs cost the node more than its stepping.
//
// Here the messages of a burst are serialized back to back, each with its own length prefix, into one
// buffer, and the poll thread is woken once for it. There (a poll thread listener, where roscpp moves
// its own publish queue into the links) each message gets the header.seq roscpp would have given it
// and the buffer goes into the links' queues as one entry (ros::Publication::enqueueMessage), sent
// with one send(). A TCPROS subscriber reads the same byte stream as before: the same messages,
// stamps, sequence numbers and order. That holds only for stream transports, so a burst is split into
// one entry per message whenever a link is not TCPROS (UDPROS frames each entry as one message; an
// intraprocess link hands it to the callback as one message). The links are only touched from the
// poll thread, as roscpp does: enabling a socket's write interest from another thread races with the
// poll thread disabling it (TransportTCP's expecting_write_), which left the poll thread spinning on
// EPOLLOUT between bursts when this class enqueued from the stepping thread.
#pragma once

#include <ros/poll_manager.h>
#include <ros/publication.h>
#include <ros/ros.h>
#include <ros/topic_manager.h>

#include <atomic>
#include <cstdint>
#include <cstring>
#include <memory>
#include <mutex>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace gear_dynamics {

template <class M>
class BurstPublisher {
 public:
  BurstPublisher() = default;
  BurstPublisher(ros::NodeHandle& nh, const std::string& name, uint32_t queue) : shared_(std::make_shared<Shared>()) {
    auto n = subscribers_;
    pub_ = nh.advertise<M>(name, queue, [n](const ros::SingleSubscriberPublisher&) { ++*n; },
                           [n](const ros::SingleSubscriberPublisher&) { --*n; });
    topic_ = pub_.getTopic();
    shared_->publication = ros::TopicManager::instance()->lookupPublication(topic_);
    if (!shared_->publication) throw std::runtime_error("BurstPublisher: no publication for " + topic_);
    std::weak_ptr<Shared> weak = shared_;
    listener_ = ros::PollManager::instance()->addPollThreadListener([weak] {
      if (const auto s = weak.lock()) s->enqueue();
    });
  }
  BurstPublisher(BurstPublisher&& other) { *this = std::move(other); }
  BurstPublisher& operator=(BurstPublisher&& other) {
    disconnect();
    pub_ = std::move(other.pub_);
    topic_ = std::move(other.topic_);
    subscribers_ = std::move(other.subscribers_);
    shared_ = std::move(other.shared_);
    listener_ = other.listener_;
    other.listener_ = {};  // a copy of the handle: the moved-from one must not disconnect it
    burst_ = std::move(other.burst_);
    held_ = std::exchange(other.held_, 0);
    return *this;
  }
  ~BurstPublisher() { disconnect(); }

  // Counted through roscpp's connect callbacks: Publisher::getNumSubscribers looks the topic up by
  // name under a lock (five lookups cost ~2 us per publish instant, a fifth of a core at 10 kHz).
  bool wanted() const { return subscribers_->load(std::memory_order_relaxed) > 0; }
  const std::string& topic() const { return topic_; }  // absolute, as the bag stores it

  // The next message of the burst, to be filled in (a reused slot: no allocation once warm).
  M& hold() {
    if (held_ == burst_.size()) burst_.emplace_back();
    return burst_[held_++];
  }

  // Serializes the held messages, in order, and wakes roscpp's poll thread to send them. Without
  // subscribers (messages held only for the bag) nothing is serialized, as roscpp's publish() does.
  void flush() {
    if (held_ == 0) return;
    if (!wanted()) {
      held_ = 0;
      return;
    }
    namespace ser = ros::serialization;
    std::uint32_t bytes = 0;
    for (std::size_t i = 0; i < held_; ++i) bytes += 4 + ser::serializationLength(burst_[i]);
    Burst b{boost::shared_array<uint8_t>(new uint8_t[bytes]), bytes, static_cast<std::uint32_t>(held_)};
    ser::OStream out(b.buffer.get(), bytes);
    for (std::size_t i = 0; i < held_; ++i) {
      out.next(ser::serializationLength(burst_[i]));
      ser::serialize(out, burst_[i]);
    }
    held_ = 0;
    {
      std::lock_guard<std::mutex> lock(shared_->mutex);
      shared_->pending.push_back(std::move(b));
    }
    ros::PollManager::instance()->getPollSet().signal();
  }

 private:
  struct Burst {
    boost::shared_array<uint8_t> buffer;
    std::uint32_t bytes, messages;
  };

  // What the poll thread's listener reaches (it may run until the listener is disconnected).
  struct Shared {
    ros::PublicationPtr publication;
    std::mutex mutex;
    std::vector<Burst> pending, taken;  // under mutex; taken: the poll thread's, reused

    // Poll thread: the pending bursts into the publication's links, in order.
    void enqueue() {
      {
        std::lock_guard<std::mutex> lock(mutex);
        if (pending.empty()) return;
        taken.swap(pending);
      }
      for (Burst& b : taken) {
        if (b.messages == 1) {
          publication->enqueueMessage(ros::SerializedMessage(b.buffer, b.bytes));
        } else if (stream_links_only()) {
          // The seq roscpp would give each in turn: enqueueMessage sets the first message's to the
          // publication's counter and advances it once; only this thread advances it.
          number(b, publication->getSequence());
          if (publication->enqueueMessage(ros::SerializedMessage(b.buffer, b.bytes)))
            for (std::uint32_t i = 1; i < b.messages; ++i) publication->incrementSequence();
        } else {
          for (std::uint32_t at = 0; at < b.bytes;) {  // one entry per message, numbered by roscpp
            const std::uint32_t size = 4 + length_at(b, at);
            boost::shared_array<uint8_t> one(new uint8_t[size]);
            std::memcpy(one.get(), b.buffer.get() + at, size);
            publication->enqueueMessage(ros::SerializedMessage(one, size));
            at += size;
          }
        }
      }
      taken.clear();  // keeps the capacity
    }

    // Every subscriber link a TCP stream (TCPROS).
    bool stream_links_only() const {
      XmlRpc::XmlRpcValue links;
      links.setSize(0);  // getInfo appends at links.size(), which throws on a value that is not an array
      publication->getInfo(links);
      for (int i = 0; i < links.size(); ++i)
        if (static_cast<std::string&>(links[i][3]) != "TCPROS") return false;
      return true;
    }

    static std::uint32_t length_at(const Burst& b, std::uint32_t at) {
      std::uint32_t n;
      std::memcpy(&n, b.buffer.get() + at, 4);  // little endian, as ROS serializes
      return n;
    }

    // header.seq (the header's first field) of each message = first, first + 1, ...
    static void number(Burst& b, std::uint32_t first) {
      if (!ros::message_traits::HasHeader<M>::value) return;
      for (std::uint32_t at = 0, k = 0; at < b.bytes; ++k) {
        const std::uint32_t seq = first + k;
        std::memcpy(b.buffer.get() + at + 4, &seq, 4);
        at += 4 + length_at(b, at);
      }
    }
  };

  void disconnect() {
    // Waits for a listener call in progress (roscpp holds its signal mutex while calling).
    if (listener_.connected()) ros::PollManager::instance()->removePollThreadListener(listener_);
    listener_ = {};
  }

  ros::Publisher pub_;
  std::string topic_;
  std::shared_ptr<std::atomic<int>> subscribers_ = std::make_shared<std::atomic<int>>(0);
  std::shared_ptr<Shared> shared_;
  boost::signals2::connection listener_;
  std::vector<M> burst_;
  std::size_t held_ = 0;
};

}  // namespace gear_dynamics
