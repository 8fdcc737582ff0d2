#!/usr/bin/python3
"""gear_monitor on two live simulators (monitor.test): the reference from streams 0-199 of the
healthy gear (8 windows each); the simulators run held-out streams 5001 (healthy) and 5000 (a 1 mm
root crack in pinion tooth 0). The healthy monitor stays OK over its 8 windows; the cracked one
reports ERROR by its third window (the CUSUM, k = 0.5 and h = 3.49, passes h after two windows at
the reference's largest score, and the debounce then needs two ERROR windows); both report STALE
once the simulators stop at t_end; a reference for another backlash is refused naming the key.
The live windows' indicators equal those of gear_monitor_reference --assess on the same streams."""
import csv
import os
import subprocess
import sys
import tempfile
import time
import unittest

import rospkg
import rospy
import rostest
from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus
from gear_dynamics.msg import GearIndicators

from simtest import Collector, links_to, services, wait_until

PKG = rospkg.RosPack().get_path('gear_dynamics')
HEALTHY_YAML = os.path.join(PKG, 'test', 'ros', 'monitor_healthy.yaml')
CRACKED_YAML = os.path.join(PKG, 'test', 'ros', 'monitor_cracked.yaml')
WINDOWS = 8
ERROR_BY = 3  # windows: CUSUM 2 + debounce 1 more


def make_reference(path, *extra):
    subprocess.run(['rosrun', 'gear_dynamics', 'gear_monitor_reference', '--output', path, '--config', HEALTHY_YAML]
                   + list(extra), check=True, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, timeout=120)


class Monitor(unittest.TestCase):
    def test_monitor(self):
        rospy.init_node('monitor_test', anonymous=True)
        folder = tempfile.mkdtemp(prefix='gd_monitor_')
        reference = os.path.join(folder, 'reference.yaml')
        other = os.path.join(folder, 'other.yaml')
        make_reference(reference, '--realizations', '200', '--windows', str(WINDOWS))
        make_reference(other, '--realizations', '20', '--false-alarm', '0.25', '--warmup', '0.02',
                       '--set', 'gear_pair.backlash=1e-4')

        diagnostics = Collector('/diagnostics', DiagnosticArray)
        indicators = {ns: Collector('/%s/indicators' % ns, GearIndicators) for ns in ('healthy', 'cracked')}
        monitors = {}
        for ns in ('healthy', 'cracked'):
            monitors[ns] = subprocess.Popen(['rosrun', 'gear_dynamics', 'gear_monitor', '__ns:=' + ns,
                                             '_reference:=' + reference, '_stale_timeout:=2.0'])
        refused = subprocess.Popen(['rosrun', 'gear_dynamics', 'gear_monitor', '__ns:=healthy',
                                    '__name:=gear_monitor_other', '_reference:=' + other],
                                   stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
        try:
            out, _ = refused.communicate(timeout=60)
            self.assertEqual(refused.returncode, 1, out)
            self.assertIn('gear_pair.backlash', out)
            self.assertIn('another gear', out)

            for c in indicators.values():
                c.wait_connected(timeout=30.0)
            # Each monitor connected to its simulator before the run starts (the simulator's own
            # links, not the master's list): the windows are then those of simulate_windows on the
            # same stream.
            for ns in ('healthy', 'cracked'):
                wait_until(lambda: links_to('/%s/gear_simulator' % ns, '/%s/gear_monitor' % ns, '/%s/state_batch' % ns),
                           30.0, '/%s/gear_simulator linked to /%s/gear_monitor on state_batch' % (ns, ns))
            for ns in ('healthy', 'cracked'):
                services('/%s/gear_simulator' % ns)['unpause']()

            got = {ns: indicators[ns].wait_for(lambda m: len(m) >= WINDOWS, 120.0, '%d windows' % WINDOWS)
                   for ns in ('healthy', 'cracked')}
            def statuses(ns):
                return [s for a in diagnostics.messages() for s in a.status
                        if s.name.lstrip('/').startswith('%s/gear_monitor:' % ns)]

            def gaps(ns):  # the monitor's count of lost states (its windows restart at each)
                return [kv.value for s in statuses(ns)[-1:] for kv in s.values if kv.key.startswith('gaps in the input')]
            for ns in ('healthy', 'cracked'):
                wait_until(lambda: gaps(ns), 10.0, ns + ' diagnostics')
                self.assertEqual(gaps(ns), ['0'], '%s: states were lost between the simulator and the monitor' % ns)
            # The live windows are simulate_windows' on the same stream: the node samples the
            # simulator's states at the reference's grid steps, at the engine's angle, and the
            # states are the engine's bit for bit (test_realization); 1e-12 leaves room for
            # the decimal text of the offline CSV only (17 digits).
            for ns, yaml_file, stream in (('healthy', HEALTHY_YAML, 5001), ('cracked', CRACKED_YAML, 5000)):
                offline = os.path.join(folder, ns + '.csv')
                subprocess.run(['rosrun', 'gear_dynamics', 'gear_monitor_reference', '--assess', reference,
                                '--config', yaml_file, '--first', str(stream), '--realizations', '1',
                                '--windows', str(WINDOWS), '--csv', offline],
                               check=True, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, timeout=120)
                with open(offline) as f:
                    rows = list(csv.DictReader(f))
                self.assertEqual(len(rows), WINDOWS)
                for row, m in zip(rows, got[ns]):
                    self.assertEqual(int(row['window']), m.window)
                    for name, value in zip(m.names, m.values):
                        self.assertAlmostEqual(float(row[name]) / value, 1.0, delta=1e-12, msg=(ns, m.window, name))
                    self.assertAlmostEqual(float(row['t2']) / m.t2, 1.0, delta=1e-12, msg=(ns, m.window))
                    self.assertAlmostEqual(float(row['cusum']), m.cusum, delta=1e-12 * max(1.0, m.cusum))

            healthy = got['healthy'][:WINDOWS]
            self.assertEqual([m.window for m in healthy], list(range(1, WINDOWS + 1)))
            self.assertEqual([m.reported_level for m in healthy], [DiagnosticStatus.OK] * WINDOWS,
                             [(m.window, m.level, m.t2, m.cusum) for m in healthy])
            cracked = got['cracked'][:WINDOWS]
            first_error = next((m.window for m in cracked if m.reported_level == DiagnosticStatus.ERROR), None)
            self.assertIsNotNone(first_error, [(m.window, m.level, m.t2, m.cusum) for m in cracked])
            self.assertLessEqual(first_error, ERROR_BY)
            self.assertTrue(all(m.reported_level == DiagnosticStatus.ERROR for m in cracked[first_error - 1:]))

            # Input stops at t_end: STALE within the 2 s timeout and the 0.5 s diagnostics period.
            for ns in ('healthy', 'cracked'):
                wait_until(lambda: statuses(ns) and statuses(ns)[-1].level == DiagnosticStatus.STALE
                           and 'no input for' in statuses(ns)[-1].message, 30.0, ns + ' STALE')
            levels = [s.level for s in statuses('healthy')]
            self.assertNotIn(DiagnosticStatus.WARN, levels)
            self.assertNotIn(DiagnosticStatus.ERROR, levels)
            self.assertIn(DiagnosticStatus.ERROR, [s.level for s in statuses('cracked')])
        finally:
            for p in list(monitors.values()) + [refused]:
                if p.poll() is None:
                    p.terminate()
                    try:
                        p.wait(timeout=10)
                    except subprocess.TimeoutExpired:
                        p.kill()


if __name__ == '__main__':
    rostest.rosrun('gear_dynamics', 'monitor', Monitor, sys.argv)
