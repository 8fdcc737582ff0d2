#!/usr/bin/python3
"""simulate.launch at publish_rate 10 kHz, real_time_factor 0, t_end 1 s, started paused: after
~unpause a subscriber of state gets all 10000 states t = k * 0.1 ms (k = 1..10000), each once, in
order, header.seq one apart, stamp exactly t + 1 s in integer nanoseconds; a subscriber of delta gets
the same 10000 values in the same order; the latched final_state is the last state. The node
hands its messages to roscpp in bursts of up to 64 publish instants; a subscriber must not see it."""
import sys
import time
import unittest

import rospy
import rostest
from gear_dynamics.msg import GearState
from std_msgs.msg import Float64

from simtest import Collector, ends_at, services

T_END, RATE = 1.0, 10000
STEPS_PER_STATE = 100  # 1 / (RATE * h), h = 1 us
STATES = int(T_END * RATE)


class EveryMessage(unittest.TestCase):
    def test_every_state_in_order_with_exact_stamps(self):
        state = Collector('/gear/state', GearState)
        delta = Collector('/gear/delta', Float64)
        final = Collector('/gear/final_state', GearState)
        for c in (state, delta):
            c.wait_connected()
        proxies = services('/gear/gear_simulator')
        time.sleep(1.0)  # wall time (simulated time stands still while paused): the node's connect callbacks have run
        state.clear()  # t = 0 went out at the start, before the connection
        delta.clear()
        proxies['unpause']()
        # 5 s of node time would do on an idle machine; the suite shares 2 cores with builds.
        msgs = state.wait_for(ends_at(T_END), 60.0, 't_end')
        values = delta.wait_for(lambda m: len(m) >= STATES, 30.0, '%d deltas' % STATES)
        end = final.wait_for(len, 10.0, 'the final state')[-1]

        self.assertEqual(len(msgs), STATES)
        ns = [m.header.stamp.to_nsec() for m in msgs]
        # grid_time_ns(n, h) + 1e9: integer nanoseconds, exact
        self.assertEqual(ns, [10**9 + k * STEPS_PER_STATE * 1000 for k in range(1, STATES + 1)])
        # state.t is the double nearest the decimal n * h (a correctly rounded integer division)
        self.assertEqual([m.t for m in msgs], [k * STEPS_PER_STATE * 1000 / 1e9 for k in range(1, STATES + 1)])
        seq = [m.header.seq for m in msgs]
        self.assertEqual(seq, list(range(seq[0], seq[0] + STATES)))
        self.assertEqual(len(values), STATES)
        self.assertEqual([v.data for v in values], [m.delta for m in msgs])
        # The latched final state is the last state (center_distance aside: final_state carries 0
        # there, LiveSimulation hands finished() a sample without it; not this test's subject).
        for field in ('header.stamp', 't', 'delta', 'delta_dot', 'phi', 'mesh_stiffness', 'mesh_phase', 'mu',
                      'sigma', 'realization', 'seed'):
            self.assertEqual(attr(end, field), attr(msgs[-1], field), field)


def attr(msg, dotted):
    for name in dotted.split('.'):
        msg = getattr(msg, name)
    return msg


if __name__ == '__main__':
    rospy.init_node('every_message_test')
    rostest.rosrun('gear_dynamics', 'every_message', EveryMessage, sys.argv)
