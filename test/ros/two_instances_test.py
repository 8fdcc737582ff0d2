#!/usr/bin/python3
"""Two gear_simulator instances side by side in the namespaces left and right (one owns /clock):
each publishes only under its own namespace, their realizations differ, and pausing one leaves the
other running."""
import sys
import unittest

import rosgraph
import rospy
import rostest
from gear_dynamics.msg import GearState

from simtest import Collector, services

GLOBAL = {'/clock', '/diagnostics', '/rosout'}


class TwoInstances(unittest.TestCase):
    def test_side_by_side(self):
        left = Collector('/left/state', GearState)
        right = Collector('/right/state', GearState)
        left.wait_for(lambda m: len(m) > 100, 30.0, '100 left states')
        right.wait_for(lambda m: len(m) > 100, 30.0, '100 right states')
        self.assertEqual({m.realization for m in left.messages()}, {0})
        self.assertEqual({m.realization for m in right.messages()}, {1})
        pubs, _, _ = rosgraph.Master('/two_instances_test').getSystemState()
        for ns in ('left', 'right'):
            mine = [t for t, nodes in pubs if '/%s/gear_simulator' % ns in nodes]
            self.assertIn('/%s/state' % ns, mine)
            self.assertEqual([t for t in mine if not t.startswith('/%s/' % ns) and t not in GLOBAL], [], mine)
        clock_owners = [nodes for t, nodes in pubs if t == '/clock']
        self.assertEqual(clock_owners, [['/left/gear_simulator']])

        services('/left/gear_simulator')['pause']()
        rospy.sleep(0.0)
        n_left = len(left.messages())
        t_right = right.messages()[-1].t
        right.wait_for(lambda m: m[-1].t > t_right + 0.2, 20.0, 'right going on')
        self.assertLessEqual(len(left.messages()), n_left + 1)  # at most one in flight


if __name__ == '__main__':
    rospy.init_node('two_instances_test')
    rostest.rosrun('gear_dynamics', 'two_instances', TwoInstances, sys.argv)
