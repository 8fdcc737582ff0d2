#!/usr/bin/python3
"""Draws the figures of a gear_aggregator report (the paper's Figs. 5-12) from its CSV files.

usage: plot_report.py REPORT_FOLDER [--mu 0.04] [--wait]

For a study with more axes than mu (points.csv with more than one axis column, doc/studies.md) it
draws the study's figures instead: axis_<key>.png per swept axis and, for a 2-D grid,
heatmap_d.png and heatmap_both_in.png. Both also get the figures over time, one line or panel per
mu or point: safety_over_time.png, first_passage.png, spectrum_band.png and poincare.png.

Every number comes from the CSV files the aggregator wrote (paper units); this script only draws.
--mu selects the friction coefficient of the series and joint-PDF figures (the paper's 0.04).
--wait reads a line from stdin before reading the folder (end of input: exit 0, nothing drawn):
gear_aggregator starts the script early, so that Python (and matplotlib, for a folder without
figures yet) is loaded when its CSV files are written.
Figures whose inputs are unchanged since they were drawn are kept (figures.sha256, see below).
"""
import argparse
import csv
import glob
import hashlib
import importlib.metadata
import math
import os
import sys
import time

# numpy and matplotlib, set by load_plotting(): about a second of CPU to import, spent only when a
# figure is drawn (the main command run again keeps its figures).
np = plt = MaxNLocator = None


def load_plotting():
    global np, plt, MaxNLocator
    if plt is not None:
        return
    import matplotlib
    import numpy
    matplotlib.use("Agg")
    import matplotlib.pyplot
    from matplotlib.ticker import MaxNLocator as locator
    np, plt, MaxNLocator = numpy, matplotlib.pyplot, locator


def read(folder, name):
    """The rows of a CSV file as dicts (column -> text); dict(zip()) is about twice csv.DictReader's speed."""
    with open(os.path.join(folder, name), newline="") as f:
        rows = csv.reader(f)
        header = next(rows, [])
        return [dict(zip(header, r)) for r in rows]


def table(folder, name):
    """The columns of a large CSV file: column -> numpy array, of floats where the first row holds a
    number, else of text. np.loadtxt parses in C: 0.1 s for the 120000 rows of series.csv, where
    csv.reader and per-row dicts took 0.4-0.8 s, and the figures then select with masks."""
    path = os.path.join(folder, name)
    with open(path, newline="") as f:
        rows = csv.reader(f)
        header = next(rows, [])
        first = next(rows, None)
    if first is None:
        return {k: np.array([]) for k in header}
    numeric = [i for i, v in enumerate(first) if is_number(v)]
    out = {}
    for usecols, dtype in ((numeric, float), ([i for i in range(len(header)) if i not in numeric], str)):
        if usecols:
            values = np.loadtxt(path, delimiter=",", skiprows=1, usecols=usecols, dtype=dtype, ndmin=2)
            out.update({header[i]: values[:, j] for j, i in enumerate(usecols)})
    return {k: out[k] for k in header}


def is_number(text):
    try:
        float(text)
        return True
    except ValueError:
        return False


def groups_of_table(columns, first_data):
    """groups_of for a table(): group label -> row indices, in the order of first appearance."""
    keys = list(columns)
    key_cols = [k for k in keys[:keys.index(first_data)] if k != "point"]
    rows = {}
    for i, key in enumerate(zip(*(columns[k] for k in key_cols))):
        rows.setdefault(key, []).append(i)
    return {", ".join("%s = %g" % ("μ" if k == "mu" else k, v) for k, v in zip(key_cols, key)): np.array(idx)
            for key, idx in rows.items()}


def col(rows, key):
    return [float(r[key]) for r in rows]


def closest(values, target):
    """The value in `values` nearest to target, or None if there is none."""
    values = sorted(set(values))
    return min(values, key=lambda v: abs(v - target)) if values else None


