#!/usr/bin/python3
"""One rule for a bad value: refused. At start, roslaunch of simulate.launch exits non-zero before
any node starts and names the key (the launch file validates its values with gear_run
--check-simulator while it is parsed), for an argument, an overlay file and an unwritable record
folder. At run time, dynamic_reconfigure answers with the value in effect (the same value refused)."""
import os
import subprocess
import sys
import tempfile
import unittest

import dynamic_reconfigure.client
import rospy
import rostest


def roslaunch(*args):
    """roslaunch simulate.launch ARGS: (exit code, output)."""
    p = subprocess.run(['roslaunch', 'gear_dynamics', 'simulate.launch', 'ns:=refused', 'output:=screen'] + list(args),
                       stdout=subprocess.PIPE, stderr=subprocess.STDOUT, timeout=60, text=True)
    return p.returncode, p.stdout


class StartFailure(unittest.TestCase):
    def test_bad_argument(self):
        code, out = roslaunch('real_time_factor:=-1')
        self.assertNotEqual(code, 0, out)
        self.assertIn('simulator.real_time_factor = -1 is out of range', out)

    def test_bad_overlay_file(self):
        with tempfile.NamedTemporaryFile('w', suffix='.yaml') as f:
            f.write('simulator:\n  publish_rate: 0.0\n')
            f.flush()
            code, out = roslaunch('config:=' + f.name)
        self.assertNotEqual(code, 0, out)
        self.assertIn('simulator.publish_rate = 0 is out of range', out)

    def test_missing_record_folder(self):
        code, out = roslaunch('record:=true', 'record_dir:=/nonexistent/gear_record')
        self.assertNotEqual(code, 0, out)
        self.assertIn('/nonexistent/gear_record', out)

    def test_same_value_refused_at_run_time(self):
        client = dynamic_reconfigure.client.Client('/good/gear_simulator', timeout=20)
        answer = client.update_configuration({'real_time_factor': -1.0})
        self.assertEqual(answer['real_time_factor'], 1.0)  # the value in effect, kept
        answer = client.update_configuration({'publish_rate': 0.0})
        self.assertEqual(answer['publish_rate'], 1000.0)


if __name__ == '__main__':
    rospy.init_node('start_failure_test')
    rostest.rosrun('gear_dynamics', 'start_failure', StartFailure, sys.argv)
