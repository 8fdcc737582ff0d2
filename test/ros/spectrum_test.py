#!/usr/bin/python3
"""The latched topic `spectrum` of gear_simulator (doc/gear_simulator.md §3) against computations
that do not go through the node: scipy.signal.welch on gear_run's series of the same run (delta), and
gear_analyze spectrum, which samples the run through the batch's Ensemble and its own mesh-force
call (delta and the mesh force). Then the physics of this case (spectrum.yaml: S1 in permanent
contact): the largest density of delta at the mesh frequency, a line of the force there, Parseval."""
import os
import subprocess
import sys
import tempfile
import unittest

import numpy as np
import rospy
import rostest
import scipy.signal
from gear_dynamics.msg import RunInfo, Spectrum

from simtest import CLOCK_OFFSET, Collector, read_csv, services

T_END = 0.5          # spectrum.yaml's t_end: the one update instant that ends the run [s]
SAMPLE_STEPS = 20    # 50 kHz at h = 1 us
H = 1e-6
# FFT round-off: kissfft (the node) and pocketfft (scipy) differ by about eps times the largest
# |X|^2, so bins far below the peak are compared against 1e-10 of the largest density, and the
# rest to 1e-8 relative (measured: a few 1e-13).
RTOL, ATOL_OF_MAX = 1e-8, 1e-10


