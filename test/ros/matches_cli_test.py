#!/usr/bin/python3
"""gear_simulator publishes, at every published instant, exactly the numbers that the core CLI
gear_run writes for the same configuration (both run the same core; the CSV has 17 significant
digits, so its doubles round-trip and the comparison is equality)."""
import os
import subprocess
import sys
import tempfile
import unittest

import rospy
import rostest
from gear_dynamics.msg import GearState, RunInfo

from simtest import Collector, ends_at, last_run, read_csv, services

T_END = 0.05  # simulator/t_end of cli_match.yaml and cli_match_s1.yaml [s]
COLUMNS = ('t', 'delta', 'delta_dot', 'phi', 'center_distance')


def run_node(ns):
    """Runs the paused node in `ns` from t = 0 to t_end; returns its states and last run_info."""
    state = Collector(ns + '/state', GearState)
    info = Collector(ns + '/run_info', RunInfo)
    state.wait_connected()
    srv = services(ns + '/gear_simulator')
    srv['reset']()  # publishes t = 0 again, now that this test listens
    srv['unpause']()
    msgs = last_run(state.wait_for(ends_at(T_END), 30.0, 't = t_end'))
    return msgs, info.wait_for(len, 10.0, 'run_info')[-1]


def gear_run(info, rate, runs):
    """gear_run's CSV rows for the configuration that run_info reports."""
    with tempfile.TemporaryDirectory() as d:
        config = os.path.join(d, 'config.yaml')
        with open(config, 'w') as f:
            f.write(info.parameters_yaml)
        out = os.path.join(d, 'run.csv')
        subprocess.run(['rosrun', 'gear_dynamics', 'gear_run', '--config', config,
                        '--set', 'run.duration=%r' % T_END, '--set', 'run.snapshot_times=[]',
                        '--rate', repr(rate), '--output', out] + runs, check=True)
        return read_csv(out)


class MatchesCli(unittest.TestCase):
    def assert_same_series(self, msgs, rows):
        self.assertEqual(len(msgs), len(rows))
        for m, row in zip(msgs, rows):
            self.assertEqual(tuple(getattr(m, c) for c in COLUMNS), tuple(float(row[c]) for c in COLUMNS),
                             'at t = %r' % m.t)

    def test_stochastic_realization(self):
        msgs, info = run_node('/gear')
        self.assertEqual((info.kind, info.seed, info.realization, info.duration), ('stochastic', 12345, 3, T_END))
        # The YAML's mu (0.03), not the .cfg default (0.04): the first reconfigure callback kept it.
        self.assertEqual({(m.mu, m.realization, m.seed) for m in msgs}, {(0.03, 3, 12345)})
        self.assertEqual(len(msgs), 51)  # 1 kHz over 0.05 s, both ends included
        rows = gear_run(info, 1000.0, ['--no-deterministic', '--realizations', '4'])
        self.assert_same_series(msgs, [r for r in rows if r['run'] == 'r3'])
        self.assertGreater(len({m.phi for m in msgs}), 1)  # the load moves

    def test_deterministic_load(self):
        msgs, info = run_node('/s1/gear')
        self.assertEqual((info.kind, info.sigma), ('S1', 0.0))
        self.assertEqual(len(msgs), 101)  # 2 kHz
        rows = gear_run(info, 2000.0, ['--realizations', '0'])
        self.assert_same_series(msgs, [r for r in rows if r['run'] == 'S1'])
        self.assertEqual({m.phi for m in msgs}, {20.0})  # sigma = 0: Phi stays at load.initial_mean


if __name__ == '__main__':
    rospy.init_node('matches_cli_test')
    rostest.rosrun('gear_dynamics', 'matches_cli', MatchesCli, sys.argv)
