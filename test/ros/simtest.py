"""Helpers shared by the gear_simulator rostests. Timeouts are in wall seconds: simulated time
stands still while the node is paused."""
import csv
import threading
import time
import xmlrpc.client

import rosgraph
import rospy
from std_srvs.srv import Empty, Trigger

CLOCK_OFFSET = 1.0  # kClockOffset in gear_dynamics/ros/conversions.hpp [s]


class Collector:
    """Every message of one topic, in arrival order."""

    def __init__(self, topic, msg_type):
        self._cond = threading.Condition()
        self._msgs = []
        self.sub = rospy.Subscriber(topic, msg_type, self._received, queue_size=None)

    def _received(self, msg):
        with self._cond:
            self._msgs.append(msg)
            self._cond.notify_all()

    def messages(self):
        with self._cond:
            return list(self._msgs)

    def clear(self):
        with self._cond:
            self._msgs = []

    def wait_for(self, predicate, timeout, what):
        """Waits until predicate(messages) holds; returns the messages."""
        deadline = time.time() + timeout
        with self._cond:
            while not predicate(self._msgs):
                left = deadline - time.time()
                if left <= 0:
                    raise AssertionError('timed out after %g s waiting for %s on %s (%d messages)'
                                         % (timeout, what, self.sub.name, len(self._msgs)))
                self._cond.wait(left)
            return list(self._msgs)

    def wait_connected(self, timeout=20.0):
        """Until a publisher is connected on both sides. This side counts a connection once the
        publisher's header has arrived, and roscpp writes that header before it adds the link to
        its publication: a message published in between (a reset's one state) is not sent here.
        So the publishers' own lists of links (XML-RPC getBusInfo) must name this node too."""
        wait_until(lambda: self.sub.get_num_connections() > 0, timeout,
                   'a publisher of ' + self.sub.name)
        wait_until(self._publishers_link_here, timeout,
                   'the publishers of %s to list this node among their links' % self.sub.name)

    def _publishers_link_here(self):
        me = rospy.get_name()
        master = rosgraph.Master(me)
        publishers = next((nodes for topic, nodes in master.getSystemState()[0] if topic == self.sub.resolved_name),
                          [])
        linked = 0
        for node in publishers:
            try:
                _, _, links = xmlrpc.client.ServerProxy(master.lookupNode(node)).getBusInfo(me)
            except (OSError, xmlrpc.client.Error, rosgraph.MasterError):
                continue  # a node gone since the master listed it
            linked += any(l[1] == me and l[2] == 'o' and l[4] == self.sub.resolved_name for l in links)
        return linked > 0 and linked >= self.sub.get_num_connections()


def wait_until(predicate, timeout, what):
    deadline = time.time() + timeout
    while not predicate():
        if time.time() > deadline:
            raise AssertionError('timed out after %g s waiting for %s' % (timeout, what))
        time.sleep(0.01)


def links_to(publisher, subscriber, topic):
    """Whether `publisher`'s own list of links (XML-RPC getBusInfo) holds a connected link to
    `subscriber` on `topic`: the master lists a subscriber before the connection exists."""
    master = rosgraph.Master(rospy.get_name())
    try:
        _, _, links = xmlrpc.client.ServerProxy(master.lookupNode(publisher)).getBusInfo(rospy.get_name())
    except (OSError, xmlrpc.client.Error, rosgraph.MasterError):
        return False
    return any(l[1] == subscriber and l[2] == 'o' and l[4] == topic and l[5] for l in links)


def services(node):
    """The node's ~pause, ~unpause, ~reset (std_srvs/Empty) and ~step (std_srvs/Trigger)."""
    proxies = {}
    for name, srv in (('pause', Empty), ('unpause', Empty), ('reset', Empty), ('step', Trigger)):
        rospy.wait_for_service(node + '/' + name, timeout=20.0)
        proxies[name] = rospy.ServiceProxy(node + '/' + name, srv)
    return proxies


def last_run(msgs):
    """The messages from the last one at t = 0 on (a run starts again at every reset)."""
    starts = [i for i, m in enumerate(msgs) if m.t == 0.0]
    assert starts, 'no state at t = 0'
    return msgs[starts[-1]:]


def ends_at(t_end, time_step=1e-6):
    """Whether the state at grid time t_end has arrived (t is step index times h, not t_end)."""
    end = round(t_end / time_step)
    return lambda msgs: any(round(m.t / time_step) == end for m in msgs)


def values(m):
    """A GearState's content without header.seq (which counts messages)."""
    return (m.header.stamp, m.t, m.delta, m.delta_dot, m.phi, m.center_distance, m.mesh_stiffness,
            m.mesh_phase, m.mu, m.sigma, m.realization, m.seed)


def read_csv(path):
    """Rows of a CSV with a header line; numbers as Python floats (17 digits round-trip doubles)."""
    with open(path) as f:
        return list(csv.DictReader(f))