class SpectrumTopic(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        spectra = Collector('/gear/spectrum', Spectrum)
        info = Collector('/gear/run_info', RunInfo)
        spectra.wait_connected()
        srv = services('/gear/gear_simulator')
        srv['unpause']()
        cls.msg = spectra.wait_for(lambda m: any(abs(s.t - T_END) < 1e-9 for s in m), 60.0, 't = t_end')[-1]
        cls.info = info.wait_for(len, 10.0, 'run_info')[-1]
        cls.tmp = tempfile.TemporaryDirectory()
        cls.config = os.path.join(cls.tmp.name, 'config.yaml')
        with open(cls.config, 'w') as f:
            f.write(cls.info.parameters_yaml)

    @classmethod
    def tearDownClass(cls):
        cls.tmp.cleanup()

    def assert_close(self, got, want, what):
        got, want = np.asarray(got), np.asarray(want)
        self.assertEqual(got.shape, want.shape, what)
        np.testing.assert_allclose(got, want, rtol=RTOL, atol=ATOL_OF_MAX * np.max(want), err_msg=what)

    def window_of(self, rows):
        """The rows of a series at the message's sample instants (t in [window_start, t])."""
        m = self.msg
        first, last = round(m.window_start / H), round(m.t / H)
        picked = [r for r in rows if first <= round(float(r['t']) / H) <= last
                  and (round(float(r['t']) / H) - first) % SAMPLE_STEPS == 0]
        self.assertEqual(len(picked), m.samples)
        return picked

    def test_1_description(self):
        m = self.msg
        self.assertEqual((m.samples, m.sample_steps, m.segment, m.segments, m.window), (18000, 20, 4500, 7, 'hann'))
        self.assertAlmostEqual(m.sample_rate, 50000.0, delta=1e-6)
        self.assertAlmostEqual(m.window_start, T_END - 17999 * SAMPLE_STEPS * H, delta=1e-12)
        self.assertEqual(m.header.stamp.to_sec() - CLOCK_OFFSET, m.t)
        self.assertAlmostEqual(m.resolution, m.sample_rate / m.segment, delta=1e-9)
        self.assertAlmostEqual(m.enbw, 1.5 * m.resolution, delta=1e-9)
        self.assertAlmostEqual(m.mesh_frequency, 1000.0 / 60.0 * 20.0, delta=1e-9)  # 1000 rpm, Z1 = 20
        self.assertEqual(len(m.frequency), m.segment // 2 + 1)
        self.assertEqual(len(m.delta_psd), len(m.frequency))
        self.assertEqual(len(m.mesh_force_psd), len(m.frequency))
        np.testing.assert_allclose(m.frequency, np.arange(len(m.frequency)) * m.resolution, rtol=1e-12)

    def test_2_delta_equals_scipy_welch_of_gear_run(self):
        """gear_run writes every 20th grid state of S1 (17 digits: exact doubles); scipy's Welch of
        the window's samples is the node's delta PSD."""
        m = self.msg
        out = os.path.join(self.tmp.name, 'run.csv')
        subprocess.run(['rosrun', 'gear_dynamics', 'gear_run', '--config', self.config,
                        '--set', 'run.duration=%r' % T_END, '--set', 'run.snapshot_times=[]',
                        '--realizations', '0', '--rate', '50000', '--output', out], check=True)
        rows = self.window_of([r for r in read_csv(out) if r['run'] == 'S1'])
        x = np.array([float(r['delta']) for r in rows])
        f, p = scipy.signal.welch(x, fs=m.sample_rate, window='hann', nperseg=m.segment,
                                  noverlap=m.segment // 2, detrend='constant', scaling='density')
        np.testing.assert_allclose(m.frequency, f, rtol=1e-12)
        self.assert_close(m.delta_psd, p, 'delta PSD against scipy.signal.welch')
        # Parseval: sum P df is the mean over segments of the windowed variance sum (w (x - mean))^2 / sum w^2.
        w = scipy.signal.get_window('hann', m.segment)
        hop = m.segment // 2
        var = np.mean([np.sum((w * (s - s.mean())) ** 2) / np.sum(w ** 2)
                       for s in (x[i:i + m.segment] for i in range(0, len(x) - m.segment + 1, hop))])
        self.assertAlmostEqual(np.sum(m.delta_psd) * m.resolution / var, 1.0, delta=1e-9)

    def test_3_equals_gear_analyze(self):
        """gear_analyze spectrum samples the same run through an Ensemble from the window's start:
        the same Welch code on the same samples gives the same densities to the last digit."""
        m = self.msg
        prefix = os.path.join(self.tmp.name, 'analyze')
        subprocess.run(['rosrun', 'gear_dynamics', 'gear_analyze', 'spectrum', '--config', self.config,
                        '--duration', repr(T_END), '--transient', repr(m.window_start),
                        '--decimate', str(SAMPLE_STEPS), '--segment', str(m.segment),
                        '--overlap', repr(m.overlap), '--output', prefix],
                       check=True, stdout=subprocess.DEVNULL)
        rows = read_csv(prefix + '_psd.csv')
        self.assertEqual([float(r['frequency']) for r in rows], list(m.frequency))
        self.assertEqual([float(r['delta_S1']) for r in rows], list(m.delta_psd))
        self.assertEqual([float(r['force_S1']) for r in rows], list(m.mesh_force_psd))

    def test_4_line_at_the_mesh_frequency(self):
        """In permanent contact the stiffness switching at f_m drives the motion: delta's largest
        density (DC excluded) is in the bin of f_m, and the force has a line there (its density over
        the median of the bins 3..10 away, as gear_analyze's prominence; 20 measured)."""
        m = self.msg
        f, d, F = np.array(m.frequency), np.array(m.delta_psd), np.array(m.mesh_force_psd)
        k = 1 + int(np.argmax(d[1:]))
        self.assertLessEqual(abs(f[k] - m.mesh_frequency), m.resolution)
        c = int(round(m.mesh_frequency / m.resolution))
        around = np.concatenate([F[c - 10:c - 2], F[c + 3:c + 11]])
        self.assertGreater(F[c] / np.median(around), 10.0)
        # The mesh force has its mean m_e Phi0 > 0 (removed per segment) and a finite, positive spectrum.
        self.assertTrue(np.all(F >= 0) and np.all(np.isfinite(F)) and np.sum(F) > 0)


if __name__ == '__main__':
    rospy.init_node('spectrum_test')
    rostest.rosrun('gear_dynamics', 'spectrum', SpectrumTopic, sys.argv)
