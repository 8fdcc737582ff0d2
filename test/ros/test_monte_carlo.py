#!/usr/bin/python3
"""gear_monte_carlo end to end, as a user runs it (roslaunch monte_carlo.launch):

- a batch interrupted by SIGINT and then resumed equals an uninterrupted batch, byte for byte;
- a batch realization equals gear_run's realization for the same (seed, r, mu), value for value;
- the progress topic reports the batch;
- bad parameters and a folder of another batch are refused with a message naming the key/reason.
"""
import csv
import filecmp
import glob
import os
import re
import shutil
import signal
import subprocess
import tempfile
import time
import unittest

import rosbag
import rospy
import rostest
import yaml

from gear_dynamics.msg import BatchProgress

MU = '[0.0, 0.04]'
REALIZATIONS = 40
RUNS = 2 * (1 + 64 + REALIZATIONS)  # S1, phase ensemble, realizations per mu
CONFIG = """run:
  duration: 0.1
  window: 0.02
  snapshot_times: [0.05, 0.1]
"""


class MonteCarloNode(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        rospy.init_node('test_monte_carlo', anonymous=True)
        cls.tmp = tempfile.mkdtemp(prefix='gd_monte_carlo_')
        cls.config = os.path.join(cls.tmp, 'short.yaml')
        with open(cls.config, 'w') as f:
            f.write(CONFIG)

    @classmethod
    def tearDownClass(cls):
        shutil.rmtree(cls.tmp)

    def start(self, folder, *args):
        command = ['roslaunch', 'gear_dynamics', 'monte_carlo.launch', 'output_dir:=' + folder,
                   'config:=' + self.config, 'mu:=' + MU, 'realizations:=%d' % REALIZATIONS,
                   'record_rate:=20000', 'sparse_record_rate:=1000'] + list(args)
        return subprocess.Popen(command, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)

    def run_batch(self, folder, *args):
        process = self.start(folder, *args)
        output, _ = process.communicate(timeout=120)
        return output

    def folder(self, name):
        return os.path.join(self.tmp, name)

    def manifest(self, folder):
        with open(os.path.join(folder, 'manifest.yaml')) as f:
            return yaml.safe_load(f)

    def test_1_interrupted_and_resumed_equals_uninterrupted(self):
        progress = []
        sub = rospy.Subscriber('/gear_monte_carlo/progress', BatchProgress, progress.append)
        reference = self.folder('reference')
        output = self.run_batch(reference, 'threads:=2')
        sub.unregister()
        self.assertIn('%d of %d bags written' % (RUNS, RUNS), output)
        self.assertTrue(self.manifest(reference)['complete'])
        self.assertEqual(len(glob.glob(os.path.join(reference, '*.bag'))), RUNS)
        self.assertTrue(progress, 'no message on /gear_monte_carlo/progress')
        self.assertEqual(progress[-1].runs_total, RUNS)
        self.assertLessEqual(progress[-1].runs_done, RUNS)

        # One thread, one lane per block: slow enough to be caught in the middle.
        interrupted = self.folder('interrupted')
        process = self.start(interrupted, 'threads:=1', 'block_lanes:=1')
        deadline = time.time() + 60
        while len(glob.glob(os.path.join(interrupted, '*.bag'))) < 3 and process.poll() is None:
            self.assertLess(time.time(), deadline, 'no bag written within 60 s')
            time.sleep(0.02)
        signaled = time.time()
        process.send_signal(signal.SIGINT)
        output, _ = process.communicate(timeout=30)
        self.assertLess(time.time() - signaled, 10.0, 'the batch took too long to stop:\n' + output)
        self.assertIn('SIGINT: abandoning the runs in flight', output,
                      'the batch ended before the signal (make it longer):\n' + output)
        manifest = self.manifest(interrupted)
        self.assertFalse(manifest['complete'])
        self.assertEqual(len(manifest['runs']), RUNS)
        kept = len(glob.glob(os.path.join(interrupted, '*.bag')))
        self.assertGreater(kept, 0)
        self.assertLess(kept, RUNS)

        output = self.run_batch(interrupted, 'threads:=2')
        self.assertIn('%d runs, %d complete, %d to do' % (RUNS, kept, RUNS - kept), output)
        self.assertTrue(self.manifest(interrupted)['complete'])
        self.assertEqual(glob.glob(os.path.join(interrupted, '*.active')), [])
        names = sorted(os.path.basename(p) for p in glob.glob(os.path.join(reference, '*.bag')))
        self.assertEqual(names, sorted(os.path.basename(p) for p in glob.glob(os.path.join(interrupted, '*.bag'))))
        for name in names:  # whatever the threads, lanes and interruptions: the same bytes
            self.assertTrue(filecmp.cmp(os.path.join(reference, name), os.path.join(interrupted, name), shallow=False),
                            name)

    def test_2_realization_equals_gear_run(self):
        reference = self.folder('reference')
        if not os.path.exists(os.path.join(reference, 'manifest.yaml')):
            self.run_batch(reference)
        table = os.path.join(self.tmp, 'gear_run.csv')
        subprocess.run(['rosrun', 'gear_dynamics', 'gear_run', '--config', self.config, '--mu', '0.04',
                        '--no-deterministic', '--realizations', '2', '--rate', '20000', '--output', table],
                       check=True, stdout=subprocess.DEVNULL)
        with open(table) as f:
            rows = [r for r in csv.DictReader(f) if r['run'] == 'r1']
        with rosbag.Bag(os.path.join(reference, 'mu0.0400_r00001.bag')) as bag:  # S3
            states = [m for _, m, _ in bag.read_messages(topics=['/gear/state'])]
            summary = next(m for _, m, _ in bag.read_messages(topics=['/gear/summary']))
        self.assertEqual(len(states), len(rows))
        self.assertEqual(len(rows), 2001)
        for s, r in zip(states, rows):
            self.assertEqual((s.t, s.delta, s.delta_dot, s.phi, s.center_distance),
                             (float(r['t']), float(r['delta']), float(r['delta_dot']), float(r['phi']),
                              float(r['center_distance'])))
        self.assertEqual(summary.final_delta, float(rows[-1]['delta']))
        self.assertEqual(summary.center_distance, float(rows[-1]['center_distance']))

    def test_3_refusals_name_the_problem(self):
        reference = self.folder('reference')
        if not os.path.exists(os.path.join(reference, 'manifest.yaml')):
            self.run_batch(reference)
        before = sorted(os.listdir(reference))
        output = self.run_batch(reference, 'seed:=7')
        self.assertIn("is refused: it holds a batch with a different configuration", output)
        self.assertEqual(sorted(os.listdir(reference)), before)

        output = self.run_batch(self.folder('bad'), 'realizations:=0', 'record_rate:=30000')
        self.assertIn('monte_carlo.realizations = 0 is out of range; allowed [1, 1000000] (integer)', output)
        self.assertIn('monte_carlo.record_rate = 30000 Hz does not fit the grid', output)
        self.assertFalse(os.path.exists(os.path.join(self.folder('bad'), 'manifest.yaml')))

    def test_4_gear_run_refuses_negative_options(self):
        # --mu and --seed go through the same validation as the files: a value < 0 is refused, not ignored.
        for option, value, message in (('--mu', '-0.1', 'gear_pair.friction_coefficient = -0.1 is out of range'),
                                       ('--seed', '-4', 'run.seed = -4 is out of range')):
            res = subprocess.run(['rosrun', 'gear_dynamics', 'gear_run', option, value, '--rate', '0'],
                                 stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
            self.assertEqual(res.returncode, 1, res.stdout)
            self.assertIn(message, res.stdout)


if __name__ == '__main__':
    rostest.rosrun('gear_dynamics', 'test_monte_carlo', MonteCarloNode)
