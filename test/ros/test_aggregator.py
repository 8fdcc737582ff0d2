#!/usr/bin/python3
"""End to end: a small Monte Carlo batch, then gear_aggregator. Every statistic of the latched
BatchReport is computed again here, independently (numpy, scipy, the Python rosbag API), from the
same bags; then a run bag is replayed with `rosbag play` and the played GearState messages are
compared with the bag's contents; last, the node is run on unusable folders and must exit with an
error naming the folder.

Parameters (private): folder (the batch folder), analysis_files (YAML files the aggregator
loaded, in order), report_timeout [s].
"""
import csv
import glob
import io
import math
import os
import shutil
import subprocess
import sys
import tempfile
import threading
import time
import unittest

import numpy as np
import rosbag
import rosparam
import rospy
import rostest
import rostopic
import yaml
from scipy import signal, stats

from gear_dynamics.msg import BatchReport, GearState

# Quantiles are interpolated with a different but equivalent formula in numpy (a + t (b - a) for
# t < 1/2, b - (1 - t) (b - a) otherwise), and scipy sums ranks in another order: both agree with
# the C++ to a few ulps, far below any meaningful digit.
REL = 1e-12


def close(a, b, rel=REL):
    if math.isnan(a) and math.isnan(b):
        return True
    return abs(a - b) <= rel * max(1.0, abs(a), abs(b))


def read_runs(folder):
    """RunInfo and RunSummary of every finished bag of the folder."""
    runs = []
    for path in sorted(glob.glob(os.path.join(folder, "*.bag"))):
        with rosbag.Bag(path) as bag:
            info = [m for _, m, _ in bag.read_messages(topics=["/gear/run_info"])]
            summary = [m for _, m, _ in bag.read_messages(topics=["/gear/summary"])]
        runs.append((path, info[0], summary[0]))
    return runs


def serialized(msg):
    buf = io.BytesIO()
    msg.serialize(buf)
    return buf.getvalue()


def read_csv(folder, name):
    with open(os.path.join(folder, name), newline="") as f:
        return list(csv.DictReader(f))


def load_analysis(files):
    settings = {}
    for f in files:
        with open(f) as stream:
            settings.update(yaml.safe_load(stream)["analysis"])
    return settings