def series_figures(folder, mu, out):
    s = table(folder, "series.csv")
    mu_s = closest(s["mu"], mu)
    if mu_s is None:
        print("plot_report: series.csv is empty; Figs. 5-7 not drawn", file=sys.stderr)
        return
    at_mu = s["mu"] == mu_s
    number = np.where(s["kind"] == "S1", 1, s["index"] + 2)  # S1, and S2, S3, ... for the stochastic runs
    runs = {"S%d" % k: {c: v[at_mu & (number == k)] for c, v in s.items()} for k in np.unique(number[at_mu])}
    names = sorted(runs)
    batch = {r["key"]: float(r["value"]) for r in read(folder, "batch.csv")}

    fig, ax = plt.subplots(figsize=(7, 4))
    for n in names:
        ax.plot(runs[n]["t[s]"], runs[n]["phi[mm/s^2]"], lw=0.8, label=n)
    ax.set_xlabel("t [s]")
    ax.set_ylabel("Φ [mm/s²]")
    ax.set_title("Load processes (Fig. 5)")
    ax.legend()
    out(fig, "fig05_load.png")

    fig, axes = plt.subplots(len(names), 1, figsize=(7, 2.2 * len(names)), sharex=True, squeeze=False)
    for ax, n in zip(axes[:, 0], names):
        ax.plot(runs[n]["t[s]"], runs[n]["delta[mm]"], lw=0.5)
        ax.set_ylabel("δ [mm]")
        ax.set_title("%s, μ = %g" % (n, mu_s), fontsize=9)
    axes[-1, 0].set_xlabel("t [s]")
    fig.suptitle("Relative displacement (Fig. 6)")
    out(fig, "fig06_delta.png")

    hi = batch["duration"]
    lo = hi - batch["window"]
    fig, axes = plt.subplots(1, len(names), figsize=(3.3 * len(names), 3.3), squeeze=False)
    for ax, n in zip(axes[0], names):
        w = (lo <= runs[n]["t[s]"]) & (runs[n]["t[s]"] <= hi)
        ax.plot(runs[n]["delta[mm]"][w], runs[n]["delta_dot[mm/s]"][w], lw=0.4)
        ax.xaxis.set_major_locator(MaxNLocator(4))
        ax.ticklabel_format(axis="x", useOffset=False)
        ax.set_xlabel("δ [mm]")
        ax.set_title(n, fontsize=9)
    axes[0, 0].set_ylabel(r"$\dot{\delta}$ [mm/s]")
    fig.suptitle("Phase portraits on [%g, %g] s, μ = %g (Fig. 7)" % (lo, hi, mu_s))
    out(fig, "fig07_phase.png")


def center_distance_figures(folder, out):
    t3 = read(folder, "table3.csv")
    box = [r for r in read(folder, "box_stats.csv") if r["quantity"] == "d"]
    mus = col(t3, "mu")
    fig, ax = plt.subplots(figsize=(6, 4))
    for key, name, style in (("s1_d", "S1", "o-"), ("s2_d", "S2", "s-"), ("s3_d", "S3", "^-")):
        ax.plot(mus, col(t3, key + "[mm*s^-1/2]"), style, label=name)
    phase = [r for r in box if r["group"] == "phase" and int(r["n"]) > 0]
    if phase:
        ax.fill_between(col(phase, "mu"), col(phase, "min"), col(phase, "max"), color="0.85",
                        label="phase ensemble min–max")
        ax.plot(col(phase, "mu"), col(phase, "median"), "k--", lw=0.8, label="phase ensemble median")
    ax.set_xlabel("μ")
    ax.set_ylabel("d [mm·s$^{-1/2}$]")
    ax.set_title("Center distance of S1, S2, S3 (Fig. 8)")
    ax.legend(fontsize=8)
    out(fig, "fig08_center_distance.png")

    stoch = [r for r in box if r["group"] == "stochastic" and int(r["n"]) > 0]
    stats = [{"med": float(r["median"]), "q1": float(r["q1"]), "q3": float(r["q3"]), "whislo": float(r["min"]),
              "whishi": float(r["max"]), "cilo": float(r["median_low"]), "cihi": float(r["median_high"]),
              "fliers": [], "label": "%g" % float(r["mu"])} for r in stoch]
    fig, ax = plt.subplots(figsize=(6, 4))
    if stats:
        ax.bxp(stats, shownotches=True, showfliers=False)
        s1 = {float(r["mu"]): float(r["s1_d[mm*s^-1/2]"]) for r in t3}
        ax.plot(range(1, len(stoch) + 1), [s1.get(float(r["mu"]), math.nan) for r in stoch], "rx", label="S1")
        ax.legend(fontsize=8)
    ax.set_xlabel("μ")
    ax.set_ylabel("d [mm·s$^{-1/2}$]")
    ax.set_title("Center distance, stochastic load (Fig. 9)\nwhiskers min–max, notches: median interval")
    out(fig, "fig09_boxplot.png")


