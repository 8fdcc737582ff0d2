#!/usr/bin/python3
"""End to end, a study: a 2 x 2 grid (mu x load.sigma) through gear_monte_carlo and gear_aggregator.
From the bags alone (Python rosbag, numpy, scipy) this recomputes what the report says per point
(points.csv: d box statistics with the exact median interval, P(d > phase median), the Table 4
probabilities and their conjunction with Wilson intervals, t_ss, Phi(T)) and per axis
(axis_tests.csv: Kruskal-Wallis and Friedman blocked by realization on every line of the grid),
and checks the folder: format 2 manifest with its points, p<iiii>_ names, the point in every
RunInfo, common random numbers (a realization's Phi(0) equal at every point).

Parameters (private): folder (the batch folder), analysis_files, report_timeout [s].
"""
import csv
import glob
import math
import os
import shutil
import unittest

import numpy as np
import rosbag
import rospy
import rostest
import yaml
from scipy import stats

from gear_dynamics.msg import BatchReport

REL = 1e-9
U = 1e3  # SI -> the report's mm units


def close(a, b, rel=REL):
    if math.isnan(a) and math.isnan(b):
        return True
    return abs(a - b) <= rel * max(1.0, abs(a), abs(b))


def wilson(k, n, conf):
    ci = stats.binomtest(k, n).proportion_ci(confidence_level=conf, method="wilson")
    return k / n, ci.low, ci.high


