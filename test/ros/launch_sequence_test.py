#!/usr/bin/python3
"""Launch files one after the other on one master, as a user with a roscore kept up runs them:
each launch does what its own arguments say, whatever the launch before it set.

- simulate.launch record:=true, then without record: the second writes no bag and leaves no
  ~record_prefix; with the first launch's folder deleted, the plain launch still runs (no FATAL).
- monte_carlo.launch study:=noise, then a plain batch: the plain one runs its own 1 point, not the
  study's 6; end_launch ends every launch quietly (no "process has died"), however many earlier
  roslaunch entries the master keeps in /roslaunch/uris.
- aggregator.launch, then plot:=false: figures only in the first report folder; the nodes' log
  lines keep their UTF-8 ("Poincaré", not "Poincar??").
- end_launch ends at once on Ctrl-C whenever it comes, also during its start-up (rospy's own
  handler, run while init_node holds rospy's locks, deadlocked there and roslaunch waited 15 s).
"""
import glob
import os
import shutil
import signal
import subprocess
import sys
import tempfile
import time
import unittest

import rosgraph
import rospy
import rostest
import yaml

from gear_dynamics.msg import GearState

PKG = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
SMALL_RUN = """run:
  duration: 0.05
  window: 0.01
  snapshot_times: [0.03, 0.04, 0.05]
monte_carlo:
  phase_ensemble: false
  record_rate: 1000.0
  sparse_record_rate: 100.0
"""
NOISE_POINTS = 6  # config/studies/noise.yaml: 6 sigma values at one mu


class Launch:
    """roslaunch in a session of its own, its output in a file."""

    def __init__(self, *args):
        self.log = tempfile.TemporaryFile('w+')
        self.process = subprocess.Popen(['roslaunch', 'gear_dynamics'] + list(args), stdout=self.log,
                                        stderr=subprocess.STDOUT, start_new_session=True)

    def output(self):
        self.log.seek(0)
        return self.log.read()

    def interrupt(self):
        """Ctrl-C; returns roslaunch's exit code."""
        if self.process.poll() is None:
            os.killpg(self.process.pid, signal.SIGINT)
        return self.process.wait(timeout=40)

    def wait(self, timeout):
        try:
            return self.process.wait(timeout=timeout)
        except subprocess.TimeoutExpired:
            self.interrupt()
            raise AssertionError('roslaunch did not end by itself:\n' + self.output()[-4000:])


