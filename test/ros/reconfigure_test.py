#!/usr/bin/python3
"""A dynparam change of mu during a run against an offline core run (mu_switch_reference, which
calls Ensemble::set_mu at the same step): equal bit for bit; and different from the run without
the change after it."""
import os
import subprocess
import sys
import tempfile
import unittest

import dynamic_reconfigure.client
import rospy
import rostest
from gear_dynamics.msg import GearState, RunInfo

from simtest import CLOCK_OFFSET, Collector, ends_at, last_run, services

T_END = 0.1    # reconfigure.yaml [s]
H = 1e-6       # run.time_step [s]
PERIOD = 1000  # steps per publish period at 1 kHz
MU0, MU1 = 0.03, 0.12


def reference(info, switch_step, mu):
    """(t, delta, delta_dot, phi, mu) rows of the offline run switching to `mu` after `switch_step`."""
    with tempfile.TemporaryDirectory() as d:
        config, out = os.path.join(d, 'config.yaml'), os.path.join(d, 'ref.csv')
        with open(config, 'w') as f:
            f.write(info.parameters_yaml)
        subprocess.run(['rosrun', 'gear_dynamics', 'mu_switch_reference', config, str(info.realization),
                        str(PERIOD), str(round(T_END / H)), str(switch_step), repr(mu), out], check=True)
        with open(out) as f:
            return [tuple(float(x) for x in line.split(',')) for line in f]


class Reconfigure(unittest.TestCase):
    def test_mu_change_during_run(self):
        client = dynamic_reconfigure.client.Client('/gear/gear_simulator', timeout=20)
        loaded = client.get_configuration(timeout=20)
        # The YAML values, not the .cfg defaults (mu 0.04).
        self.assertEqual((loaded['mu'], loaded['sigma'], loaded['real_time_factor']), (MU0, 5.0, 0.1))

        state = Collector('/gear/state', GearState)
        info = Collector('/gear/run_info', RunInfo)
        state.wait_connected()
        srv = services('/gear/gear_simulator')
        srv['reset']()
        first_info = info.wait_for(len, 10.0, 'run_info')[-1]
        srv['unpause']()
        state.wait_for(lambda m: m and m[-1].t >= 0.02, 30.0, 't >= 0.02 s')
        client.update_configuration({'mu': MU1})  # returns once applied
        msgs = last_run(state.wait_for(ends_at(T_END), 60.0, 't = t_end'))

        # state.mu shows the change from one message on; the node applied it right after
        # publishing the message before, i.e. at that step.
        mus = [m.mu for m in msgs]
        k = mus.index(MU1)
        self.assertTrue(0 < k < len(msgs) - 1, 'the change did not land inside the run')
        self.assertEqual(set(mus[:k]), {MU0})
        self.assertEqual(set(mus[k:]), {MU1})
        switch_step = round(msgs[k - 1].t / H)

        # The run_info re-published at the change holds from that instant.
        changed = info.wait_for(lambda m: m[-1].mu == MU1, 10.0, 'run_info with the new mu')[-1]
        self.assertAlmostEqual(changed.header.stamp.to_sec(), CLOCK_OFFSET + msgs[k - 1].t, places=9)
        self.assertIn('friction_coefficient: %g' % MU1, changed.parameters_yaml)

        published = [(m.t, m.delta, m.delta_dot, m.phi, m.mu) for m in msgs]
        self.assertEqual(published, reference(first_info, switch_step, MU1))
        unchanged = reference(first_info, -1, MU0)
        self.assertEqual(published[:k], unchanged[:k])
        differs = [a[0] for a, b in zip(published[k:], unchanged[k:]) if a[1:4] != b[1:4]]
        self.assertTrue(differs, 'the change of mu did not change the dynamics')
        rospy.loginfo('mu %g -> %g after step %d; delta first differs at t = %g s', MU0, MU1, switch_step, differs[0])


if __name__ == '__main__':
    rospy.init_node('reconfigure_test')
    rostest.rosrun('gear_dynamics', 'reconfigure', Reconfigure, sys.argv)