def joint_figure(folder, mu, out):
    rows = read(folder, "joint_pdf.csv")
    mu_j = closest(col(rows, "mu"), mu)
    if mu_j is None:
        return
    rows = [r for r in rows if float(r["mu"]) == mu_j]
    times = sorted(set(col(rows, "t[s]")))
    ncol = 2 if len(times) > 1 else 1
    nrow = int(math.ceil(len(times) / ncol))
    fig, axes = plt.subplots(nrow, ncol, figsize=(5 * ncol, 3.6 * nrow), squeeze=False)
    for ax, t in zip(axes.flat, times):
        cells = [r for r in rows if float(r["t[s]"]) == t]
        xs = sorted(set(col(cells, "delta_lo[mm]")) | set(col(cells, "delta_hi[mm]")))
        ys = sorted(set(col(cells, "delta_dot_lo[mm/s]")) | set(col(cells, "delta_dot_hi[mm/s]")))
        grid = [[0.0] * (len(xs) - 1) for _ in range(len(ys) - 1)]
        for c in cells:
            grid[ys.index(float(c["delta_dot_lo[mm/s]"]))][xs.index(float(c["delta_lo[mm]"]))] = float(c["density[s/mm^2]"])
        m = ax.pcolormesh(xs, ys, grid, cmap="viridis", shading="flat")
        fig.colorbar(m, ax=ax, label="density [s/mm²]")
        ax.set_title("t = %g s" % t)
        ax.set_xlabel("δ [mm]")
        ax.set_ylabel(r"$\dot{\delta}$ [mm/s]")
    for ax in list(axes.flat)[len(times):]:
        ax.axis("off")
    fig.suptitle(r"Joint PDF of ($\delta$, $\dot{\delta}$), μ = %g (Fig. 10)" % mu_j)
    out(fig, "fig10_joint_pdf.png")


def pdf_figure(folder, name, unit, label, title, filename, out):
    """One panel per mu (small multiples read better than six overlaid histograms)."""
    rows = read(folder, name)
    outside = {(float(r["mu"]), r["quantity"]): float(r["fraction"]) for r in read(folder, "pdf_outside.csv")}
    quantity = "delta_T" if unit == "mm" else "delta_dot_T"
    kde = read(folder, "kde.csv") if os.path.exists(os.path.join(folder, "kde.csv")) else []
    mus = sorted(set(col(rows, "mu")))
    ncol = min(3, len(mus))
    nrow = int(math.ceil(len(mus) / ncol))
    fig, axes = plt.subplots(nrow, ncol, figsize=(3.4 * ncol, 2.6 * nrow), sharex=True, sharey=True, squeeze=False)
    density = [k for k in rows[0] if k.startswith("density")][0]
    for ax, mu in zip(axes.flat, mus):
        r = [x for x in rows if float(x["mu"]) == mu]
        edges = col(r, "lo[%s]" % unit) + [float(r[-1]["hi[%s]" % unit])]
        ax.stairs(col(r, density), edges, fill=True, alpha=0.6)
        k = [x for x in kde if float(x["mu"]) == mu and x["quantity"] == quantity]
        if k:
            ax.plot(col(k, "x"), col(k, "density"), "k", lw=0.8,
                    label="KDE, h = %.2g %s" % (float(k[0]["bandwidth"]), unit))
            ax.legend(fontsize=6)
        ax.set_title("μ = %g (%.0f %% outside)" % (mu, 100 * outside.get((mu, quantity), 0.0)), fontsize=9)
    for ax in axes[-1]:
        ax.set_xlabel("%s [%s]" % (label, unit))
    for ax in axes[:, 0]:
        ax.set_ylabel("PDF [%s]" % density[density.index("[") + 1:-1])
    for ax in list(axes.flat)[len(mus):]:
        ax.axis("off")
    fig.suptitle(title)
    out(fig, filename)


