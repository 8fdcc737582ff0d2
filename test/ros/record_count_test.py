#!/usr/bin/python3
"""simulate.launch record:=true as fast as possible (real_time_factor 0), t_end 2 s at 1 kHz: the
node's bag holds every message it published, 2001 states (t = 0, 1 ms, ..., 2 s, each once, in
order) and as many of each scalar, whatever the disk's speed (the node waits for its writer)."""
import glob
import os
import shutil
import signal
import subprocess
import sys
import tempfile
import unittest

import rosbag
import rospy
import rostest

from simtest import wait_until

T_END, RATE = 2.0, 1000.0
STATES = int(T_END * RATE) + 1  # both ends included


class RecordCount(unittest.TestCase):
    def test_every_message_of_a_fast_run(self):
        folder = tempfile.mkdtemp(prefix='gear_record_count_')
        self.addCleanup(shutil.rmtree, folder)
        log = tempfile.TemporaryFile('w+')
        launch = subprocess.Popen(
            ['roslaunch', 'gear_dynamics', 'simulate.launch', 'record:=true', 'record_dir:=' + folder,
             't_end:=%r' % T_END, 'real_time_factor:=0', 'publish_rate:=%r' % RATE, 'output:=screen'],
            stdout=log, stderr=subprocess.STDOUT, start_new_session=True)
        try:
            # The node closes the run's bag at t_end (renamed from .bag.active).
            wait_until(lambda: glob.glob(os.path.join(folder, 'gear_*.bag')), 60.0, 'the closed bag')
        finally:
            os.killpg(launch.pid, signal.SIGINT)
            launch.wait(timeout=30)
        log.seek(0)
        output = log.read()
        bags = glob.glob(os.path.join(folder, 'gear_*.bag'))
        self.assertEqual(len(bags), 1, os.listdir(folder))
        with rosbag.Bag(bags[0]) as bag:
            counts = bag.get_type_and_topic_info().topics
            times = [m.t for _, m, _ in bag.read_messages(topics=['/gear/state'])]
        print('messages per topic: %s' % {t: counts[t].message_count for t in sorted(counts)})
        self.assertEqual(counts['/gear/state'].message_count, STATES, output[-3000:])
        self.assertEqual(times, [round(k / RATE, 9) for k in range(STATES)])
        for t in ('/gear/delta', '/gear/delta_dot', '/gear/phi', '/gear/center_distance'):
            self.assertEqual(counts[t].message_count, STATES, t)
        self.assertEqual(counts['/gear/run_info'].message_count, 1)
        self.assertEqual(counts['/gear/final_state'].message_count, 1)
        self.assertIn('holds all %d messages' % (5 * STATES + 2), output)


if __name__ == '__main__':
    rospy.init_node('record_count_test')
    rostest.rosrun('gear_dynamics', 'record_count', RecordCount, sys.argv)
