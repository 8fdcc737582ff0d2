#!/usr/bin/python3
"""simulate.launch as a user meets it. With the defaults the node runs until stopped (t_end 0) under
the namespace gear: every topic it publishes is /gear/... (or the global /clock, /diagnostics,
/rosout). A finite run (namespace finite, t_end 0.05 s) keeps its last state for late subscribers:
/finite/final_state is latched (with its center distance), as is /finite/run_info."""
import sys
import time
import unittest

import rosgraph
import rospy
import rostest
from gear_dynamics.msg import GearState, RunInfo

from simtest import Collector, wait_until

GLOBAL = {'/clock', '/diagnostics', '/rosout'}


def published_by(node):
    """The topics `node` publishes, from the master."""
    pubs, _, _ = rosgraph.Master('/watchable_test').getSystemState()
    return sorted(t for t, nodes in pubs if node in nodes)


class Watchable(unittest.TestCase):
    def test_default_runs_until_stopped_under_gear(self):
        state = Collector('/gear/state', GearState)
        info = Collector('/gear/run_info', RunInfo)
        self.assertEqual(info.wait_for(len, 20.0, 'run_info')[-1].duration, 0.0)  # open-ended
        state.wait_for(lambda m: len(m) > 0 and m[-1].t > 1.5, 30.0, 't past 1.5 s')
        # Still running: more states arrive, time goes on.
        t = state.messages()[-1].t
        state.wait_for(lambda m: m[-1].t > t + 0.5, 10.0, 'half a second more')
        topics = published_by('/gear/gear_simulator')
        self.assertIn('/gear/state', topics)
        self.assertIn('/gear/final_state', topics)
        self.assertEqual([t for t in topics if not t.startswith('/gear/') and t not in GLOBAL], [], topics)

    def test_final_state_for_a_late_subscriber(self):
        # Subscribe only once the finite run has ended.
        wait_until(self._ended, 60.0, 'the finite run to end')
        final = Collector('/finite/final_state', GearState)
        info = Collector('/finite/run_info', RunInfo)
        m = final.wait_for(len, 10.0, 'the latched final state')[-1]
        self.assertEqual(m.t, 0.05)
        self.assertGreater(m.center_distance, 0.0)  # d over [0, 0.05] s, though no one took the states
        self.assertEqual(info.wait_for(len, 10.0, 'the latched run_info')[-1].duration, 0.05)

    @staticmethod
    def _ended():
        """Whether /finite/gear_simulator reports 'stopped at t_end' in its diagnostics. Both nodes
        publish /diagnostics at 1 Hz: listen for 2.5 s, long enough to hear each of them (taking only
        the first message can lock onto the other node's phase and never hear this one)."""
        from diagnostic_msgs.msg import DiagnosticArray
        heard = []
        sub = rospy.Subscriber('/diagnostics', DiagnosticArray, heard.append)
        try:
            deadline = time.time() + 2.5
            while time.time() < deadline:
                if any('finite/gear_simulator' in s.name and s.message == 'stopped at t_end'
                       for arr in list(heard) for s in arr.status):
                    return True
                time.sleep(0.05)
            return False
        finally:
            sub.unregister()


if __name__ == '__main__':
    rospy.init_node('watchable_test')
    rostest.rosrun('gear_dynamics', 'watchable', Watchable, sys.argv)