def group_label(row, first_data):
    """The group of a row of the files over time: the key columns before `first_data` ("mu = 0.04",
    or a study point's axis values)."""
    keys = list(row.keys())
    cols = [k for k in keys[:keys.index(first_data)] if k != "point"]
    return ", ".join("%s = %g" % ("μ" if k == "mu" else k, float(row[k])) for k in cols)


def groups_of(rows, first_data):
    out = {}
    for r in rows:
        out.setdefault(group_label(r, first_data), []).append(r)
    return out


def safety_figure(folder, out):
    rows = read(folder, "safety_over_time.csv")
    if not rows:
        return
    groups = groups_of(rows, "t[s]")
    fig, axes = plt.subplots(1, 3, figsize=(14, 4), sharey=True)
    for ax, quantity, title in zip(axes, ("joint", "delta", "delta_dot"),
                                   (r"P($\delta \in I_\delta \wedge \dot\delta \in I_v$)", r"P($\delta \in I_\delta$)",
                                    r"P($\dot\delta \in I_v$)")):
        for label, g in groups.items():
            q = [r for r in g if r["quantity"] == quantity]
            t = col(q, "t[s]")
            line, = ax.plot(t, [100 * v for v in col(q, "estimate")], lw=1, label=label)
            ax.fill_between(t, [100 * v for v in col(q, "wilson_low")], [100 * v for v in col(q, "wilson_high")],
                            color=line.get_color(), alpha=0.15, lw=0)
        ax.set_title(title)
        ax.set_xlabel("t [s]")
        ax.grid(alpha=0.3)
    axes[0].set_ylabel("probability [%] (95 % Wilson band)")
    axes[0].legend(fontsize=7)
    fig.suptitle("Safety over time, stochastic realizations")
    out(fig, "safety_over_time.png")


def first_passage_figure(folder, out):
    km = read(folder, "survival.csv")
    if not km:
        return
    passage = groups_of(read(folder, "first_passage.csv"), "realization")
    fig, (ax_s, ax_h) = plt.subplots(1, 2, figsize=(12, 4))
    for label, g in groups_of(km, "t[s]").items():
        t = col(g, "t[s]")
        line, = ax_s.step(t, col(g, "survival"), where="post", lw=1, label=label)
        ax_s.fill_between(t, col(g, "low"), col(g, "high"), step="post", color=line.get_color(), alpha=0.15, lw=0)
        exits = [float(r["t[s]"]) for r in passage.get(label, []) if r["event"] == "1"]
        if exits:
            ax_h.hist(exits, bins=sorted(set(t)) + [max(t) + 1e-9], histtype="step", color=line.get_color(), label=label)
    ax_s.set_xlabel("t [s]")
    ax_s.set_ylabel("S(t): no exit since the settling time")
    ax_s.set_title("Kaplan–Meier survival (95 % log(−log) band)")
    ax_s.set_ylim(0, 1.02)
    ax_s.grid(alpha=0.3)
    ax_s.legend(fontsize=7)
    ax_h.set_xlabel("first passage time [s]")
    ax_h.set_ylabel("realizations")
    ax_h.set_title("First passage out of the safe set (exits only)")
    out(fig, "first_passage.png")