class AggregatorEndToEnd(unittest.TestCase):
    report = None

    @classmethod
    def setUpClass(cls):
        rospy.init_node("test_aggregator")
        cls.folder = rospy.get_param("~folder")
        cls.analysis = load_analysis(rospy.get_param("~analysis_files"))
        timeout = rospy.get_param("~report_timeout", 90.0)
        cls.report = rospy.wait_for_message("/gear_aggregator/report", BatchReport, timeout=timeout)
        cls.runs = read_runs(cls.folder)

    @classmethod
    def tearDownClass(cls):
        shutil.rmtree(rospy.get_param("~folder"), ignore_errors=True)

    def box(self, msg, values, what):
        x = np.sort(np.asarray(values, dtype=float))
        n = len(x)
        self.assertEqual(msg.n, n, what)
        for got, p, name in ((msg.min, 0, "min"), (msg.q1, 0.25, "q1"), (msg.median, 0.5, "median"),
                             (msg.q3, 0.75, "q3"), (msg.max, 1, "max")):
            self.assertTrue(close(got, float(np.quantile(x, p))), "%s %s: %r vs numpy %r" % (what, name, got, np.quantile(x, p)))
        # Exact median interval: the largest l with P(l <= B <= n - l) >= confidence, B ~ Bin(n, 1/2).
        conf = self.report.confidence
        ls = [l for l in range(1, (n + 1) // 2 + 1) if stats.binom.cdf(n - l, n, 0.5) - stats.binom.cdf(l - 1, n, 0.5) >= conf]
        l = max(ls) if ls else 1
        self.assertEqual(msg.median_low, x[l - 1], what)
        self.assertEqual(msg.median_high, x[n - l], what)

    def proportion(self, msg, successes, trials, what):
        self.assertEqual((msg.successes, msg.trials), (successes, trials), what)
        if trials == 0:
            self.assertTrue(math.isnan(msg.estimate))
            return
        ci = stats.binomtest(successes, trials).proportion_ci(confidence_level=self.report.confidence, method="wilson")
        self.assertTrue(close(msg.low, ci.low, 1e-9) and close(msg.high, ci.high, 1e-9),
                        "%s: [%r, %r] vs scipy [%r, %r]" % (what, msg.low, msg.high, ci.low, ci.high))

    def test_1_every_statistic_equals_an_independent_computation(self):
        r, a = self.report, self.analysis
        self.assertEqual(r.runs_used, len(self.runs))
        self.assertEqual(r.runs_expected, len(self.runs))
        self.assertEqual(list(r.skipped_files), [])
        self.assertEqual(list(r.missing_runs), [])
        self.assertEqual(list(r.delta_interval), a["delta_interval"])
        mus = sorted({s.mu for _, _, s in self.runs})
        self.assertEqual([f.mu for f in r.friction], mus)
        d_by_mu = []
        for f in r.friction:
            mine = [s for _, _, s in self.runs if s.mu == f.mu]
            s1 = [s for s in mine if s.kind == "S1"]
            phase = [s for s in mine if s.kind == "phase"]
            sto = sorted((s for s in mine if s.kind == "stochastic"), key=lambda s: s.realization)
            self.assertEqual((len(s1), f.phase_runs, f.stochastic_runs), (1, len(phase), len(sto)))
            self.assertGreater(len(phase), 0)
            s1 = s1[0]
            d = [s.center_distance for s in sto]
            d_by_mu.append(d)
            what = "mu = %g" % f.mu
            self.box(f.center_distance, d, what + " d")
            self.box(f.steady_state_time, [s.steady_state_time for s in sto], what + " t_ss")
            self.box(f.steady_state_time_fine, [s.steady_state_time_fine for s in sto], what + " t_ss fine")
            self.box(f.final_delta, [s.final_delta for s in sto], what + " delta(T)")
            self.box(f.final_delta_dot, [s.final_delta_dot for s in sto], what + " delta_dot(T)")
            self.box(f.phase_center_distance, [s.center_distance for s in phase], what + " phase d")
            self.box(f.phase_final_delta, [s.final_delta for s in phase], what + " phase delta(T)")
            # Table 3 and Fig. 8.
            self.assertEqual((f.s1_center_distance, f.s1_final_delta, f.s1_final_delta_dot),
                             (s1.center_distance, s1.final_delta, s1.final_delta_dot))
            self.assertEqual((f.s2_center_distance, f.s3_center_distance), (d[0], d[1]))
            # Probabilities.
            n = len(d)
            self.proportion(f.d_exceeds_s1, sum(x > s1.center_distance for x in d), n, what + " d > d_S1")
            med = float(np.median([s.center_distance for s in phase]))
            self.proportion(f.d_exceeds_phase_median, sum(x > med for x in d), n, what + " d > phase median")
            self.proportion(f.reached_steady_state, sum(s.reached_steady_state for s in sto), n, what + " t_ss < T")
            lo, hi = a["delta_interval"]
            self.proportion(f.delta_in_interval, sum(lo <= s.final_delta <= hi for s in sto), n, what + " Table 4 delta")
            lo, hi = a["delta_dot_interval"]
            self.proportion(f.delta_dot_in_interval, sum(lo <= s.final_delta_dot <= hi for s in sto), n,
                            what + " Table 4 delta_dot")
            # Histograms (numpy's rule, edges like numpy.linspace).
            for msg, key, values in ((f.delta_pdf, "delta_bins", [s.final_delta for s in sto]),
                                     (f.delta_dot_pdf, "delta_dot_bins", [s.final_delta_dot for s in sto])):
                b0, b1, w = a[key]
                edges = np.linspace(b0, b1, int(round((b1 - b0) / w)) + 1)
                counts, _ = np.histogram(values, bins=edges)
                self.assertEqual(list(msg.edges), list(edges), key)
                self.assertEqual(list(msg.counts), list(counts), key)
                self.assertEqual(msg.outside, n - counts.sum(), key)
                self.assertTrue(np.allclose(msg.density, counts / (n * np.diff(edges)), rtol=REL, atol=0), key)
            self.assertEqual(len(f.joint_pdf), len(a["joint_times"]))
            for msg, t in zip(f.joint_pdf, a["joint_times"]):
                k = [i for i, st in enumerate(sto[0].snapshot_times) if abs(st - t) < 1e-9][0]
                x = [s.snapshot_delta[k] for s in sto]
                y = [s.snapshot_delta_dot[k] for s in sto]
                xe = np.linspace(a["joint_delta_bins"][0], a["joint_delta_bins"][1],
                                 int(round((a["joint_delta_bins"][1] - a["joint_delta_bins"][0]) / a["joint_delta_bins"][2])) + 1)
                ye = np.linspace(a["joint_delta_dot_bins"][0], a["joint_delta_dot_bins"][1],
                                 int(round((a["joint_delta_dot_bins"][1] - a["joint_delta_dot_bins"][0]) / a["joint_delta_dot_bins"][2])) + 1)
                h, _, _ = np.histogram2d(x, y, bins=[xe, ye])
                self.assertEqual(msg.time, t)
                self.assertEqual(list(msg.counts), [int(c) for c in h.flatten()], "joint at %g s" % t)
                self.assertEqual(msg.outside, n - int(h.sum()))
                self.assertGreater(int(h.sum()), 0, "the test's joint bins should hold some realizations")
        # Tests across mu.
        kw = stats.kruskal(*d_by_mu)
        self.assertTrue(close(r.kruskal_wallis.statistic, kw.statistic, 1e-9) and close(r.kruskal_wallis.p_value, kw.pvalue, 1e-9))
        fr = stats.friedmanchisquare(*d_by_mu) if len(d_by_mu) > 2 else None
        if fr is None:  # scipy needs 3 treatments; with 2 the statistic is the sign test's
            plus = sum(b > a_ for a_, b in zip(*d_by_mu))
            ties = sum(b == a_ for a_, b in zip(*d_by_mu))
            m = len(d_by_mu[0]) - ties
            q = (2 * plus - m) ** 2 / m
            self.assertTrue(close(r.friedman.statistic, q, 1e-9), "%r vs %r" % (r.friedman.statistic, q))
            # Its p is the sign test's exact one (tied pairs carry no sign).
            self.assertTrue(close(r.friedman.p_value, stats.binomtest(plus, m, 0.5).pvalue, 1e-9))
        else:
            self.assertTrue(close(r.friedman.statistic, fr.statistic, 1e-9))
        # The report folder.
        for name in ("report.md", "box_stats.csv", "probabilities.csv", "table3.csv", "pdf_delta.csv", "joint_pdf.csv",
                     "series.csv", "fig09_boxplot.png", "fig10_joint_pdf.png", "fig11_pdf_delta.png"):
            self.assertTrue(os.path.isfile(os.path.join(r.report_folder, name)), name)

    def test_4_over_time_equals_an_independent_computation(self):
        """Safety over time, first passage and Kaplan-Meier, the spectrum band and the KDEs of the
        report, recomputed from the bags' /gear/state series (numpy, scipy, by hand)."""
        r, a = self.report, self.analysis
        folder = r.report_folder
        conf = r.confidence
        z = stats.norm.ppf(0.5 + 0.5 * conf)
        safety = read_csv(folder, "safety_over_time.csv")
        passage = read_csv(folder, "first_passage.csv")
        survival = read_csv(folder, "survival.csv")
        band = read_csv(folder, "spectrum_band.csv")
        info = read_csv(folder, "spectrum_info.csv")
        kde = read_csv(folder, "kde.csv")
        (dlo, dhi), (vlo, vhi) = a["delta_interval"], a["delta_dot_interval"]
        settle = a["first_passage_settle"]
        inside = lambda d, v: (dlo <= d <= dhi) & (vlo <= v <= vhi)  # noqa: E731
        exits_seen = 0
        for f in r.friction:
            mu = "%.10g" % f.mu
            sto = sorted(((p, s) for p, i, s in self.runs if s.mu == f.mu and i.kind == "stochastic"),
                         key=lambda x: x[1].realization)
            series = []
            for path, _ in sto:
                with rosbag.Bag(path) as bag:
                    states = [m for _, m, _ in bag.read_messages(topics=["/gear/state"])]
                series.append({round(m.t, 9): (m.delta, m.delta_dot) for m in states})
            times = sorted(set.intersection(*(set(x) for x in series)))
            T = max(times)
            self.assertAlmostEqual(T, sto[0][1].snapshot_times[-1], delta=1e-9)
            # Safety over time: counts at every common time, Wilson intervals by scipy.
            rows = [x for x in safety if x["mu"] == mu]
            self.assertEqual(len(rows), 3 * len(times), mu)
            for row in rows:
                t = round(float(row["t[s]"]), 9)
                states = [x[t] for x in series]
                k = {"joint": sum(inside(d, v) for d, v in states), "delta": sum(dlo <= d <= dhi for d, _ in states),
                     "delta_dot": sum(vlo <= v <= vhi for _, v in states)}[row["quantity"]]
                self.assertEqual((int(row["successes"]), int(row["trials"])), (k, len(sto)), "%s at %g s" % (mu, t))
                ci = stats.binomtest(k, len(sto)).proportion_ci(confidence_level=conf, method="wilson")
                self.assertTrue(close(float(row["wilson_low"]), ci.low, 1e-9) and close(float(row["wilson_high"]), ci.high, 1e-9))
            # At t = T the same definition as the final-time probabilities of the report: the
            # marginals are Table 4's (the latched message), the joint counts the summaries' final states.
            final = {x["quantity"]: x for x in rows if abs(float(x["t[s]"]) - T) < 1e-9}
            for quantity, msg in (("delta", f.delta_in_interval), ("delta_dot", f.delta_dot_in_interval)):
                self.assertEqual((int(final[quantity]["successes"]), int(final[quantity]["trials"])),
                                 (msg.successes, msg.trials), "%s %s at T" % (mu, quantity))
                self.assertTrue(close(float(final[quantity]["estimate"]), msg.estimate, 1e-9))
            self.assertEqual(int(final["joint"]["successes"]),
                             sum(inside(s.final_delta, s.final_delta_dot) for _, s in sto), mu + " joint at T")
            # First passage: the first common time >= settle outside the safe set, else censored at T.
            later = [t for t in times if t >= settle - 1e-9]
            self.assertGreater(len(later), 1, "the test's settle time must leave several recorded times")
            expected = []
            for x in series:
                hit = [t for t in later if not inside(*x[t])]
                expected.append((hit[0], 1) if hit else (T, 0))
            got = [(float(x["t[s]"]), int(x["event"])) for x in passage if x["mu"] == mu]
            self.assertEqual(len(got), len(expected))
            for (tg, eg), (te, ee) in zip(got, expected):
                self.assertAlmostEqual(tg, te, delta=1e-9)
                self.assertEqual(eg, ee)
            exits_seen += sum(e for _, e in expected)
            # Kaplan-Meier by hand: S = prod(1 - d/n) over the event times, Greenwood, log(-log) interval.
            km = [x for x in survival if x["mu"] == mu]
            self.assertEqual((float(km[0]["t[s]"]), int(km[0]["at_risk"]), float(km[0]["survival"])),
                             (settle, len(sto), 1.0))
            times_e = sorted({t for t, e in expected if e})
            self.assertEqual(len(km) - 1, len(times_e))
            s_, gw = 1.0, 0.0
            for row, t in zip(km[1:], times_e):
                n = sum(1 for te, _ in expected if te >= t)
                d = sum(1 for te, e in expected if e and te == t)
                s_ *= 1 - d / n
                gw += d / (n * (n - d)) if n > d else 0.0
                self.assertEqual((int(row["at_risk"]), int(row["events"])), (n, d), "%s KM at %g" % (mu, t))
                self.assertTrue(close(float(row["survival"]), s_, 1e-12), "%s S(%g)" % (mu, t))
                if 0 < s_ < 1:
                    se = math.sqrt(gw) / abs(math.log(s_))
                    c = math.log(-math.log(s_))
                    self.assertTrue(close(float(row["low"]), math.exp(-math.exp(c + z * se)), 1e-9))
                    self.assertTrue(close(float(row["high"]), math.exp(-math.exp(c - z * se)), 1e-9))
            # Censoring happens only at T, so S(T) is the fraction that never left.
            censored = sum(1 for _, e in expected if not e)
            self.assertTrue(close(float(km[-1]["survival"]) if len(km) > 1 else 1.0, censored / len(sto), 1e-12))
            # Spectrum: scipy's Welch (periodic Hann, 50 % overlap, mean removed) of the dense
            # realizations' delta after the transient, averaged; in mm^2/Hz.
            spec = [x for x in info if x["mu"] == mu]
            self.assertEqual(len(spec), 1, mu)
            fs, L = float(spec[0]["sample_rate[Hz]"]), int(spec[0]["segment"])
            dense = [x for x in series if len(x) > len(times)]
            self.assertEqual(int(spec[0]["runs"]), len(dense))
            self.assertGreater(len(dense), 0)
            psd = []
            for x in dense:
                ts = sorted(x)
                y = np.array([x[t][0] for t in ts if t >= a["spectrum_transient"] - 1e-9]) * 1e3
                fr, p = signal.welch(y, fs=fs, window="hann", nperseg=L, noverlap=L - math.floor(L * 0.5 + 0.5),
                                     detrend="constant", scaling="density")
                psd.append(p)
            mean = np.mean(psd, axis=0)
            # The CSV has 10 significant digits; the two FFTs' rounding, ~1e-16 of the peak, is up to
            # ~1e-9 of the smallest bins (7 decades below it): 1e-6 relative leaves a margin.
            rows = [x for x in band if x["mu"] == mu]
            self.assertTrue(np.allclose([float(x["f[Hz]"]) for x in rows], fr, rtol=1e-9, atol=0))
            self.assertTrue(np.allclose([float(x["mean[mm^2/Hz]"]) for x in rows], mean, rtol=1e-6, atol=0), mu + " PSD")
            # KDE: scipy's gaussian_kde with the bandwidth of Silverman's rule computed here.
            for quantity, values in (("delta_T", [s.final_delta * 1e3 for _, s in sto]),
                                     ("delta_dot_T", [s.final_delta_dot * 1e3 for _, s in sto])):
                v = np.asarray(values)
                q75, q25 = np.quantile(v, [0.75, 0.25])
                h = 0.9 * min(np.std(v, ddof=1), (q75 - q25) / 1.34) * len(v) ** -0.2
                rows = [x for x in kde if x["mu"] == mu and x["quantity"] == quantity]
                self.assertTrue(close(float(rows[0]["bandwidth"]), h, 1e-9), "%s %s h" % (mu, quantity))
                grid = np.array([float(x["x"]) for x in rows])
                want = stats.gaussian_kde(v, bw_method=h / np.std(v, ddof=1))(grid)
                # 10 significant digits in the CSV; in the far tails both underflow differently.
                self.assertTrue(np.allclose([float(x["density"]) for x in rows], want, rtol=1e-6, atol=1e-12 * want.max()),
                                mu + " " + quantity)
        self.assertGreater(exits_seen, 0, "no realization left the safe set: the first-passage check would be empty")
        for name in ("safety_over_time.png", "first_passage.png", "spectrum_band.png"):
            self.assertTrue(os.path.isfile(os.path.join(folder, name)), name)

    def test_5_poincare_section_equals_an_independent_computation(self):
        """The bags' /gear/poincare points: at t_k = (phi_n - phi0)/Omega + k T_m (from RunInfo),
        S1's equal to its dense /gear/state series at those times exactly, and the report's
        poincare.csv and report.md table recomputed from the phase runs' points (numpy)."""
        r, a = self.report, self.analysis
        transient = a["poincare_transient"]
        rows = read_csv(r.report_folder, "poincare.csv")
        with open(os.path.join(r.report_folder, "report.md")) as f:
            report_md = f.read()
        self.assertIn("## Poincaré section of the phase ensemble", report_md)
        for f in r.friction:
            mu = "%.10g" % f.mu
            expected = []  # (j, t, delta [mm], delta_dot [mm/s]) of the phase runs after the transient
            runs = sorted(((p, i) for p, i, s in self.runs if s.mu == f.mu and i.kind != "stochastic"),
                          key=lambda x: (x[1].kind != "S1", x[1].realization))
            self.assertEqual(len(runs), 65, mu)  # S1 and the 64 phase runs
            for path, info in runs:
                with rosbag.Bag(path) as bag:
                    points = [m for _, m, _ in bag.read_messages(topics=["/gear/poincare"])]
                    states = {round(m.t, 9): m for _, m, _ in bag.read_messages(topics=["/gear/state"])}
                gear = yaml.safe_load(info.parameters_yaml)["gear_pair"]
                phi_n, omega = 2 * math.pi / gear["pinion_teeth"], gear["pinion_speed"]
                t0 = 0.0 if info.mesh_phase == 0 else (phi_n - info.mesh_phase) / omega
                tm = phi_n / omega
                n = int(math.floor((info.duration - t0) / tm + 1e-9)) + 1
                self.assertEqual(len(points), n, path)
                # t_k computed as the writer does (t_0 + k T_m in double): equal to a few ulps.
                for k, p in enumerate(points):
                    self.assertAlmostEqual(p.t, t0 + k * tm, delta=1e-15, msg="%s k %d" % (path, k))
                    self.assertEqual(p.mesh_phase, 0.0)
                if info.kind == "S1":
                    # S1 (phi0 = 0) at 1000 rpm: t_k = 3 k ms are grid steps 3000 k, recorded by the
                    # 100 kHz series (every 10 steps): the same grid state, bit for bit.
                    for p in points:
                        s = states[round(p.t, 9)]
                        self.assertEqual((p.delta, p.delta_dot), (s.delta, s.delta_dot), "%s t %r" % (path, p.t))
                    continue
                expected += [(info.realization, p.t, p.delta * 1e3, p.delta_dot * 1e3) for p in points
                             if p.t >= transient - 1e-9]
            got = [x for x in rows if x["mu"] == mu]
            self.assertEqual(len(got), len(expected), mu)
            self.assertGreater(len(got), 64 * 5, mu)  # T = 0.05 s: at least 5 points per run after 0.02 s
            for row, (j, t, d, v) in zip(got, expected):  # the order: j, then time
                self.assertEqual(int(row["phase"]), j)
                # 10 significant digits in the CSV.
                for value, want in ((float(row["t[s]"]), t), (float(row["delta[mm]"]), d), (float(row["delta_dot[mm/s]"]), v)):
                    self.assertTrue(close(value, want, 1e-9), "%s j %d t %r: %r vs %r" % (mu, j, t, value, want))
            # report.md: points and the spread (mean +- sd with ddof 1, min - max; 5 and 2 decimals).
            d = np.array([x[2] for x in expected])
            v = np.array([x[3] for x in expected])
            section = report_md.split("## Poincaré section of the phase ensemble")[1]
            line = [x for x in section.splitlines() if x.startswith("| %.2f | " % f.mu)][0]
            cells = [c.strip() for c in line.strip("|").split("|")]
            self.assertEqual((int(cells[1]), int(cells[2])), (64, len(expected)), line)
            numbers = [float(x) for c in cells[3:] for x in c.replace("±", " ").replace("–", " ").split()]
            want = [d.mean(), d.std(ddof=1), d.min(), d.max(), v.mean(), v.std(ddof=1), v.min(), v.max()]
            # Printed with 5 (mm) and 2 (mm/s) decimals: within half a unit of the last one (and a hair).
            for got_x, want_x, half in zip(numbers, want, [0.5e-5 * 1.001] * 4 + [0.5e-2 * 1.001] * 4):
                self.assertLessEqual(abs(got_x - want_x), half, "%s: %s vs %r" % (mu, line, want))
        self.assertTrue(os.path.isfile(os.path.join(r.report_folder, "poincare.png")))

    def test_6_bags_without_the_section_read_and_say_so(self):
        """A folder of older bags (no /gear/poincare) is read as before; the report says the
        section is unavailable for every mu instead of leaving it out silently."""
        name = "/aggregator_old_bags"
        rosparam.upload_params(name, {"analysis": self.analysis})
        with tempfile.TemporaryDirectory() as old:
            shutil.copy(os.path.join(self.folder, "manifest.yaml"), old)
            for path, _, _ in self.runs:
                with rosbag.Bag(path) as src, rosbag.Bag(os.path.join(old, os.path.basename(path)), "w",
                                                         compression="lz4") as dst:
                    for topic, msg, t in src.read_messages(raw=True):
                        if topic != "/gear/poincare":
                            dst.write(topic, msg, t, raw=True)
            report = os.path.join(old, "report")
            run = subprocess.run(["rosrun", "gear_dynamics", "gear_aggregator", "__name:=" + name[1:], "_folders:=" + old,
                                  "_report_folder:=" + report, "_exit_when_done:=true"],
                                 capture_output=True, text=True, timeout=60)
            self.assertEqual(run.returncode, 0, run.stdout + run.stderr)
            with open(os.path.join(report, "report.md")) as f:
                report_md = f.read()
            for f in self.report.friction:
                self.assertIn("| %.2f | – | unavailable (below) |" % f.mu, report_md)
                self.assertIn("mu = %.10g: Poincaré section: the phase runs' bags hold no /gear/poincare points" % f.mu,
                              report_md)
            self.assertEqual(read_csv(report, "poincare.csv"), [])
            # Everything else reads as from the full bags.
            for csv_name in ("runs.csv", "table3.csv", "safety_over_time.csv"):
                with open(os.path.join(report, csv_name)) as a, open(os.path.join(self.report.report_folder, csv_name)) as b:
                    self.assertEqual(a.read(), b.read(), csv_name)

    def test_2_rosbag_play_publishes_the_bags_gear_states(self):
        path = [p for p, info, _ in self.runs if info.kind == "stochastic" and info.realization == 0][0]
        with rosbag.Bag(path) as bag:
            expected = [m for _, m, _ in bag.read_messages(topics=["/gear/state"])]
        self.assertGreater(len(expected), 10)
        received, lock = [], threading.Lock()

        def on_state(msg):
            with lock:
                received.append(msg)

        sub = rospy.Subscriber("/gear/state", GearState, on_state, queue_size=len(expected) + 10)
        # -d: pause after advertising so that the subscription is connected before the first message;
        # -r: at its recorded rate the series would play at 1e5 messages/s of wall time, and
        # messages still queued when rosbag play exits are lost (seen under load): 2000/s instead.
        subprocess.run(["rosbag", "play", "-q", "-d", "1", "-r", "0.02", "--queue", str(len(expected) + 10),
                        "--topics", "/gear/state", "--", path], check=True, stdout=subprocess.DEVNULL, timeout=60)
        deadline = time.time() + 10
        while time.time() < deadline:
            with lock:
                if len(received) >= len(expected):
                    break
            time.sleep(0.05)
        sub.unregister()
        self.assertEqual(len(received), len(expected))
        # The bag reader builds its own classes from the bag's definitions: compare the bytes.
        for got, want in zip(received, expected):
            self.assertEqual(serialized(got), serialized(want))
        # The field paths that `rostopic echo /gear/state/delta` and rqt_plot use.
        for field in ("delta", "delta_dot", "phi", "center_distance"):
            self.assertEqual(rostopic.msgevalgen("/" + field)(received[-1]), getattr(expected[-1], field))

    def test_3_a_folder_without_usable_bags_is_an_error_not_a_crash(self):
        name = "/aggregator_bad_input"
        rosparam.upload_params(name, {"analysis": self.analysis})
        with tempfile.TemporaryDirectory() as empty, tempfile.TemporaryDirectory() as broken:
            # A manifest whose only bag is truncated.
            shutil.copy(os.path.join(self.folder, "manifest.yaml"), broken)
            with open(self.runs[0][0], "rb") as f:
                head = f.read(300)
            with open(os.path.join(broken, os.path.basename(self.runs[0][0])), "wb") as f:
                f.write(head)
            for folder, message in ((empty, "has no manifest.yaml"), (broken, "has no usable bag")):
                run = subprocess.run(["rosrun", "gear_dynamics", "gear_aggregator", "__name:=" + name[1:],
                                      "_folders:=" + folder, "_exit_when_done:=true"],
                                     capture_output=True, text=True, timeout=60)
                self.assertEqual(run.returncode, 1, run.stdout + run.stderr)
                self.assertIn(message, run.stdout + run.stderr)
                self.assertIn(folder, run.stdout + run.stderr)


if __name__ == "__main__":
    rostest.rosrun("gear_dynamics", "test_aggregator", AggregatorEndToEnd, sys.argv)
