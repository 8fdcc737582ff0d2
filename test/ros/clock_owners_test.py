#!/usr/bin/python3
"""Two gear_simulator instances that both publish /clock: each warns once, naming the other node,
within a few wall seconds (it asks the master once a wall second), and not again."""
import os
import signal
import subprocess
import sys
import tempfile
import time
import unittest

import rospy
import rostest

WARNING = '%s publishes /clock too'


class ClockOwners(unittest.TestCase):
    def test_each_names_the_other_once(self):
        launches = {}
        for ns in ('left', 'right'):
            log = tempfile.TemporaryFile('w+')
            launches[ns] = (log, subprocess.Popen(
                ['roslaunch', 'gear_dynamics', 'simulate.launch', 'ns:=' + ns, 'output:=screen'],
                stdout=log, stderr=subprocess.STDOUT, start_new_session=True))
        try:
            time.sleep(8.0)  # both up, then several checks of the master each
        finally:
            for _, p in launches.values():
                os.killpg(p.pid, signal.SIGINT)
            for _, p in launches.values():
                p.wait(timeout=40)
        for ns, other in (('left', 'right'), ('right', 'left')):
            log = launches[ns][0]
            log.seek(0)
            output = log.read()
            self.assertEqual(output.count('publishes /clock too'), 1, output[-3000:])
            self.assertIn(WARNING % ('/%s/gear_simulator' % other), output)
            self.assertIn('publish_clock:=false', output)


if __name__ == '__main__':
    rospy.init_node('clock_owners_test')
    rostest.rosrun('gear_dynamics', 'clock_owners', ClockOwners, sys.argv)
