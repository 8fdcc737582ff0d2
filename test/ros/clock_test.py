#!/usr/bin/python3
"""/clock of a running gear_simulator: never 0, at least the clock offset, strictly increasing."""
import sys
import time
import unittest

import rospy
import rostest
from rosgraph_msgs.msg import Clock

from simtest import CLOCK_OFFSET, Collector


class ClockTest(unittest.TestCase):
    def test_clock_positive_and_monotonic(self):
        clock = Collector('/clock', Clock)
        clock.wait_for(lambda m: len(m) > 0, 20.0, 'a first /clock')
        time.sleep(1.0)
        stamps = [m.clock.to_sec() for m in clock.messages()]
        # 1 wall second at real_time_factor 1 and one clock per 1 ms publish period: ~1000.
        self.assertGreater(len(stamps), 100)
        self.assertGreaterEqual(min(stamps), CLOCK_OFFSET)
        backwards = [(a, b) for a, b in zip(stamps, stamps[1:]) if not b > a]
        self.assertEqual(backwards, [], 'clock did not increase')


if __name__ == '__main__':
    rospy.init_node('clock_test')
    rostest.rosrun('gear_dynamics', 'clock_test', ClockTest, sys.argv)