def spectrum_figure(folder, out):
    rows = table(folder, "spectrum_band.csv")
    if not len(rows["f[Hz]"]):
        return
    info = {group_label(r, "mesh_frequency[Hz]"): r for r in read(folder, "spectrum_info.csv")}
    groups = groups_of_table(rows, "f[Hz]")
    ncol = min(3, len(groups))
    nrow = int(math.ceil(len(groups) / ncol))
    fig, axes = plt.subplots(nrow, ncol, figsize=(4.5 * ncol, 3.2 * nrow), sharex=True, sharey=True, squeeze=False)
    for ax, (label, idx) in zip(axes.flat, groups.items()):
        fm = float(info[label]["mesh_frequency[Hz]"])
        f = rows["f[Hz]"][idx]
        idx = idx[(0 < f) & (f <= 15 * fm)]  # the harmonics; the CSV goes to Nyquist
        g = {k: v[idx] for k, v in rows.items()}
        f = g["f[Hz]"]
        ax.fill_between(f, g["run_low[mm^2/Hz]"], g["run_high[mm^2/Hz]"], color="0.85", lw=0,
                        label="single runs' 95 % range")
        if int(info[label]["runs"]) >= 5:  # the normal interval of a mean of fewer runs reaches 0 (log axis)
            ax.fill_between(f, g["mean_low[mm^2/Hz]"], g["mean_high[mm^2/Hz]"], color="C0", alpha=0.3, lw=0,
                            label="95 % interval of the mean")
        ax.plot(f, g["mean[mm^2/Hz]"], "C0", lw=0.7, label="mean PSD")
        for k in range(1, 6):
            ax.axvline(k * fm, color="C3", lw=0.6, ls=":", label="k·f$_m$, k = 1…5" if k == 1 else None)
        ax.set_yscale("log")
        ax.set_title("%s (%s runs)" % (label, info[label]["runs"]), fontsize=9)
    for ax in axes[-1]:
        ax.set_xlabel("f [Hz]")
    for ax in axes[:, 0]:
        ax.set_ylabel("PSD of δ [mm²/Hz]")
    for ax in list(axes.flat)[len(groups):]:
        ax.axis("off")
    axes[0, 0].legend(fontsize=7)
    fig.suptitle("Welch PSD of δ over the dense realizations, f$_m$ = %g Hz" % float(next(iter(info.values()))["mesh_frequency[Hz]"]))
    out(fig, "spectrum_band.png")


def poincare_figure(folder, out):
    """δ against δ̇ of the phase ensemble's Poincaré points, one panel per mu or point."""
    if not os.path.exists(os.path.join(folder, "poincare.csv")):
        return
    rows = table(folder, "poincare.csv")
    if not len(rows["phase"]):
        return
    groups = groups_of_table(rows, "phase")
    ncol = min(3, len(groups))
    nrow = int(math.ceil(len(groups) / ncol))
    fig, axes = plt.subplots(nrow, ncol, figsize=(4.5 * ncol, 3.6 * nrow), sharex=True, sharey=True, squeeze=False)
    for ax, (label, idx) in zip(axes.flat, groups.items()):
        runs = len(np.unique(rows["phase"][idx]))
        ax.scatter(rows["delta[mm]"][idx], rows["delta_dot[mm/s]"][idx], color="C0", s=2, lw=0, alpha=0.6)
        ax.set_title("%s (%d runs, %d points)" % (label, runs, len(idx)), fontsize=9)
        ax.grid(alpha=0.3)
    for ax in axes[-1]:
        ax.set_xlabel("δ [mm]")
    for ax in axes[:, 0]:
        ax.set_ylabel(r"$\dot\delta$ [mm/s]")
    for ax in list(axes.flat)[len(groups):]:
        ax.axis("off")
    fig.suptitle("Poincaré section of the phase ensemble (φ0 = j·φn/64) at mesh phase 0, from t = %.3g s"
                 % rows["t[s]"].min())
    out(fig, "poincare.png")


