#!/usr/bin/python3
"""simulate.launch record:=true stopped by a signal mid-run (t_end 0: the run never ends by itself):

- Ctrl-C of roslaunch (SIGINT to the node) and SIGTERM to the node itself: the node closes its bag
  (renamed from .bag.active) and says on stderr, after roscpp's shutdown turned rosconsole off,
  `record: PATH holds all N messages published`; the bag holds exactly N messages, its states
  every publish period from t = 0 without a gap.
- SIGKILL: the bag stays as .bag.active without an index; `rosbag reindex` (doc/gear_simulator.md
  §8) makes it readable, with its states from t = 0 without a gap.
"""
import glob
import os
import re
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

NODE = '/gear/gear_simulator'
PERIOD = 1e-3  # the default publish rate, 1 kHz of simulated time


class StopSignal(unittest.TestCase):
    def setUp(self):
        self.folder = tempfile.mkdtemp(prefix='gd_stop_signal_')
        self.addCleanup(shutil.rmtree, self.folder)
        self.log = tempfile.TemporaryFile('w+')
        # real_time_factor 1: a stop comes while the node runs and writes its bag
        self.launch = subprocess.Popen(
            ['roslaunch', 'gear_dynamics', 'simulate.launch', 'record:=true', 'record_dir:=' + self.folder,
             'real_time_factor:=1', 'output:=screen'],
            stdout=self.log, stderr=subprocess.STDOUT, start_new_session=True)
        self.addCleanup(self.end_launch)
        # Stopped once 0.3 s of simulated time are in the bag (wall timeouts).
        msg = rospy.wait_for_message('/gear/state', GearState, timeout=30.0)
        while msg.t < 0.3:
            msg = rospy.wait_for_message('/gear/state', GearState, timeout=30.0)

    def end_launch(self):
        if self.launch.poll() is None:
            os.killpg(self.launch.pid, signal.SIGINT)
            self.launch.wait(timeout=40)

    def output(self):
        self.launch.wait(timeout=40)
        self.log.seek(0)
        return self.log.read()

    def node_pid(self):
        master = rosgraph.Master('/stop_signal_test')
        code, _, pid = xmlrpc.client.ServerProxy(rosnode.get_api_uri(master, NODE, skip_cache=True)).getPid('/stop_signal_test')
        self.assertEqual(code, 1)
        return pid

    def states(self, path):
        with rosbag.Bag(path) as bag:
            count = bag.get_message_count()
            times = [m.t for _, m, _ in bag.read_messages(topics=['/gear/state'])]
        self.assertGreater(len(times), 300, path)
        self.assertEqual(times, [round(k * PERIOD, 9) for k in range(len(times))], 'a gap in the states')
        return count

    def check_closed(self, signal_name):
        output = self.output()
        self.assertEqual(glob.glob(os.path.join(self.folder, '*.active')), [], output[-3000:])
        bags = glob.glob(os.path.join(self.folder, 'gear_*.bag'))
        self.assertEqual(len(bags), 1, os.listdir(self.folder))
        said = re.search(r'record: (\S+) holds all (\d+) messages published', output)
        self.assertIsNotNone(said, output[-3000:])
        self.assertEqual(said.group(1), bags[0])
        self.assertEqual(self.states(bags[0]), int(said.group(2)))
        self.assertIn('gear_simulator: stopped by %s at t = ' % signal_name, output)

    def test_ctrl_c_of_roslaunch(self):
        os.killpg(self.launch.pid, signal.SIGINT)
        self.check_closed('SIGINT')

    def test_sigterm_to_the_node(self):
        os.kill(self.node_pid(), signal.SIGTERM)  # the node is required: roslaunch ends after it
        self.check_closed('SIGTERM')

    def test_sigkill_then_reindex(self):
        # The bag's first chunk on disk (rosbag writes a chunk once it holds 768 kB).
        active = os.path.join(self.folder, '*.bag.active')
        deadline = time.time() + 60.0
        while not any(os.path.getsize(p) > 8192 for p in glob.glob(active)):
            self.assertLess(time.time(), deadline, 'no chunk written')
            time.sleep(0.1)
        os.kill(self.node_pid(), signal.SIGKILL)
        output = self.output()
        active = glob.glob(os.path.join(self.folder, 'gear_*.bag.active'))
        self.assertEqual(len(active), 1, os.listdir(self.folder))
        self.assertNotIn('holds all', output)
        with self.assertRaises(rosbag.ROSBagException):
            rosbag.Bag(active[0]).close()  # no index: unreadable as it is
        subprocess.run(['rosbag', 'reindex', active[0]], check=True, stdout=subprocess.DEVNULL)
        self.states(active[0])


if __name__ == '__main__':
    rospy.init_node('stop_signal_test')
    rostest.rosrun('gear_dynamics', 'stop_signal', StopSignal, sys.argv)
