#!/usr/bin/python3
"""~pause stops simulated time, ~step advances exactly one publish period, ~reset repeats a run
bit for bit, real_time_factor paces by wall time, and loop starts over at t_end."""
import sys
import time
import unittest

import dynamic_reconfigure.client
import rospy
import rostest
from gear_dynamics.msg import GearState
from rosgraph_msgs.msg import Clock

from simtest import CLOCK_OFFSET, Collector, ends_at, last_run, services, values

T_END = 0.02  # services.yaml [s]
H = 1e-6      # run.time_step [s]
PERIOD = 1000  # steps per publish period (1 kHz)


def t_of(k):
    """Simulated time of publish instant k as the node writes it: step index times h rounded to
    whole nanoseconds (grid_time), i.e. the double nearest the decimal k * PERIOD * H."""
    return round(float(k * PERIOD) * H, 9)


class Services(unittest.TestCase):
    """The methods run in name order and continue one session of the node."""

    @classmethod
    def setUpClass(cls):
        cls.state = Collector('/gear/state', GearState)
        cls.clock = Collector('/clock', Clock)
        cls.state.wait_connected()
        cls.clock.wait_connected()
        cls.srv = services('/gear/gear_simulator')

    def test_1_paused_clock_stands_still(self):
        self.srv['reset']()  # t = 0, published now that the test listens
        self.state.wait_for(lambda m: any(x.t == 0.0 for x in m), 10.0, 't = 0')
        self.state.clear()
        self.clock.clear()
        time.sleep(0.5)
        self.assertEqual(self.state.messages(), [])
        stamps = [c.clock.to_sec() for c in self.clock.messages()]
        self.assertGreaterEqual(len(stamps), 2)  # republished every 0.1 s while paused
        self.assertEqual(set(stamps), {CLOCK_OFFSET})

    def test_2_step_advances_one_publish_period(self):
        stepped = []
        for k in (1, 2, 3):
            self.state.clear()
            answer = self.srv['step']()
            self.assertTrue(answer.success, answer.message)
            self.assertEqual(answer.message, 't = %.9g s' % t_of(k))
            self.state.wait_for(len, 10.0, 'the stepped state')
            time.sleep(0.2)  # and nothing after it
            msgs = self.state.messages()
            self.assertEqual([m.t for m in msgs], [t_of(k)])
            stepped += msgs
        last_clock = self.clock.wait_for(
            lambda m: m and abs(m[-1].clock.to_sec() - CLOCK_OFFSET - t_of(3)) < 1e-9, 5.0, 'clock at step 3')
        self.assertAlmostEqual(last_clock[-1].clock.to_sec(), CLOCK_OFFSET + t_of(3), places=9)
        Services.stepped = stepped

    def test_3_reset_repeats_the_run_bit_for_bit(self):
        runs = []
        for _ in range(2):
            self.state.clear()
            self.srv['pause']()  # a reset keeps the node running or paused as it was
            self.srv['reset']()
            self.srv['unpause']()
            runs.append([values(m) for m in last_run(self.state.wait_for(ends_at(T_END), 30.0, 't_end'))])
        self.assertEqual([v[1] for v in runs[0]], [t_of(k) for k in range(21)])
        self.assertEqual(runs[0], runs[1])
        # Stepping gave the same numbers as running.
        self.assertEqual([values(m) for m in self.stepped], runs[0][1:4])

    def test_4_refused_at_t_end(self):
        with self.assertRaises(rospy.ServiceException):
            self.srv['unpause']()
        answer = self.srv['step']()
        self.assertFalse(answer.success)
        self.assertIn('t_end', answer.message)

    def test_5_pause_while_running_and_pacing(self):
        client = dynamic_reconfigure.client.Client('/gear/gear_simulator', timeout=20)
        client.update_configuration({'real_time_factor': 0.05})  # 20 ms simulated take 0.4 s
        self.state.clear()
        start = time.time()
        self.srv['reset']()  # runs on: the node is not paused
        msgs = last_run(self.state.wait_for(ends_at(T_END), 30.0, 't_end'))
        elapsed = time.time() - start
        self.assertEqual(len(msgs), 21)
        # Pacing can only make it slower; the first 1 ms period runs before pacing anchors.
        self.assertGreaterEqual(elapsed, (T_END - t_of(1)) / 0.05 - 0.02)

        self.srv['reset']()
        self.state.wait_for(lambda m: m and m[-1].t >= t_of(5), 30.0, 't >= 5 ms')
        self.srv['pause']()
        time.sleep(0.1)  # messages already on the way
        before = self.state.messages()
        self.clock.clear()
        time.sleep(0.5)
        self.assertEqual(self.state.messages(), before)
        self.assertEqual({round(c.clock.to_sec(), 9) for c in self.clock.messages()},
                         {round(CLOCK_OFFSET + before[-1].t, 9)})
        self.srv['unpause']()
        self.state.wait_for(ends_at(T_END), 30.0, 't_end after unpause')

    def test_6_loop_repeats(self):
        loop = Collector('/loop/gear/state', GearState)
        msgs = loop.wait_for(lambda m: sum(x.t == 0.0 for x in m) >= 3, 30.0, 'three loop starts')
        starts = [i for i, m in enumerate(msgs) if m.t == 0.0]
        first, second = msgs[starts[0]:starts[1]], msgs[starts[1]:starts[2]]
        self.assertEqual([m.t for m in first], [t_of(k) for k in range(4)])  # t_end = 3 ms
        self.assertEqual([values(m) for m in first], [values(m) for m in second])


if __name__ == '__main__':
    rospy.init_node('services_test')
    rostest.rosrun('gear_dynamics', 'services', Services, sys.argv)
