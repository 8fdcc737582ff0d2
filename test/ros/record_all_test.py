#!/usr/bin/python3
"""Standard tools at real_time_factor 0 (doc/gear_simulator.md §3.2): a recorder started first and
a node started paused, then unpaused, as a ROS user records a run.

- `rosbag record -a`: every state by header.seq (0 .. N-1, no gap) with t = 0, 1 ms, ..., t_end;
  every Float64 topic and state_batch complete too (the node paces what it sends).
- `rosbag record -a` started first and the node not paused: the node holds t = 0 for
  simulator.subscriber_wait, and the bag has every state from t = 0.
- `rosbag record NS/state_batch` alone: every state from t = 0 to t_end, in far fewer messages
  (bursts of up to 64 states), with the batches' header.seq without a gap.
"""
import os
import shutil
import signal
import subprocess
import sys
import tempfile
import time
import unittest
import xmlrpc.client

import rosbag
import rosgraph
import rosnode
import rospy
import rostest

from gear_dynamics.msg import GearState
from std_srvs.srv import Empty

NODE = '/gear/gear_simulator'
PER_INSTANT = ['/gear/state', '/gear/delta', '/gear/delta_dot', '/gear/phi', '/gear/center_distance']
BATCH = '/gear/state_batch'
PERIOD = 1e-3


def grid(count):
    return [round(k * PERIOD, 9) for k in range(count)]


class RecordAll(unittest.TestCase):
    def setUp(self):
        self.tmp = tempfile.mkdtemp(prefix='gd_record_all_')
        self.addCleanup(shutil.rmtree, self.tmp)
        self.processes = []
        self.addCleanup(self.stop_all)

    def stop_all(self):
        for p in reversed(self.processes):
            if p.poll() is None:
                os.killpg(p.pid, signal.SIGINT)
                p.wait(timeout=40)

    def start(self, *command):
        p = subprocess.Popen(list(command), stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                             start_new_session=True)
        self.processes.append(p)
        return p

    def connected(self, recorder, topics):
        """Whether the node has a connection to `recorder` on each of `topics` (its bus info)."""
        master = rosgraph.Master('/record_all_test')
        try:
            uri = rosnode.get_api_uri(master, NODE, skip_cache=True)
            if not uri:
                return False
            _, _, bus = xmlrpc.client.ServerProxy(uri).getBusInfo('/record_all_test')
        except (OSError, rosgraph.MasterError):
            return False
        linked = {c[4] for c in bus if c[1] == recorder and c[2] == 'o' and c[5]}
        return set(topics) <= linked

    def record(self, name, recorder_args, topics, t_end):
        """Recorder first, the node paused at rtf 0, then ~unpause; returns the bag's path."""
        bag = os.path.join(self.tmp, name + '.bag')
        recorder = self.start('rosbag', 'record', '-O', bag, '__name:=' + name, *recorder_args)
        launch = self.start('roslaunch', 'gear_dynamics', 'simulate.launch', 'paused:=true',
                            'real_time_factor:=0', 't_end:=%g' % t_end)
        rospy.wait_for_service(NODE + '/unpause', timeout=30.0)
        deadline = time.time() + 30.0
        while not self.connected('/' + name, topics):
            self.assertLess(time.time(), deadline, 'the recorder did not connect to %s' % topics)
            time.sleep(0.1)
        start = time.time()
        rospy.ServiceProxy(NODE + '/unpause', Empty)()
        rospy.wait_for_message('/gear/final_state', GearState, timeout=120.0)
        wall = time.time() - start
        time.sleep(1.0)  # the recorder drains its queue
        os.killpg(recorder.pid, signal.SIGINT)
        recorder.wait(timeout=30)
        os.killpg(launch.pid, signal.SIGINT)
        launch.wait(timeout=40)
        print('%s: t_end %g s in %.2f s of wall time' % (name, t_end, wall))
        return bag

    def test_record_all_started_first_unpaused(self):
        """`rosbag record -a` started first, then a launch at real_time_factor 0 that is not paused: the
        node holds t = 0 for simulator.subscriber_wait while the recorder (polling the master once a
        second) finds it, so the bag has every state from t = 0 without a gap."""
        t_end = 2.0
        count = int(t_end / PERIOD) + 1
        bag_path = os.path.join(self.tmp, 'first.bag')
        recorder = self.start('rosbag', 'record', '-a', '-O', bag_path, '__name:=recorder_first')
        deadline = time.time() + 30.0
        while '/recorder_first' not in rosnode.get_node_names():
            self.assertLess(time.time(), deadline, 'the recorder did not start')
            time.sleep(0.1)
        launch = self.start('roslaunch', 'gear_dynamics', 'simulate.launch', 'real_time_factor:=0',
                            't_end:=%g' % t_end)
        rospy.wait_for_message('/gear/final_state', GearState, timeout=120.0)
        time.sleep(1.0)  # the recorder drains its queue
        os.killpg(recorder.pid, signal.SIGINT)
        recorder.wait(timeout=30)
        os.killpg(launch.pid, signal.SIGINT)
        launch.wait(timeout=40)
        with rosbag.Bag(bag_path) as bag:
            states = [(m.header.seq, round(m.t, 9)) for _, m, _ in bag.read_messages(topics=['/gear/state'])]
        self.assertEqual([t for _, t in states], grid(count), 'the bag does not hold every state from t = 0')
        self.assertEqual([s for s, _ in states], list(range(count)), 'gaps in header.seq')

    def batch_states(self, bag):
        seqs, times = [], []
        for _, m, _ in bag.read_messages(topics=[BATCH]):
            seqs.append(m.header.seq)
            times.extend(round(s.t, 9) for s in m.states)
        self.assertEqual(seqs, list(range(len(seqs))), 'a batch lost')
        return seqs, times

    def test_record_all_topics(self):
        t_end = 2.0
        count = int(t_end / PERIOD) + 1
        path = self.record('recorder_all', ['-a'], PER_INSTANT + [BATCH], t_end)
        with rosbag.Bag(path) as bag:
            states = [(m.header.seq, round(m.t, 9)) for _, m, _ in bag.read_messages(topics=['/gear/state'])]
            counts = bag.get_type_and_topic_info().topics
            _, batched = self.batch_states(bag)
        print('messages per topic: %s' % {t: counts[t].message_count for t in sorted(counts)})
        self.assertEqual([s for s, _ in states], list(range(count)), 'gaps in header.seq')
        self.assertEqual([t for _, t in states], grid(count))
        for topic in PER_INSTANT[1:]:
            self.assertEqual(counts[topic].message_count, count, topic)
        self.assertEqual(batched, grid(count))

    def test_state_batch_alone(self):
        t_end = 10.0
        count = int(t_end / PERIOD) + 1
        path = self.record('recorder_batch', [BATCH], [BATCH], t_end)
        with rosbag.Bag(path) as bag:
            seqs, batched = self.batch_states(bag)
        self.assertEqual(batched, grid(count))
        self.assertLess(len(seqs), count / 4, 'not batched')


if __name__ == '__main__':
    rospy.init_node('record_all_test')
    rostest.rosrun('gear_dynamics', 'record_all', RecordAll, sys.argv)
