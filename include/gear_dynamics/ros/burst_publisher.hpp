// A topic of the live node whose messages leave in bursts (doc/gear_simulator.md §2, "Publishing"):
// the stepping thread holds the messages of a few publish instants and hands them to roscpp together.
//
// Why not ros::Publisher::publish per message: roscpp serializes the message, queues it for its poll
// thread and writes a byte into that thread's wake-up pipe, every time; the poll thread then reads
// the byte and sends the message with one send() per subscriber. At 10 kHz those syscalls and the
// thread hand-offs cost the node more than the stepping itself. Here a burst of n ≥ 2 messages is
// serialized back to back, each with its own length prefix and header.seq, into one buffer that goes
// into the publication's queue as one entry (ros::Publication::enqueueMessage, what roscpp's poll
// thread does with each published message): the poll thread is woken once per burst and sends the
// burst with one send(). A TCPROS subscriber reads the same byte stream as before, so it receives the
// same messages, stamps, sequence numbers and order. That holds only for stream transports: a burst
// goes out message by message whenever a link is not TCPROS (UDPROS frames each queue entry as one
// message; an intraprocess link hands it to the callback as one message).
#pragma once

#include <ros/publication.h>
#include <ros/ros.h>
#include <ros/topic_manager.h>

#include <atomic>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

namespace gear_dynamics {

template <class M>
class BurstPublisher {
 public:
  BurstPublisher() = default;
  BurstPublisher(ros::NodeHandle& nh, const std::string& name, uint32_t queue) {
    auto n = subscribers_;
    pub_ = nh.advertise<M>(name, queue, [n](const ros::SingleSubscriberPublisher&) { ++*n; },
                           [n](const ros::SingleSubscriberPublisher&) { --*n; });
    topic_ = pub_.getTopic();
    publication_ = ros::TopicManager::instance()->lookupPublication(topic_);
  }

  // Counted through roscpp's connect callbacks: Publisher::getNumSubscribers looks the topic up by
  // name under a lock (five lookups cost ~2 us per publish instant, a fifth of a core at 10 kHz).
  bool wanted() const { return subscribers_->load(std::memory_order_relaxed) > 0; }
  const std::string& topic() const { return topic_; }  // absolute, as the bag stores it
  std::size_t held() const { return held_; }

  // The next message of the burst, to be filled in (a reused slot: no allocation once warm).
  M& hold() {
    if (held_ == burst_.size()) burst_.emplace_back();
    return burst_[held_++];
  }

  // Hands the held messages to roscpp, in order.
  void flush() {
    if (held_ == 0) return;
    if (!publication_) {  // not expected (advertise failed); the plain path still works
      for (std::size_t i = 0; i < held_; ++i) pub_.publish(burst_[i]);
    } else if (held_ == 1 || !stream_links_only()) {
      for (std::size_t i = 0; i < held_; ++i)
        publication_->enqueueMessage(ros::serialization::serializeMessage(burst_[i]));
    } else {
      enqueue_burst();
    }
    held_ = 0;
  }

 private:
  // Every subscriber link a TCP stream (TCPROS). Asked at each burst, not cached from the connect
  // callbacks: those run on the spinner thread after the link is already in the publication.
  bool stream_links_only() const {
    XmlRpc::XmlRpcValue links;
    links.setSize(0);  // getInfo appends at links.size(), which throws on a value that is not an array
    publication_->getInfo(links);
    for (int i = 0; i < links.size(); ++i)
      if (static_cast<std::string&>(links[i][3]) != "TCPROS") return false;
    return true;
  }

  void enqueue_burst() {
    namespace ser = ros::serialization;
    // The sequence numbers roscpp would give them one by one: enqueueMessage sets the first
    // message's header.seq to the publication's counter and advances it once; this thread is the
    // only one that publishes on the topic, so the rest follow from the counter read here.
    const std::uint32_t seq = publication_->getSequence();
    std::uint32_t bytes = 0;
    for (std::size_t i = 0; i < held_; ++i) {
      if constexpr (ros::message_traits::HasHeader<M>::value) burst_[i].header.seq = seq + static_cast<std::uint32_t>(i);
      bytes += 4 + ser::serializationLength(burst_[i]);
    }
    boost::shared_array<uint8_t> buffer(new uint8_t[bytes]);
    ser::OStream out(buffer.get(), bytes);
    for (std::size_t i = 0; i < held_; ++i) {
      out.next(ser::serializationLength(burst_[i]));
      ser::serialize(out, burst_[i]);
    }
    if (!publication_->enqueueMessage(ros::SerializedMessage(buffer, bytes))) return;  // dropped: shutting down
    for (std::size_t i = 1; i < held_; ++i) publication_->incrementSequence();
  }

  ros::Publisher pub_;
  ros::PublicationPtr publication_;
  std::string topic_;
  std::shared_ptr<std::atomic<int>> subscribers_ = std::make_shared<std::atomic<int>>(0);
  std::vector<M> burst_;
  std::size_t held_ = 0;
};

}  // namespace gear_dynamics