def bearing_forces_figure(folder, out):
    """The bearings model's forces: per force, box plots of the runs' RMS over the window, one box
    per mu or study point (stochastic runs). From bearing_forces.csv; nothing for the torsional model."""
    if not os.path.exists(os.path.join(folder, "bearing_forces.csv")):
        return
    rows = [r for r in read(folder, "bearing_forces.csv") if r["kind"] == "stochastic"]
    if not rows:
        return
    keys = list(rows[0].keys())
    group_keys = keys[keys.index("kind") + 1:keys.index("force")]  # mu, or point and the axes
    group_keys = [k for k in group_keys if k != "point"]
    forces = list(dict.fromkeys(r["force"] for r in rows))
    rms = {}  # (group, force) -> the runs' RMS, in the file's order
    for r in rows:
        rms.setdefault((tuple(r[k] for k in group_keys), r["force"]), []).append(float(r["rms[N]"]))
    groups = list(dict.fromkeys(g for g, _ in rms))
    symbol = {"mu": "μ", "bearing_damping_ratio": "ζ_b", "bearing_stiffness": "k_b", "initial_mean": "Φ0",
              "sigma": "σ", "friction_model": "law"}
    labels = ["\n".join("%s %s" % (symbol.get(k.split(".")[-1], k.split(".")[-1]),
                                    value_text(float(v)) if is_number(v) else v) for k, v in zip(group_keys, g))
              for g in groups]
    fig, axes = plt.subplots(len(forces), 1, figsize=(max(8.0, 0.9 * len(groups) + 2), 2.2 * len(forces)),
                             sharex=True, squeeze=False)
    for ax, force in zip(axes[:, 0], forces):
        data = [rms[(g, force)] for g in groups]
        ax.boxplot(data, showfliers=False)
        positive = [v for d in data for v in d if v > 0]
        if positive and max(positive) > 100 * min(positive):  # the rattle's forces beside contact's
            ax.set_yscale("log")
        ax.set_ylabel("%s\nRMS [N]" % force)
        ax.grid(alpha=0.3)
    axes[-1, 0].set_xticks(range(1, len(groups) + 1), labels, fontsize=7)
    fig.suptitle("Mesh and bearing forces (x across, y along the line of action): RMS over the window per run")
    out(fig, "bearing_forces.png")


def axis_columns(points):
    """The axis columns of points.csv: every column between `point` and `R`."""
    keys = list(points[0].keys())
    return keys[1:keys.index("R")]


def axis_values(points, a):
    """The values of axis `a`: numbers ascending, or the labels of a text axis (friction_model, ...)
    in the study's order; and a function from a row to that value."""
    try:
        values = sorted(set(float(p[a]) for p in points))
        return values, lambda p: float(p[a])
    except ValueError:
        return list(dict.fromkeys(p[a] for p in points)), lambda p: p[a]


def value_text(v):
    return "%g" % v if isinstance(v, float) else v


