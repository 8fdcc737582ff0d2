#!/usr/bin/python3
"""gear_analyze on a live bag: simulate.launch record:=true of the deterministic run S1 (1 s at
full speed, states at 1 kHz), then `gear_analyze spectrum --bag` of that bag against `gear_analyze
spectrum` of the same run simulated (the live node steps S1 bit for bit as the engine does, so the
PSDs must agree to rounding); poincare and safety read it too; a bag that lost a state, and one
still being written, are refused with the reason; the condition monitor of a recorded stochastic
run (delta, and a bearing force of the bearings model) against the same stream simulated."""
import csv
import glob
import os
import shutil
import signal
import subprocess
import sys
import tempfile
import unittest

import rosbag
import rospkg
import rospy
import rostest
from gear_dynamics.msg import GearState

from simtest import Collector, ends_at, services, wait_until

PKG = rospkg.RosPack().get_path('gear_dynamics')

T_END = 1.0


def read_psd(prefix):
    with open(prefix + '_psd.csv') as f:
        return [(float(r['frequency']), float(r['delta_S1']), float(r['force_S1'])) for r in csv.DictReader(f)]


def analyze(*args):
    return subprocess.run(['rosrun', 'gear_dynamics', 'gear_analyze'] + list(args), capture_output=True, text=True,
                          timeout=120)


