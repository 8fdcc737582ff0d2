#!/usr/bin/python3
"""load_input: external: Phi is the last load_command, held, with no noise; a dynparam request for
sigma or lambda is refused and the server's answer shows the 0 in effect. A command out of range
is refused (Phi stays, diagnostics count it); a running node without commands for over a wall
second turns diagnostics WARN, Phi held."""
import time
import unittest

import dynamic_reconfigure.client
import rospy
import rostest
from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus
from gear_dynamics.msg import GearState
from std_msgs.msg import Float64

from simtest import Collector, services

COMMAND = 42.0  # [m/s^2], not load.initial_mean (20)


class ExternalLoad(unittest.TestCase):
    def test_command_held_and_noise_refused(self):
        client = dynamic_reconfigure.client.Client('/gear/gear_simulator', timeout=20)
        answer = client.update_configuration({'sigma': 5.0, 'lambda': 3.0})
        self.assertEqual((answer['sigma'], answer['lambda']), (0.0, 0.0))

        state = Collector('/gear/state', GearState)
        state.wait_connected()
        command = rospy.Publisher('/gear/load_command', Float64, queue_size=1, latch=True)
        time.sleep(1.0)  # the node's subscription connects (wall time: /clock stands still while paused)
        command.publish(Float64(COMMAND))
        time.sleep(0.5)
        srv = services('/gear/gear_simulator')
        for _ in range(5):
            srv['step']()
        msgs = state.wait_for(lambda m: len(m) >= 5, 20.0, 'five stepped states')
        self.assertEqual({m.phi for m in msgs[-3:]}, {COMMAND})
        self.assertEqual({m.sigma for m in msgs}, {0.0})

        diagnostics = Collector('/diagnostics', DiagnosticArray)
        command.publish(Float64(2.0e4))  # outside [-1e4, 1e4]
        time.sleep(0.5)
        state.clear()
        srv['step']()
        self.assertEqual(state.wait_for(len, 20.0, 'a stepped state')[-1].phi, COMMAND)

        def ours(arrays):
            return [s for a in arrays for s in a.status if s.name.endswith('simulation')]

        def value(s, key):
            return {v.key: v.value for v in s.values}.get(key)

        refused = lambda arrays: [s for s in ours(arrays) if value(s, 'load commands refused (out of range)') == '1']
        diagnostics.wait_for(refused, 10.0, 'one refused command in diagnostics')
        srv['unpause']()  # running without commands
        silent = lambda arrays: [s for s in ours(arrays) if s.level == DiagnosticStatus.WARN and
                                 'no load command' in s.message]
        diagnostics.wait_for(silent, 10.0, 'a WARN for the silent command stream')
        self.assertEqual(state.wait_for(lambda m: len(m) > 10, 20.0, 'states while running')[-1].phi, COMMAND)


if __name__ == '__main__':
    rospy.init_node('external_load_test')
    rostest.rosrun('gear_dynamics', 'external_load', ExternalLoad)
