#!/usr/bin/python3
"""Bad parameters, Ctrl-C and divergence of gear_simulator."""
import math
import os
import signal
import subprocess
import sys
import time
import unittest

import rosparam
import rospkg
import rospy
import rostest
from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus
from gear_dynamics.msg import GearState, RunInfo
from rosgraph_msgs.msg import Clock
from std_msgs.msg import Float64

from simtest import Collector, services

NS = '/sandbox'
NODE = NS + '/gear_simulator'
# (parameter, bad value or None = left out, the name the log must give)
BAD = [
    ('load/sigma', -1.0, 'load.sigma'),
    ('gear_pair/backlahs', 5e-5, 'gear_pair.backlahs'),
    ('run/seed', None, 'run.seed'),
    ('simulator/publish_rate', 0.0, 'simulator.publish_rate'),
    ('simulator/t_end', 'soon', 'simulator.t_end'),
    ('simulator/loop', 'yes please', 'simulator.loop'),
]


def upload_defaults():
    if rospy.has_param(NODE):
        rospy.delete_param(NODE)
    config = os.path.join(rospkg.RosPack().get_path('gear_dynamics'), 'config')
    for name in ('gear_pair', 'load', 'run', 'simulator'):
        for params, _ in rosparam.load_file(os.path.join(config, name + '.yaml')):
            rosparam.upload_params(NODE, params)


def start_node():
    return subprocess.Popen(['rosrun', 'gear_dynamics', 'gear_simulator', '__ns:=' + NS],
                            stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)


class Robustness(unittest.TestCase):
    def test_1_bad_parameter_exits_naming_it(self):
        published = [Collector('/clock', Clock), Collector(NS + '/state', GearState),
                     Collector(NS + '/run_info', RunInfo)]
        for param, value, name in BAD:
            upload_defaults()
            if value is None:
                rospy.delete_param(NODE + '/' + param)
            else:
                rospy.set_param(NODE + '/' + param, value)
            node = start_node()
            log, _ = node.communicate(timeout=30)
            self.assertNotEqual(node.returncode, 0, log)
            self.assertIn(name, log)
            self.assertIn('FATAL', log)
        time.sleep(0.2)
        self.assertEqual([c.messages() for c in published], [[], [], []])

    def test_2_ctrl_c_stops_within_a_second(self):
        upload_defaults()
        rospy.set_param(NODE + '/simulator/real_time_factor', 0.0)  # busy stepping
        rospy.set_param(NODE + '/simulator/t_end', 0.0)
        state = Collector(NS + '/state', GearState)
        node = start_node()
        try:
            state.wait_for(lambda m: len(m) > 10, 30.0, 'the node running')
            start = time.time()
            node.send_signal(signal.SIGINT)
            node.wait(timeout=10)
            elapsed = time.time() - start
        finally:
            node.kill()
        self.assertEqual(node.returncode, 0)
        self.assertLess(elapsed, 1.0)
        rospy.loginfo('gear_simulator stopped %.3f s after SIGINT', elapsed)

    def test_3_divergence_pauses_and_publishes_no_nan(self):
        state = Collector('/diverge/gear/state', GearState)
        scalars = [Collector('/diverge/gear/' + t, Float64) for t in ('delta', 'delta_dot', 'phi', 'center_distance')]
        diagnostics = Collector('/diagnostics', DiagnosticArray)
        for c in [state] + scalars:
            c.wait_connected()
        srv = services('/diverge/gear/gear_simulator')
        srv['reset']()
        srv['unpause']()  # diverges at t = 0.12 ms, before the first publish instant (1 ms)

        def status(level, text):
            return lambda arrays: any(s.level == level and text in s.message and 'diverge/gear/gear_simulator' in s.name
                                      for a in arrays for s in a.status)
        diagnostics.wait_for(status(DiagnosticStatus.ERROR, 'diverged'), 10.0, 'an ERROR status')
        time.sleep(0.3)
        self.assertEqual({m.t for m in state.messages()}, {0.0})
        values = [v for m in state.messages() for v in (m.delta, m.delta_dot, m.phi, m.center_distance)]
        values += [m.data for c in scalars for m in c.messages()]
        self.assertTrue(values and all(math.isfinite(v) for v in values), values)
        with self.assertRaises(rospy.ServiceException):
            srv['unpause']()  # refused until ~reset

        state.clear()
        diagnostics.clear()
        srv['reset']()
        state.wait_for(lambda m: any(x.t == 0.0 for x in m), 10.0, 't = 0 after reset')
        diagnostics.wait_for(status(DiagnosticStatus.OK, 'paused'), 10.0, 'an OK status after reset')


if __name__ == '__main__':
    rospy.init_node('robustness_test')
    rostest.rosrun('gear_dynamics', 'robustness', Robustness, sys.argv)
