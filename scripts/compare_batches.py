#!/usr/bin/python3
"""Do two batches agree in distribution? Two-sample tests per statistic of gear_aggregator reports.

usage: compare_batches.py REPORT_A REPORT_B [--alpha 0.05] [--markdown FILE]

REPORT_A and REPORT_B are gear_aggregator report folders (their runs.csv) of batches with the same
model and analysis settings but different random numbers: two seeds, or two builds whose numbers
differ (a new normal generator, fused multiply-adds). Single trajectories of the model separate
after about 0.1 s (doc/model.md §6), so such batches can only agree in distribution.

Per friction coefficient mu and run kind (the stochastic realizations; the deterministic phase
ensemble), each per-run statistic of runs.csv is compared: the continuous ones (d, t_ss, t_ss_fine,
delta(T), delta_dot(T), Phi(T)) by the two-sample Kolmogorov-Smirnov test, the share that reached
steady state by Fisher's exact test. The p-values are adjusted by Holm's method over all tests, so
the whole table holds at family-wise level alpha; the exit status is 1 if any adjusted p < alpha.
The deterministic run S1 is printed, not tested (one value each); samples with the same values on
both sides (the phase ensemble of two seeds, Phi(T) of the phase runs) are skipped.
"""
import argparse
import csv
import math
import sys

import numpy as np
from scipy import stats

CONTINUOUS = ["d[mm*s^-1/2]", "t_ss[s]", "t_ss_fine[s]", "delta_T[mm]", "delta_dot_T[mm/s]", "phi_T[mm/s^2]"]
BINARY = "reached_steady_state"
KINDS = ["stochastic", "phase"]


def read_runs(folder):
    path = f"{folder}/runs.csv"
    try:
        with open(path, newline="") as f:
            rows = list(csv.DictReader(f))
    except OSError as e:
        sys.exit(f"compare_batches: cannot read {path}: {e.strerror}")
    if not rows:
        sys.exit(f"compare_batches: {path} has no runs")
    return rows


def column(rows, mu, kind, key):
    return np.array([float(r[key]) for r in rows if r["kind"] == kind and float(r["mu"]) == mu])


def holm(p_values):
    """Holm-Bonferroni adjusted p-values, in the input order."""
    order = np.argsort(p_values)
    adjusted = np.empty(len(p_values))
    running = 0.0
    for rank, i in enumerate(order):
        running = max(running, min(1.0, (len(p_values) - rank) * p_values[i]))
        adjusted[i] = running
    return adjusted


def compare(a_rows, b_rows):
    mus = sorted({float(r["mu"]) for r in a_rows})
    if mus != sorted({float(r["mu"]) for r in b_rows}):
        sys.exit("compare_batches: the two reports have different friction coefficients")
    tests = []
    for kind in KINDS:
        for mu in mus:
            for key in CONTINUOUS + [BINARY]:
                a, b = column(a_rows, mu, kind, key), column(b_rows, mu, kind, key)
                if len(a) < 2 or len(b) < 2 or np.array_equal(np.sort(a), np.sort(b)):
                    continue  # too few runs, or the same values (the phase runs of two seeds): nothing to test
                if key == BINARY:
                    table = [[int(a.sum()), len(a) - int(a.sum())], [int(b.sum()), len(b) - int(b.sum())]]
                    p, test = stats.fisher_exact(table).pvalue, "Fisher"
                    centre_a, centre_b = a.mean(), b.mean()
                else:
                    p, test = stats.ks_2samp(a, b).pvalue, "KS"
                    centre_a, centre_b = np.median(a), np.median(b)
                tests.append(dict(kind=kind, mu=mu, key=key, n_a=len(a), n_b=len(b), centre_a=centre_a,
                                  centre_b=centre_b, test=test, p=p))
    if not tests:
        sys.exit("compare_batches: no statistic to compare (no stochastic or phase runs)")
    for t, adjusted in zip(tests, holm(np.array([t["p"] for t in tests]))):
        t["p_holm"] = adjusted
    return mus, tests


def s1_lines(a_rows, b_rows, mus):
    lines = []
    for mu in mus:
        a, b = column(a_rows, mu, "S1", CONTINUOUS[0]), column(b_rows, mu, "S1", CONTINUOUS[0])
        if len(a) and len(b):
            lines.append(f"S1 at mu = {mu:g}: d = {a[0]:.4g} (A) and {b[0]:.4g} (B) mm*s^-1/2")
    return lines


def markdown(tests, alpha):
    out = ["| runs | mu | statistic | n A | n B | A | B | test | p | p (Holm) |",
           "|---|---|---|---|---|---|---|---|---|---|"]
    for t in tests:
        centre = "share" if t["test"] == "Fisher" else "median"
        flag = " **reject**" if t["p_holm"] < alpha else ""
        out.append(f"| {t['kind']} | {t['mu']:g} | {t['key']} ({centre}) | {t['n_a']} | {t['n_b']} | "
                   f"{t['centre_a']:.4g} | {t['centre_b']:.4g} | {t['test']} | {t['p']:.3g} | "
                   f"{t['p_holm']:.3g}{flag} |")
    return out


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("report_a")
    parser.add_argument("report_b")
    parser.add_argument("--alpha", type=float, default=0.05, help="family-wise level (default 0.05)")
    parser.add_argument("--markdown", help="also write the table to this file")
    args = parser.parse_args()
    if not 0.0 < args.alpha < 1.0:
        sys.exit(f"compare_batches: --alpha {args.alpha} is outside (0, 1)")
    a_rows, b_rows = read_runs(args.report_a), read_runs(args.report_b)
    mus, tests = compare(a_rows, b_rows)
    table = markdown(tests, args.alpha)
    print("\n".join(table))
    for line in s1_lines(a_rows, b_rows, mus):
        print(line)
    below = sum(t["p"] < args.alpha for t in tests)
    rejected = [t for t in tests if t["p_holm"] < args.alpha]
    # Under the null the raw p-values are about uniform: about alpha of them fall below alpha.
    print(f"{len(tests)} tests: {below} with p < {args.alpha:g} before adjustment "
          f"(about {args.alpha * len(tests):.1f} expected by chance), {len(rejected)} rejected after Holm's adjustment")
    if args.markdown:
        with open(args.markdown, "w") as f:
            f.write("\n".join(table) + "\n")
    return 1 if rejected else 0


if __name__ == "__main__":
    sys.exit(main())
