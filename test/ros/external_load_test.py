#!/usr/bin/python3
"""load_input: external: Phi is the last load_command, held, with no noise; a dynparam request for
sigma or lambda is refused and the server's answer shows the 0 in effect."""
import time
import unittest

import dynamic_reconfigure.client
import rospy
import rostest
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


if __name__ == '__main__':
    rospy.init_node('external_load_test')
    rostest.rosrun('gear_dynamics', 'external_load', ExternalLoad)
