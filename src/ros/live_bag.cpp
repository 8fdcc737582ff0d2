#include "gear_dynamics/ros/live_bag.hpp"

#include <gear_dynamics/GearState.h>
#include <gear_dynamics/GearStateBatch.h>
#include <gear_dynamics/RunInfo.h>
#include <geometry_msgs/WrenchStamped.h>
#include <rosbag/bag.h>
#include <rosbag/view.h>

#include <cmath>
#include <map>
#include <stdexcept>

namespace gear_dynamics {

namespace {

bool ends_with(const std::string& s, const std::string& tail) {
  return s.size() >= tail.size() && s.compare(s.size() - tail.size(), tail.size(), tail) == 0;
}

// The state topic to read: state_batch if the bag has it (lossless at full speed), else the state
// topic with the most messages.
std::string choose_topic(const rosbag::Bag& bag) {
  rosbag::View all(bag);
  std::string batch, single;
  std::map<std::string, std::size_t> counts;
  for (const rosbag::ConnectionInfo* c : all.getConnections()) {
    if (c->datatype == "gear_dynamics/GearStateBatch") batch = c->topic;
    if (c->datatype == "gear_dynamics/GearState" && !ends_with(c->topic, "final_state"))
      counts[c->topic] = rosbag::View(bag, rosbag::TopicQuery(c->topic)).size();
  }
  if (!batch.empty()) return batch;
  for (const auto& [topic, n] : counts)
    if (single.empty() || n > counts[single]) single = topic;
  return single;
}

// A bearing's wrenches by their stamp (a later run's, after a ~reset, replaces an earlier one's).
struct Wrenches {
  std::string topic;
  std::map<ros::Time, std::pair<double, double>> force;  // force.x, force.y
};

Wrenches read_wrenches(const rosbag::Bag& bag, const std::string& suffix) {
  Wrenches w;
  rosbag::View all(bag);
  for (const rosbag::ConnectionInfo* c : all.getConnections())
    if (c->datatype == "geometry_msgs/WrenchStamped" && ends_with(c->topic, suffix)) w.topic = c->topic;
  if (w.topic.empty()) return w;
  for (const rosbag::MessageInstance& m : rosbag::View(bag, rosbag::TopicQuery(w.topic)))
    if (const auto msg = m.instantiate<geometry_msgs::WrenchStamped>())
      w.force[msg->header.stamp] = {msg->wrench.force.x, msg->wrench.force.y};
  return w;
}

// The wrench of each state's stamp. Throws naming the topic and the time of a state without one.
void pair_wrenches(const Wrenches& w, const std::string& path, const std::vector<GearState>& states,
                   std::size_t first, std::vector<double>& x, std::vector<double>& y) {
  for (std::size_t i = first; i < states.size(); ++i) {
    const auto it = w.force.find(states[i].header.stamp);
    if (it == w.force.end())
      throw std::runtime_error(path + ": " + w.topic + " has no wrench at the state of t = " +
                               std::to_string(states[i].t) + " s (stamp " + std::to_string(states[i].header.stamp.toSec()) +
                               "); record it with the states (record:=true, or rosbag record both topics)");
    x.push_back(it->second.first);
    y.push_back(it->second.second);
  }
}

}  // namespace

LiveBagRun read_live_bag(const std::string& path) {
  if (ends_with(path, ".bag.active"))
    throw std::runtime_error(path + " is still being written, or its recorder was killed: index it with `rosbag "
                                    "reindex " + path + "`, then read the .bag that this leaves");
  rosbag::Bag bag;
  try {
    bag.open(path, rosbag::bagmode::Read);
  } catch (const rosbag::BagException& e) {
    throw std::runtime_error("cannot read the bag " + path + ": " + e.what());
  }
  LiveBagRun run;
  run.topic = choose_topic(bag);
  if (run.topic.empty())
    throw std::runtime_error(path + " holds no gear_dynamics/GearState or GearStateBatch states (record /gear/state, "
                                    "/gear/state_batch, or use record:=true)");
  std::vector<GearState> states;
  std::size_t seq_gaps = 0;
  double gap_at = 0.0;
  bool have_seq = false;
  std::uint32_t last_seq = 0;
  for (const rosbag::MessageInstance& m : rosbag::View(bag, rosbag::TopicQuery(run.topic))) {
    if (const auto batch = m.instantiate<GearStateBatch>()) {
      states.insert(states.end(), batch->states.begin(), batch->states.end());
    } else if (const auto s = m.instantiate<GearState>()) {
      // The node's own bag keeps the publisher's sequence; a gap there is a lost state.
      if (have_seq && s->header.seq != last_seq + 1 && s->header.seq != 0 && !seq_gaps++) gap_at = s->t;
      have_seq = true;
      last_seq = s->header.seq;
      states.push_back(*s);
    }
  }
  for (const rosbag::MessageInstance& m : rosbag::View(bag))
    if (const auto info = m.instantiate<RunInfo>()) run.parameters_yaml = info->parameters_yaml;
  std::map<std::string, Wrenches> wrenches;
  for (const char* ending : kBearingWrenchTopics)
    if (Wrenches w = read_wrenches(bag, ending); !w.topic.empty()) wrenches[ending] = std::move(w);
  bag.close();
  if (seq_gaps > 0)
    throw std::runtime_error(path + ": " + run.topic + " lost states: " + std::to_string(seq_gaps) +
                             " gaps in header.seq, the first before t = " + std::to_string(gap_at) +
                             " s; record state_batch or use record:=true (doc/gear_simulator.md §3.2)");
  // After a ~reset t starts again at 0: the last run.
  std::size_t first = 0;
  for (std::size_t i = 1; i < states.size(); ++i)
    if (states[i].t < states[i - 1].t) first = i;
  if (first > 0) run.note = "the bag holds " + std::to_string(first) + " states of earlier runs (before a ~reset): read the last run only";
  if (states.size() - first < 8)
    throw std::runtime_error(path + ": " + run.topic + " has " + std::to_string(states.size() - first) +
                             " states of the last run; at least 8 are needed");
  const double dt = states[first + 1].t - states[first].t;
  for (std::size_t i = first; i < states.size(); ++i) {
    const GearState& s = states[i];
    if (i > first && std::abs(s.t - states[i - 1].t - dt) > 1e-6 * dt)
      throw std::runtime_error(path + ": " + run.topic + " has uneven times: " + std::to_string(states[i - 1].t) +
                               " s then " + std::to_string(s.t) + " s (recording period " + std::to_string(dt) +
                               " s): states were lost, or the publish rate changed during the run");
    run.t.push_back(s.t);
    run.delta.push_back(s.delta);
    run.delta_dot.push_back(s.delta_dot);
    run.phi.push_back(s.phi);
    run.stiffness.push_back(s.mesh_stiffness);
  }
  for (const auto& [ending, w] : wrenches) {
    LiveBagRun::Forces& f = run.wrenches[ending];
    pair_wrenches(w, path, states, first, f.x, f.y);
  }
  return run;
}

}  // namespace gear_dynamics
