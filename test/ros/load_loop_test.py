#!/usr/bin/python3
"""The simulator as the plant of a control loop: load_controller.py holds Phi at 30 m/s^2 through
/gear/load_command while the load noise (sigma 50 m/s^2/sqrt(s)) pushes it away. Over two seconds
of simulated time Phi stays near the setpoint (open loop it would wander by ~70 m/s^2), the node
applies the commands (diagnostics count them) and the states carry the noise (Phi is not constant)."""
import math
import sys
import unittest

import rospy
import rostest
from diagnostic_msgs.msg import DiagnosticArray
from gear_dynamics.msg import GearState

from simtest import Collector

SETPOINT = 30.0


class LoadLoop(unittest.TestCase):
    def test_closed_loop_holds_phi(self):
        state = Collector('/gear/state', GearState)
        diagnostics = Collector('/diagnostics', DiagnosticArray)

        def applied(n):
            def check(arrays):
                for a in arrays:
                    for s in a.status:
                        if 'gear/gear_simulator' in s.name:
                            values = {kv.key: kv.value for kv in s.values}
                            if int(values.get('load commands applied', '0')) > n:
                                return True
                return False
            return check
        # The loop is closed once the controller's commands arrive (it starts after the node).
        diagnostics.wait_for(applied(0), 30.0, 'a first load command applied')
        start = state.wait_for(len, 10.0, 'a state')[-1].t + 0.5  # settled
        msgs = state.wait_for(lambda m: m[-1].t >= start + 2.0, 60.0, 'two more seconds')
        window = [m.phi for m in msgs if m.t >= start]
        rms = math.sqrt(sum((p - SETPOINT) ** 2 for p in window) / len(window))
        print('Phi over t in [%.3f, %.3f] s: %d states, rms error %.3f m/s^2, range [%.2f, %.2f]'
              % (start, msgs[-1].t, len(window), rms, min(window), max(window)))
        self.assertLess(rms, 15.0)
        self.assertGreater(max(window) - min(window), 1.0)  # the noise is there, the loop cancels its drift
        diagnostics.wait_for(applied(100), 10.0, 'more than 100 load commands applied')


if __name__ == '__main__':
    rospy.init_node('load_loop_test')
    rostest.rosrun('gear_dynamics', 'load_loop', LoadLoop, sys.argv)