def study_figures(folder, out):
    """A figure per axis with more than one value (lines for the other axes' values), and for a
    2-D grid heat maps of median d and of P(delta(T) in and delta_dot(T) in). From points.csv."""
    points = read(folder, "points.csv")
    axes = axis_columns(points)
    values, value = {}, {}
    for a in axes:
        values[a], value[a] = axis_values(points, a)
    varied = [a for a in axes if len(values[a]) > 1]
    for a in varied:
        others = [b for b in varied if b != a]
        lines = {}
        for p in points:
            lines.setdefault(tuple(value[b](p) for b in others), []).append(p)
        fig, (ax_d, ax_p, ax_b) = plt.subplots(1, 3, figsize=(13, 3.8))
        for key, rows in sorted(lines.items()):
            rows.sort(key=lambda p: values[a].index(value[a](p)))
            x = [values[a].index(value[a](p)) for p in rows] if isinstance(values[a][0], str) else col(rows, a)
            label = ", ".join("%s = %s" % (b, value_text(v)) for b, v in zip(others, key)) or None
            med = col(rows, "d_median")
            lo = [m - l for m, l in zip(med, col(rows, "d_median_low"))]
            hi = [h - m for m, h in zip(med, col(rows, "d_median_high"))]
            ax_d.errorbar(x, med, yerr=[lo, hi], marker="o", capsize=3, label=label)
            for axis, name in ((ax_p, "d>median_phase_d"), (ax_b, "both_in")):
                est = [100 * v for v in col(rows, name)]
                axis.errorbar(x, est, yerr=[[e - 100 * v for e, v in zip(est, col(rows, name + "_low"))],
                                            [100 * v - e for e, v in zip(est, col(rows, name + "_high"))]],
                              marker="o", capsize=3, label=label)
        ax_d.set_ylabel("median d [mm·s$^{-1/2}$] (95 % interval)")
        ax_p.set_ylabel("P(d > phase-ensemble median) [%]")
        ax_b.set_ylabel(r"P($\delta$(T) $\in$ I $\wedge$ $\dot{\delta}$(T) $\in$ I) [%]")
        for axis in (ax_d, ax_p, ax_b):
            if isinstance(values[a][0], str):  # a text axis: one tick per label
                axis.set_xticks(range(len(values[a])), values[a])
            axis.set_xlabel(a)
            axis.grid(alpha=0.3)
        if others:
            ax_d.legend(fontsize=7)
        fig.suptitle("Along %s" % a)
        out(fig, "axis_%s.png" % a)
    if len(varied) == 2:
        a, b = varied
        for name, label, filename in (("d_median", "median d [mm·s$^{-1/2}$]", "heatmap_d.png"),
                                      ("both_in", r"P($\delta$ $\in$ I $\wedge$ $\dot{\delta}$ $\in$ I)", "heatmap_both_in.png")):
            grid = [[float("nan")] * len(values[a]) for _ in values[b]]
            for p in points:
                grid[values[b].index(value[b](p))][values[a].index(value[a](p))] = float(p[name])
            fig, ax = plt.subplots(figsize=(1.2 * len(values[a]) + 2.5, 0.8 * len(values[b]) + 1.8))
            im = ax.imshow(grid, origin="lower", aspect="auto", cmap="viridis")
            ax.set_xticks(range(len(values[a])), [value_text(v) for v in values[a]])
            ax.set_yticks(range(len(values[b])), [value_text(v) for v in values[b]])
            for i, row in enumerate(grid):
                for j, v in enumerate(row):
                    ax.text(j, i, "%.3g" % v, ha="center", va="center", color="w", fontsize=8)
            ax.set_xlabel(a)
            ax.set_ylabel(b)
            fig.colorbar(im, ax=ax, label=label)
            out(fig, filename)


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("folder")
    parser.add_argument("--mu", type=float, default=0.04, help="mu of Figs. 5-7 and 10 (default 0.04)")
    parser.add_argument("--wait", action="store_true", help="draw only after a line on stdin (end of input: exit 0)")
    args = parser.parse_args()
    # A folder without figures gets them drawn: the imports then overlap the caller's work (--wait).
    if not os.path.exists(os.path.join(args.folder, FIGURES_DIGEST)):
        load_plotting()
    if args.wait:
        try:
            if not sys.stdin.readline():
                return
        except KeyboardInterrupt:  # the launch was stopped while the caller waited
            return

    def out(fig, filename):
        fig.tight_layout()
        fig.savefig(os.path.join(args.folder, filename), dpi=120)
        plt.close(fig)

    inputs = inputs_digest(args.folder, args.mu)
    if figures_current(args.folder, inputs):
        print("plot_report: the figures in %s are those of these CSV files; not drawn again" % args.folder)
        return
    load_plotting()
    started = time.time()
    points = os.path.join(args.folder, "points.csv")
    study = os.path.exists(points) and len(axis_columns(read(args.folder, "points.csv"))) > 1
    if study:  # a study with more axes than mu: its figures, not the paper's
        draw_in_parallel([lambda: study_figures(args.folder, out), lambda: safety_figure(args.folder, out),
                          lambda: first_passage_figure(args.folder, out), lambda: spectrum_figure(args.folder, out),
                          lambda: poincare_figure(args.folder, out), lambda: bearing_forces_figure(args.folder, out)])
        record_figures(args.folder, inputs, started)
        print("plot_report: study figures written to %s" % args.folder)
        return
    # Dearest first (the series, spectrum band and Poincaré points are the largest CSV files), so
    # that the cheap ones, taken last, even out the processes' shares.
    draw_in_parallel([
        lambda: spectrum_figure(args.folder, out),
        lambda: series_figures(args.folder, args.mu, out),
        lambda: poincare_figure(args.folder, out),
        lambda: joint_figure(args.folder, args.mu, out),
        lambda: pdf_figure(args.folder, "pdf_delta.csv", "mm", "δ(T)", "PDF of δ at T (Fig. 11)", "fig11_pdf_delta.png",
                           out),
        lambda: pdf_figure(args.folder, "pdf_delta_dot.csv", "mm/s", r"$\dot{\delta}$(T)",
                           r"PDF of $\dot{\delta}$ at T (Fig. 12)", "fig12_pdf_delta_dot.png", out),
        lambda: safety_figure(args.folder, out),
        lambda: center_distance_figures(args.folder, out),
        lambda: first_passage_figure(args.folder, out),
        lambda: bearing_forces_figure(args.folder, out),
    ])
    record_figures(args.folder, inputs, started)
    print("plot_report: figures written to %s" % args.folder)