class AnalyzeBag(unittest.TestCase):
    def setUp(self):
        self.folder = tempfile.mkdtemp(prefix='gear_analyze_bag_')
        self.addCleanup(shutil.rmtree, self.folder)

    def record(self, t_end=T_END, run=('deterministic:=true', 't_end:=%r' % T_END)):
        launch = subprocess.Popen(
            ['roslaunch', 'gear_dynamics', 'simulate.launch', 'record:=true', 'record_dir:=' + self.folder,
             'paused:=true', 'real_time_factor:=0', 'output:=log'] + list(run),
            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, start_new_session=True)
        try:
            state = Collector('/gear/state', GearState)
            state.wait_connected(30.0)
            services('/gear/gear_simulator')['unpause']()
            state.wait_for(ends_at(t_end), 60.0, 't_end')
            wait_until(lambda: glob.glob(os.path.join(self.folder, 'gear_*.bag')), 30.0, 'the closed bag')
        finally:
            os.killpg(launch.pid, signal.SIGINT)
            launch.wait(timeout=30)
        return glob.glob(os.path.join(self.folder, 'gear_*.bag'))[0]

    def test_bag_against_the_simulated_run(self):
        bag = self.record()
        a, b = os.path.join(self.folder, 'bag'), os.path.join(self.folder, 'sim')
        got = analyze('spectrum', '--bag', bag, '--transient', '0.2', '--output', a)
        self.assertEqual(got.returncode, 0, got.stderr)
        self.assertIn('states from /gear/state', got.stdout)
        # The same run simulated, sampled at the recording's 1 ms (400 steps of 2.5 us).
        sim = analyze('spectrum', '--set', 'run.duration=%r' % T_END, '--transient', '0.2', '--decimate', '400',
                      '--output', b)
        self.assertEqual(sim.returncode, 0, sim.stderr)
        from_bag, simulated = read_psd(a), read_psd(b)
        self.assertEqual(len(from_bag), len(simulated))
        self.assertGreater(len(from_bag), 40)
        for (f1, d1, p1), (f2, d2, p2) in zip(from_bag, simulated):
            self.assertAlmostEqual(f1, f2, delta=1e-9 * max(f2, 1.0))
            # The CSV prints 17 digits: the series are equal, so the PSDs agree to rounding.
            self.assertAlmostEqual(d1, d2, delta=1e-12 * max(abs(d2), 1e-300))
            self.assertAlmostEqual(p1, p2, delta=1e-12 * max(abs(p2), 1e-300))

        poincare = analyze('poincare', '--bag', bag, '--output', a)
        self.assertEqual(poincare.returncode, 0, poincare.stderr)
        with open(a + '_poincare.csv') as f:
            rows = list(csv.DictReader(f))
        # Mesh phase 0 every 3 ms from 0.2 s to 1 s, each on a recorded state (3 recording periods).
        self.assertEqual(len(rows), 267)
        self.assertTrue(all(r['on_grid'] == '1' for r in rows))
        safety = analyze('safety', '--bag', bag, '--output', a)
        self.assertEqual(safety.returncode, 0, safety.stderr)
        self.assertIn('recorded states inside', safety.stdout)

        # A bag that lost a state is refused, naming the gap.
        lossy = os.path.join(self.folder, 'lossy.bag')
        with rosbag.Bag(bag) as src, rosbag.Bag(lossy, 'w') as dst:
            dropped = False
            for topic, msg, t in src.read_messages():
                if topic == '/gear/state' and abs(msg.t - 0.5) < 1e-9 and not dropped:
                    dropped = True
                    continue
                dst.write(topic, msg, t)
        self.assertTrue(dropped)
        refused = analyze('spectrum', '--bag', lossy, '--output', a)
        self.assertEqual(refused.returncode, 1)
        self.assertIn('uneven times', refused.stderr)
        self.assertEqual(refused.stderr.count('\n'), 1, refused.stderr)  # one line
        active = analyze('spectrum', '--bag', bag + '.active', '--output', a)
        self.assertEqual(active.returncode, 1)
        self.assertIn('rosbag reindex', active.stderr)

    def monitor_matches_simulation(self, model_args, launch_args):
        """gear_analyze monitor on a recorded stochastic run gives the windows that
        gear_monitor_reference --assess computes by simulating the same stream (the node's states
        are the engine's bit for bit; 1e-12 leaves room for the CSVs' 17 digits). Returns the
        reference, the bag and the output prefix."""
        healthy = os.path.join(PKG, 'test', 'ros', 'monitor_healthy.yaml')  # 0.7 s at 40 kHz, 2000 m/s^2
        reference = os.path.join(self.folder, 'reference.yaml')
        subprocess.run(['rosrun', 'gear_dynamics', 'gear_monitor_reference', '--output', reference, '--config',
                        healthy, '--realizations', '20', '--windows', '4', '--false-alarm', '0.25'] + model_args,
                       check=True, capture_output=True, timeout=120)
        bag = self.record(0.7, ('config:=' + healthy, 'realization:=5001') + launch_args)
        prefix = os.path.join(self.folder, 'bag')
        got = analyze('monitor', '--reference', reference, '--bag', bag, '--output', prefix)
        self.assertEqual(got.returncode, 0, got.stderr)
        offline = os.path.join(self.folder, 'offline.csv')
        subprocess.run(['rosrun', 'gear_dynamics', 'gear_monitor_reference', '--assess', reference, '--config',
                        healthy, '--first', '5001', '--realizations', '1', '--windows', '8', '--csv', offline]
                       + model_args[:2], check=True, capture_output=True, timeout=120)
        with open(prefix + '_monitor.csv') as f:
            from_bag = list(csv.DictReader(f))
        with open(offline) as f:
            simulated = list(csv.DictReader(f))
        self.assertEqual(len(simulated), 8)
        self.assertGreaterEqual(len(from_bag), 8, got.stdout)  # the run may hold a ninth whole window
        names = [n for n in simulated[0] if n not in ('realization', 'window', 'load', 'band', 'level')]
        for b, s in zip(from_bag, simulated):
            self.assertEqual(b['window'], s['window'])
            self.assertEqual(b['level'], s['level'])
            for name in names:
                self.assertAlmostEqual(float(b[name]), float(s[name]),
                                       delta=1e-12 * max(abs(float(s[name])), 1e-300), msg=(b['window'], name))
        return reference, bag, prefix

    def test_monitor_of_a_bearing_force_in_a_bag(self):
        """The same on the pinion's bearing force along the line of action: the bag's
        pinion_bearing/wrench paired with its states by stamp. A torsional run's bag is refused
        by the reference's model."""
        reference, bag, prefix = self.monitor_matches_simulation(
            ['--set', 'gear_pair.model=bearings', '--signal', 'pinion_fy'], ('model:=bearings',))
        os.remove(bag)
        healthy = os.path.join(PKG, 'test', 'ros', 'monitor_healthy.yaml')
        torsional = self.record(0.2, ('config:=' + healthy, 't_end:=0.2'))
        refused = analyze('monitor', '--reference', reference, '--bag', torsional, '--output', prefix)
        self.assertEqual(refused.returncode, 1)
        self.assertIn('gear_pair.model', refused.stderr)

    def test_monitor_of_a_bag(self):
        reference, bag, prefix = self.monitor_matches_simulation([], ())
        healthy = os.path.join(PKG, 'test', 'ros', 'monitor_healthy.yaml')
        # A bag sampled otherwise than the reference is refused, naming the rate it needs.
        os.remove(bag)
        slow_bag = self.record(0.2, ('config:=' + healthy, 'publish_rate:=1000', 't_end:=0.2'))
        slow = analyze('monitor', '--reference', reference, '--bag', slow_bag, '--output', prefix)
        self.assertEqual(slow.returncode, 1)
        self.assertIn('publish_rate:=40000', slow.stderr)


if __name__ == '__main__':
    rospy.init_node('analyze_bag_test')
    rostest.rosrun('gear_dynamics', 'analyze_bag', AnalyzeBag, sys.argv)
