#!/usr/bin/python3
"""/clock of a running gear_simulator: never 0, at least the clock offset, strictly increasing;
state stamped in simulated time exactly one publish period apart."""
import sys
import time
import unittest

import rospy
import rostest
from rosgraph_msgs.msg import Clock

from gear_dynamics.msg import GearState

from simtest import CLOCK_OFFSET, Collector


class ClockTest(unittest.TestCase):
    def test_clock_positive_and_monotonic(self):
        clock = Collector('/clock', Clock)
        clock.wait_for(lambda m: len(m) > 0, 20.0, 'a first /clock')
        time.sleep(1.0)
        stamps = [m.clock.to_sec() for m in clock.messages()]
        # 1 wall second at real_time_factor 1, /clock throttled to 200 Hz of wall time: ~200.
        self.assertGreater(len(stamps), 50)
        self.assertGreaterEqual(min(stamps), CLOCK_OFFSET)
        backwards = [(a, b) for a, b in zip(stamps, stamps[1:]) if not b > a]
        self.assertEqual(backwards, [], 'clock did not increase')

    def test_state_stamps_one_publish_period_apart(self):
        state = Collector('/gear/state', GearState)
        state.wait_for(lambda m: len(m) > 200, 20.0, '200 states')
        msgs = state.messages()
        # 1 kHz in simulated time: consecutive states are 1 ms (1000 integration steps) apart.
        gaps = [round((b.t - a.t) * 1e6) for a, b in zip(msgs, msgs[1:])]
        self.assertEqual(set(gaps), {1000})
        for m in msgs:
            self.assertAlmostEqual(m.header.stamp.to_sec(), CLOCK_OFFSET + m.t, places=6)


if __name__ == '__main__':
    rospy.init_node('clock_test')
    rostest.rosrun('gear_dynamics', 'clock_test', ClockTest, sys.argv)
