#!/usr/bin/python3
"""gear_monitor on the pinion's bearing force along the line of action (monitor_bearings.test): a
reference from streams 0-199 of the healthy gear on its bearings (8 windows each), the simulator on
held-out stream 5001. The monitor pairs /bearings/state_batch with /bearings/pinion_bearing/wrench
by stamp; every live window's indicators equal those of gear_monitor_reference --assess on the same
stream, no state is lost, the healthy gear stays OK and goes STALE at t_end."""
import csv
import os
import subprocess
import sys
import tempfile
import unittest

import rospkg
import rospy
import rostest
from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus
from gear_dynamics.msg import GearIndicators

from simtest import Collector, links_to, services, wait_until

PKG = rospkg.RosPack().get_path('gear_dynamics')
HEALTHY_YAML = os.path.join(PKG, 'test', 'ros', 'monitor_healthy.yaml')
WINDOWS = 8
MODEL = ['--set', 'gear_pair.model=bearings', '--signal', 'pinion_fy']


class MonitorBearings(unittest.TestCase):
    def test_monitor_on_a_bearing_force(self):
        rospy.init_node('monitor_bearings_test', anonymous=True)
        folder = tempfile.mkdtemp(prefix='gd_monitor_bearings_')
        reference = os.path.join(folder, 'reference.yaml')
        subprocess.run(['rosrun', 'gear_dynamics', 'gear_monitor_reference', '--output', reference, '--config',
                        HEALTHY_YAML, '--realizations', '200', '--windows', str(WINDOWS)] + MODEL,
                       check=True, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, timeout=120)
        diagnostics = Collector('/diagnostics', DiagnosticArray)
        indicators = Collector('/bearings/indicators', GearIndicators)
        monitor = subprocess.Popen(['rosrun', 'gear_dynamics', 'gear_monitor', '__ns:=bearings',
                                    '_reference:=' + reference, '_stale_timeout:=2.0'])
        try:
            indicators.wait_connected(timeout=30.0)
            for topic in ('state_batch', 'pinion_bearing/wrench'):
                wait_until(lambda: links_to('/bearings/gear_simulator', '/bearings/gear_monitor', '/bearings/' + topic),
                           30.0, '/bearings/gear_simulator linked to the monitor on ' + topic)
            services('/bearings/gear_simulator')['unpause']()
            got = indicators.wait_for(lambda m: len(m) >= WINDOWS, 120.0, '%d windows' % WINDOWS)[:WINDOWS]

            def statuses():
                return [s for a in diagnostics.messages() for s in a.status
                        if s.name.lstrip('/').startswith('bearings/gear_monitor:')]

            def value(key):
                return [kv.value for s in statuses()[-1:] for kv in s.values if kv.key.startswith(key)]
            wait_until(lambda: value('gaps in the input'), 10.0, 'the diagnostics')
            self.assertEqual(value('gaps in the input'), ['0'], 'states or wrenches lost between simulator and monitor')

            offline = os.path.join(folder, 'offline.csv')
            subprocess.run(['rosrun', 'gear_dynamics', 'gear_monitor_reference', '--assess', reference, '--config',
                            HEALTHY_YAML, '--first', '5001', '--realizations', '1', '--windows', str(WINDOWS),
                            '--csv', offline] + MODEL[:2],
                           check=True, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, timeout=120)
            with open(offline) as f:
                rows = list(csv.DictReader(f))
            self.assertEqual(len(rows), WINDOWS)
            # The simulator's outputs are the engine's bit for bit; 1e-12 leaves room for the CSV's
            # 17 decimal digits only.
            for row, m in zip(rows, got):
                self.assertEqual(int(row['window']), m.window)
                for name, v in zip(m.names, m.values):
                    self.assertAlmostEqual(float(row[name]) / v, 1.0, delta=1e-12, msg=(m.window, name))
                self.assertAlmostEqual(float(row['t2']) / m.t2, 1.0, delta=1e-12, msg=m.window)
            self.assertEqual([m.reported_level for m in got], [DiagnosticStatus.OK] * WINDOWS,
                             [(m.window, m.level, m.t2, m.cusum) for m in got])

            wait_until(lambda: statuses() and statuses()[-1].level == DiagnosticStatus.STALE, 30.0, 'STALE')
            self.assertIn('pinion_fy', statuses()[-1].hardware_id)
        finally:
            if monitor.poll() is None:
                monitor.terminate()
                monitor.wait(timeout=10)


if __name__ == '__main__':
    rostest.rosrun('gear_dynamics', 'monitor_bearings', MonitorBearings, sys.argv)