# The figures are a function of the CSV files, this script, --mu and matplotlib: FIGURES_DIGEST
# records that input's digest and each figure's, so that a report rewritten with the same numbers
# (the main command run again) keeps its figures instead of drawing them again.
FIGURES_DIGEST = "figures.sha256"


def file_digest(path):
    with open(path, "rb") as f:
        return hashlib.sha256(f.read()).hexdigest()


def inputs_digest(folder, mu):
    h = hashlib.sha256()
    h.update(("mu %r matplotlib %s\n" % (mu, importlib.metadata.version("matplotlib"))).encode())
    h.update(file_digest(os.path.abspath(__file__)).encode())
    for path in sorted(glob.glob(os.path.join(folder, "*.csv"))):
        h.update(("%s %s\n" % (os.path.basename(path), file_digest(path))).encode())
    return h.hexdigest()


def figures_current(folder, inputs):
    """Whether FIGURES_DIGEST names these inputs and every figure it lists is there, unchanged."""
    try:
        with open(os.path.join(folder, FIGURES_DIGEST)) as f:
            lines = f.read().split("\n")
    except OSError:
        return False
    if lines[0] != "inputs " + inputs:
        return False
    figures = [line.split(" ", 1) for line in lines[1:] if line]
    return bool(figures) and all(os.path.exists(os.path.join(folder, name)) and
                                 file_digest(os.path.join(folder, name)) == digest for digest, name in figures)


def record_figures(folder, inputs, started):
    """Writes FIGURES_DIGEST for the figures written since `started`."""
    drawn = sorted(p for p in glob.glob(os.path.join(folder, "*.png")) if os.path.getmtime(p) >= started - 0.05)
    with open(os.path.join(folder, FIGURES_DIGEST), "w") as f:
        f.write("inputs %s\n" % inputs)
        f.writelines("%s %s\n" % (file_digest(p), os.path.basename(p)) for p in drawn)


def draw_in_parallel(tasks):
    """Runs the figure functions in one forked process per core, each process taking the next task
    when it is free (the tasks' costs differ by 5x: dealing them out in turn left one process idle
    for a second); each figure is drawn whole by one process, so the files are those of a serial
    run. Exits with status 1 if any process failed."""
    n = max(1, min(len(os.sched_getaffinity(0)), len(tasks)))
    # The task numbers, one byte each, in a pipe: a read of one byte takes exactly one.
    todo, queue = os.pipe()
    os.write(queue, bytes(range(len(tasks))))
    os.close(queue)

    def work():
        while True:
            task = os.read(todo, 1)
            if not task:
                return
            tasks[task[0]]()

    children = []
    for _ in range(1, n):
        pid = os.fork()
        if pid == 0:
            status = 0
            try:
                work()
            except BaseException:  # noqa: B902 -- report it, then end the child without cleanup
                import traceback
                traceback.print_exc()
                status = 1
            sys.stderr.flush()
            os._exit(status)
        children.append(pid)
    failed = False
    try:
        work()
    finally:
        for pid in children:
            failed = os.waitpid(pid, 0)[1] != 0 or failed
    if failed:
        sys.exit(1)


if __name__ == "__main__":
    main()
