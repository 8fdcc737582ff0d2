#!/usr/bin/env python3
"""Figures of the monitor's detection study (doc/monitor_study.md) from gear_monitor_study's CSV:
PREFIX_roc.png (ROC per detector at the deepest crack, one panel per load), PREFIX_pod.png (PoD
against depth with its 95 % Clopper-Pearson interval) and PREFIX_delay.png (runs detected and mean
delay to the first alarm against depth).

    python3 scripts/plot_monitor_study.py PREFIX [--detectors fm4,na4,t2,cusum]
"""
import argparse
import csv
import math
from collections import defaultdict

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def read(path):
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("prefix")
    parser.add_argument("--detectors", default="rms,fm0,fm4,na4,na4_star,nb4,sideband_level,t2,cusum")
    args = parser.parse_args()
    chosen = args.detectors.split(",")
    summary = read(args.prefix + "_summary.csv")
    roc = read(args.prefix + "_roc.csv")
    loads = sorted({float(r["load"]) for r in summary})
    depths = sorted({float(r["depth"]) for r in summary})

    fig, axes = plt.subplots(1, len(loads), figsize=(4.2 * len(loads), 4), squeeze=False)
    deepest = depths[-1]
    for ax, load in zip(axes[0], loads):
        curves = defaultdict(lambda: ([], []))
        for r in roc:
            if float(r["load"]) == load and float(r["depth"]) == deepest and r["detector"] in chosen:
                curves[r["detector"]][0].append(float(r["false_positive"]))
                curves[r["detector"]][1].append(float(r["true_positive"]))
        for name, (x, y) in curves.items():
            ax.plot(x, y, label=name, lw=1)
        ax.plot([0, 1], [0, 1], "k:", lw=0.8)
        ax.set(title=f"load {load:g} m/s², crack {1e3 * deepest:g} mm", xlabel="false-positive rate",
               ylabel="true-positive rate")
    axes[0][0].legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(args.prefix + "_roc.png", dpi=80)

    fig, axes = plt.subplots(1, len(loads), figsize=(4.2 * len(loads), 4), squeeze=False)
    for ax, load in zip(axes[0], loads):
        for name in chosen:
            rows = [r for r in summary if float(r["load"]) == load and r["detector"] == name]
            if not rows:
                continue
            d = [1e3 * float(r["depth"]) for r in rows]
            p = [float(r["pod"]) for r in rows]
            lo = [p_ - float(r["pod_low"]) for p_, r in zip(p, rows)]
            hi = [float(r["pod_high"]) - p_ for p_, r in zip(p, rows)]
            ax.errorbar(d, p, yerr=[lo, hi], label=name, capsize=2, lw=1, marker=".")
        ax.axhline(0.9, color="k", ls=":", lw=0.8)
        ax.set(title=f"load {load:g} m/s²", xlabel="crack depth [mm]", ylabel="PoD per window", ylim=(-0.02, 1.02))
    axes[0][0].legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(args.prefix + "_pod.png", dpi=80)

    fig, axes = plt.subplots(1, 2, figsize=(9, 4))
    for load in loads:
        for name in ("t2", "cusum"):
            rows = [r for r in summary if float(r["load"]) == load and r["detector"] == name]
            d = [1e3 * float(r["depth"]) for r in rows]
            axes[0].plot(d, [int(r["runs_detected"]) / int(r["runs"]) for r in rows], marker=".",
                         label=f"{name}, {load:g} m/s²")
            delay = [float(r["mean_delay_seconds"]) for r in rows]
            axes[1].plot(d, [x if math.isfinite(x) else float("nan") for x in delay], marker=".",
                         label=f"{name}, {load:g} m/s²")
    axes[0].set(xlabel="crack depth [mm]", ylabel="runs with an alarm within their windows")
    axes[1].set(xlabel="crack depth [mm]", ylabel="mean delay to the first alarm [s]")
    axes[0].legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(args.prefix + "_delay.png", dpi=80)


if __name__ == "__main__":
    main()