class LaunchSequence(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.tmp = tempfile.mkdtemp(prefix='gd_launch_sequence_')
        cls.small = os.path.join(cls.tmp, 'small.yaml')
        with open(cls.small, 'w') as f:
            f.write(SMALL_RUN)

    @classmethod
    def tearDownClass(cls):
        shutil.rmtree(cls.tmp)

    def simulate(self, *args):
        """simulate.launch to t_end 0.05 s as fast as possible; returns (output, the node's private
        parameter names while it ran)."""
        launch = Launch('simulate.launch', 't_end:=0.05', 'real_time_factor:=0', *args)
        try:
            try:  # latched at t_end (the node's output reaches the file only when it exits)
                rospy.wait_for_message('/gear/final_state', GearState, timeout=60.0)
            except rospy.ROSException:
                launch.interrupt()
                raise AssertionError('no final_state:\n' + launch.output()[-4000:])
            names = rosgraph.Master('/launch_sequence_test').getParamNames()
            private = sorted(n for n in names if n.startswith('/gear/gear_simulator/'))
        finally:
            launch.interrupt()
        return launch.output(), private

    def test_record_then_not(self):
        folder = os.path.join(self.tmp, 'bags')
        os.mkdir(folder)
        output, private = self.simulate('record:=true', 'record_dir:=' + folder)
        self.assertIn('/gear/gear_simulator/record_prefix', private)
        self.assertEqual(len(glob.glob(os.path.join(folder, 'gear_*.bag'))), 1, output[-3000:])

        output, private = self.simulate()
        self.assertNotIn('/gear/gear_simulator/record_prefix', private)
        self.assertNotIn('record: writing', output)
        self.assertEqual(len(os.listdir(folder)), 1, os.listdir(folder))

        shutil.rmtree(folder)  # the first launch's folder gone: the plain launch does not care
        output, _ = self.simulate()
        self.assertNotIn('FATAL', output)
        self.assertNotIn('record: writing', output)

    def batch(self, folder, *args):
        launch = Launch('monte_carlo.launch', 'output_dir:=' + folder, 'config:=' + self.small, *args)
        code = launch.wait(180.0)
        output = launch.output()
        self.assertEqual(code, 0, output[-4000:])
        self.assertNotIn('has died', output)
        with open(os.path.join(folder, 'manifest.yaml')) as f:
            return yaml.safe_load(f), output

    def test_study_then_not(self):
        study = os.path.join(self.tmp, 'study')
        manifest, _ = self.batch(study, 'study:=noise', 'realizations:=2')
        bags = glob.glob(os.path.join(study, '*.bag'))
        self.assertEqual(len(bags), NOISE_POINTS * (1 + 2), sorted(bags))

        plain = os.path.join(self.tmp, 'plain')
        manifest, output = self.batch(plain, 'mu:=[0.04]', 'realizations:=4')
        bags = sorted(os.path.basename(b) for b in glob.glob(os.path.join(plain, '*.bag')))
        self.assertEqual(len(bags), 1 + 4, bags)
        self.assertNotIn('sweep', yaml.safe_dump(manifest), 'the study leaked into the plain batch')
        self.assertIn('5 runs', output)

        # The master now lists three dead roslaunch servers (and rostest's own): a third launch
        # still ends quietly through end_launch.
        dead = len(rospy.get_param('/roslaunch/uris'))
        self.assertGreaterEqual(dead, 3)
        again = os.path.join(self.tmp, 'again')
        self.batch(again, 'mu:=[0.0]', 'realizations:=2')
        self.assertEqual(len(glob.glob(os.path.join(again, '*.bag'))), 3)

    def test_plot_then_not(self):
        folder = os.path.join(self.tmp, 'for_reports')
        self.batch(folder, 'mu:=[0.0, 0.04]', 'realizations:=8')
        analysis = os.path.join(PKG, 'test', 'ros', 'small_analysis.yaml')
        figures = []
        for name, extra in (('with', []), ('without', ['plot:=false'])):
            report = os.path.join(self.tmp, 'report_' + name)
            launch = Launch('aggregator.launch', 'folders:=' + folder, 'config:=' + analysis,
                            'report_folder:=' + report, 'exit_when_done:=true', *extra)
            code = launch.wait(180.0)
            self.assertEqual(code, 0, launch.output()[-4000:])
            self.assertNotIn('has died', launch.output())
            # UTF-8 intact in the log (no phase runs here: the node warns about the section)
            self.assertIn('Poincaré section', launch.output())
            self.assertTrue(os.path.exists(os.path.join(report, 'report.md')), launch.output()[-4000:])
            figures.append(glob.glob(os.path.join(report, '*.png')))
        self.assertGreater(len(figures[0]), 0)
        self.assertEqual(figures[1], [])

    def test_end_launch_ends_at_once_on_a_signal(self):
        program = os.path.join(PKG, 'nodes', 'end_launch.py')
        for delay in (0.0, 0.1, 0.2, 0.3, 0.4, 0.5, 0.7, 1.0, 2.0):  # start-up takes about 0.4 s
            process = subprocess.Popen([program, '__name:=end_launch_signal_test'], stdout=subprocess.DEVNULL,
                                       stderr=subprocess.DEVNULL)
            try:
                time.sleep(delay)
                if delay >= 2.0:  # up and idle: the signals keep their default action, no handler
                    with open('/proc/%d/status' % process.pid) as f:
                        caught = int(next(l for l in f if l.startswith('SigCgt:')).split()[1], 16)
                    self.assertFalse(caught & (1 << (signal.SIGINT - 1) | 1 << (signal.SIGTERM - 1)),
                                     'end_launch handles SIGINT or SIGTERM itself (SigCgt %x)' % caught)
                process.send_signal(signal.SIGINT)
                try:
                    process.wait(timeout=3.0)
                except subprocess.TimeoutExpired:
                    self.fail('end_launch did not end within 3 s of a SIGINT sent %.1f s after its start' % delay)
            finally:
                if process.poll() is None:
                    process.kill()
                    process.wait()


if __name__ == '__main__':
    rospy.init_node('launch_sequence_test')
    rostest.rosrun('gear_dynamics', 'launch_sequence', LaunchSequence, sys.argv)