def median_interval(x, conf):
    x = np.sort(np.asarray(x, dtype=float))
    n = len(x)
    ls = [l for l in range(1, (n + 1) // 2 + 1) if stats.binom.cdf(n - l, n, 0.5) - stats.binom.cdf(l - 1, n, 0.5) >= conf]
    l = max(ls) if ls else 1
    return x[l - 1], x[n - l]


def friedman(columns):
    """Friedman's chi-square with the tie correction and its p (for two treatments the exact sign
    test's); columns[j][b] is treatment j in block b."""
    data = np.asarray(columns, dtype=float).T  # blocks x treatments
    n, k = data.shape
    ranks = np.apply_along_axis(stats.rankdata, 1, data)
    r = ranks.sum(axis=0)
    ties = 0.0
    for row in data:
        _, counts = np.unique(row, return_counts=True)
        ties += float(np.sum(counts ** 3 - counts))
    denom = 1 - ties / (n * k * (k * k - 1))
    if denom <= 0:
        return float("nan"), float("nan")
    chi2 = (12.0 / (n * k * (k + 1)) * float(np.sum(r ** 2)) - 3.0 * n * (k + 1)) / denom
    if k == 2:  # the sign test, exact (tied blocks carry no sign)
        up, down = int(np.sum(data[:, 1] > data[:, 0])), int(np.sum(data[:, 1] < data[:, 0]))
        return chi2, float(stats.binomtest(up, up + down, 0.5).pvalue)
    return chi2, float(stats.chi2.sf(chi2, k - 1))


def read_csv(path):
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


class StudyEndToEnd(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        rospy.init_node("test_study")
        cls.folder = rospy.get_param("~folder")
        cls.analysis = {}
        for f in rospy.get_param("~analysis_files"):
            with open(f) as stream:
                cls.analysis.update(yaml.safe_load(stream)["analysis"])
        cls.report = rospy.wait_for_message("/gear_aggregator/report", BatchReport,
                                            timeout=rospy.get_param("~report_timeout", 150.0))
        with open(os.path.join(cls.folder, "manifest.yaml")) as f:
            cls.manifest = yaml.safe_load(f)
        cls.runs = []
        for path in sorted(glob.glob(os.path.join(cls.folder, "*.bag"))):
            with rosbag.Bag(path) as bag:
                info = [m for _, m, _ in bag.read_messages(topics=["/gear/run_info"])]
                summary = [m for _, m, _ in bag.read_messages(topics=["/gear/summary"])]
                first = next(bag.read_messages(topics=["/gear/state"]), None)
            cls.runs.append((os.path.basename(path), info[0], summary[0], first.message if first else None))

    @classmethod
    def tearDownClass(cls):
        shutil.rmtree(rospy.get_param("~folder"), ignore_errors=True)

    def test_1_folder_names_manifest_and_common_random_numbers(self):
        m = self.manifest
        self.assertEqual(m["format"], "gear_dynamics_batch/2")
        self.assertEqual(m["axes"], ["gear_pair.friction_coefficient", "load.sigma"])
        self.assertEqual([p["values"] for p in m["points"]], [[0.0, 2.5], [0.0, 10.0], [0.04, 2.5], [0.04, 10.0]])
        self.assertEqual(m["config"]["monte_carlo"]["sweep"], {"load.sigma": [2.5, 10.0]})
        self.assertEqual(len(self.runs), 4 * (1 + 64 + 8))
        entries = {e["name"]: e for e in m["runs"]}
        phi0 = {}
        for name, info, summary, first in self.runs:
            e = entries[name[:-4]]
            self.assertTrue(name.startswith("p%04d_mu%.4f_" % (e["point"], e["mu"])), name)
            params = yaml.safe_load(info.parameters_yaml)
            self.assertEqual(params["study"]["point"], e["point"], name)
            values = m["points"][e["point"]]["values"]
            self.assertEqual(params["study"]["values"], {"gear_pair.friction_coefficient": values[0], "load.sigma": values[1]})
            self.assertEqual(params["load"]["sigma"], values[1], name)
            self.assertEqual(info.sigma, values[1] if info.kind == "stochastic" else 0.0, name)
            if info.kind == "stochastic":
                phi0.setdefault(info.realization, set()).add(first.phi)
        # Common random numbers: Phi(0) of realization r is the same at every point.
        self.assertEqual(len(phi0), 8)
        for r, values in phi0.items():
            self.assertEqual(len(values), 1, "realization %d" % r)

    def test_2_points_csv_equals_an_independent_computation(self):
        conf = self.report.confidence
        rows = read_csv(os.path.join(self.report.report_folder, "points.csv"))
        self.assertEqual(len(rows), 4)
        lo_d, hi_d = self.analysis["delta_interval"]
        lo_v, hi_v = self.analysis["delta_dot_interval"]
        for row in rows:
            p = int(row["point"])
            mine = [(info, s) for _, info, s, _ in self.runs if yaml.safe_load(info.parameters_yaml)["study"]["point"] == p]
            values = self.manifest["points"][p]["values"]
            self.assertEqual((float(row["mu"]), float(row["load.sigma"])), tuple(values))
            sto = [s for info, s in mine if s.kind == "stochastic"]
            phase = [s for info, s in mine if s.kind == "phase"]
            s1 = [s for info, s in mine if s.kind == "S1"][0]
            d = np.array([s.center_distance for s in sto])
            n = len(d)
            self.assertEqual(int(row["R"]), n)
            self.assertEqual(int(row["phase_n"]), 64)
            for col, q in (("d_min", 0), ("d_q1", 0.25), ("d_median", 0.5), ("d_q3", 0.75), ("d_max", 1)):
                self.assertTrue(close(float(row[col if col != "d_min" else "d_min[mm*s^-1/2]"]), U * float(np.quantile(d, q)), 1e-9),
                                "point %d %s" % (p, col))
            lo, hi = median_interval(d, conf)
            self.assertTrue(close(float(row["d_median_low"]), U * lo) and close(float(row["d_median_high"]), U * hi))
            self.assertTrue(close(float(row["s1_d[mm*s^-1/2]"]), U * s1.center_distance))
            med_phase = float(np.median([s.center_distance for s in phase]))
            self.assertTrue(close(float(row["phase_d_median[mm*s^-1/2]"]), U * med_phase))
            checks = {
                "d>median_phase_d": sum(x > med_phase for x in d),
                "d>d_S1": sum(x > s1.center_distance for x in d),
                "delta_T_in": sum(lo_d <= s.final_delta <= hi_d for s in sto),
                "delta_dot_T_in": sum(lo_v <= s.final_delta_dot <= hi_v for s in sto),
                "both_in": sum(lo_d <= s.final_delta <= hi_d and lo_v <= s.final_delta_dot <= hi_v for s in sto),
                "t_ss<T": sum(s.reached_steady_state for s in sto),
            }
            for name, k in checks.items():
                est, wlo, whi = wilson(k, n, conf)
                self.assertEqual((int(row[name + "_k"]), int(row[name + "_n"])), (k, n), "point %d %s" % (p, name))
                self.assertTrue(close(float(row[name]), est) and close(float(row[name + "_low"]), wlo) and
                                close(float(row[name + "_high"]), whi), "point %d %s" % (p, name))
            tss = [s.steady_state_time for s in sto]
            self.assertTrue(close(float(row["t_ss_median[s]"]), float(np.median(tss))))
            phi = np.array([s.final_phi for s in sto])
            self.assertTrue(close(float(row["phi_T_mean[mm/s^2]"]), U * phi.mean(), 1e-9))
            self.assertTrue(close(float(row["phi_T_sd[mm/s^2]"]), U * phi.std(ddof=1), 1e-9))

    def test_3_axis_tests_equal_an_independent_computation(self):
        rows = read_csv(os.path.join(self.report.report_folder, "axis_tests.csv"))
        d = {}  # point -> realization -> d
        for _, info, s, _ in self.runs:
            if s.kind == "stochastic":
                d.setdefault(yaml.safe_load(info.parameters_yaml)["study"]["point"], {})[s.realization] = s.center_distance
        points = [p["values"] for p in self.manifest["points"]]
        expected = []
        for axis, name in ((0, "mu"), (1, "load.sigma")):
            other = 1 - axis
            for fixed in sorted({v[other] for v in points}):
                line = [i for i, v in enumerate(points) if v[other] == fixed]
                line.sort(key=lambda i: points[i][axis])
                expected.append((name, line))
        self.assertEqual(sorted((r["axis"], [int(x) for x in r["points"].split(";")]) for r in rows), sorted(expected))
        for r in rows:
            line = [int(x) for x in r["points"].split(";")]
            groups = [[d[p][k] for k in sorted(d[p])] for p in line]
            kw = stats.kruskal(*groups)
            self.assertTrue(close(float(r["kruskal_wallis_H"]), kw.statistic) and close(float(r["kruskal_wallis_p"]), kw.pvalue),
                            "%s %s" % (r["axis"], r["fixed"]))
            chi2, p = friedman(groups)
            self.assertEqual(int(r["friedman_blocks"]), 8)
            self.assertTrue(close(float(r["friedman_chi2"]), chi2) and close(float(r["friedman_p"]), p),
                            "%s %s: %s vs %r" % (r["axis"], r["fixed"], r["friedman_chi2"], chi2))
        # The report is organised by axis, and the study's figures are drawn.
        with open(os.path.join(self.report.report_folder, "report.md")) as f:
            md = f.read()
        self.assertIn("## Along `load.sigma`", md)
        self.assertIn("## Along `gear_pair.friction_coefficient`", md)
        for name in ("axis_mu.png", "axis_load.sigma.png", "heatmap_d.png", "heatmap_both_in.png"):
            self.assertTrue(os.path.isfile(os.path.join(self.report.report_folder, name)), name)


if __name__ == "__main__":
    rostest.rosrun("gear_dynamics", "study_end_to_end", StudyEndToEnd)
