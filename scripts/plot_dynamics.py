#!/usr/bin/python3
"""Figures of gear_analyze's CSV files (doc/nonlinear-dynamics.md).

usage: plot_dynamics.py SUBCOMMAND PREFIX [--lyapunov LYAPUNOV_PREFIX]

SUBCOMMAND is the gear_analyze subcommand that wrote PREFIX_*.csv (spectrum, poincare, bifurcation,
lyapunov, safety, stiffness); the figures are written as PREFIX_<name>.png. Units on the axes: mm, mm/s, Hz, N.
For a bifurcation diagram, --lyapunov adds the exponent along the same parameter (from
`gear_analyze lyapunov --parameter ...`) as a second panel.
"""
import argparse
import csv
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402


def read(path):
    with open(path, newline="") as f:
        rows = list(csv.DictReader(f))
    if not rows:
        sys.exit(f"plot_dynamics: {path} is empty")
    return rows


def col(rows, key, kind=float):
    return np.array([kind(r[key]) for r in rows])


def save(fig, prefix, name):
    path = f"{prefix}_{name}.png"
    fig.savefig(path, dpi=130, bbox_inches="tight")
    plt.close(fig)
    print(f"wrote {path}")


def spectrum(prefix, _args):
    rows = read(prefix + "_psd.csv")
    info = read(prefix + "_spectrum_info.csv")[0]
    peaks = read(prefix + "_peaks.csv")
    fm = float(info["mesh_frequency"])
    f = col(rows, "frequency")
    ensemble = "delta_mean" in rows[0]
    fig, axes = plt.subplots(2, 1, figsize=(9, 7), sharex=True)
    for ax, var, unit, scale in ((axes[0], "delta", "mm$^2$/Hz", 1e6), (axes[1], "force", "N$^2$/Hz", 1.0)):
        sel = f > 0
        ax.semilogy(f[sel], col(rows, f"{var}_S1")[sel] * scale, lw=0.7, color="k", label="S1")
        if ensemble:
            ax.semilogy(f[sel], col(rows, f"{var}_mean")[sel] * scale, lw=0.9, color="C0",
                        label=f"mean of {info['realizations']} realizations")
            ax.fill_between(f[sel], col(rows, f"{var}_run_low")[sel] * scale, col(rows, f"{var}_run_high")[sel] * scale,
                            color="C0", alpha=0.2, lw=0, label="2.5-97.5 % of the realizations")
            lo = col(rows, f"{var}_mean_low")[sel] * scale
            ax.fill_between(f[sel], np.where(lo > 0, lo, np.nan), col(rows, f"{var}_mean_high")[sel] * scale,
                            color="C0", alpha=0.5, lw=0, label="95 % interval of the mean (where > 0)")
        for k in range(1, 11):
            ax.axvline(k * fm, color="C3", lw=0.5, ls=":", alpha=0.7)
        sidebands = prefix + "_sidebands.csv"
        if var == "force" and os.path.exists(sidebands):
            for sb in read(sidebands):
                if sb["line"] == "1":
                    ax.plot(float(sb["bin_frequency"]), float(sb["density"]), "o", mfc="none", color="C1", ms=6)
        series = f"{var}_mean" if ensemble else f"{var}_S1"
        for p in peaks:
            if p["series"] == series and p["is_harmonic"] == "0":
                ax.plot(float(p["frequency"]), float(p["density"]) * scale, "v", color="C2", ms=5)
        what = "$\\delta$" if var == "delta" else "mesh force"
        ax.set_ylabel(f"PSD of {what} [{unit}]")
        ax.legend(fontsize=7, loc="upper right")
    axes[1].set_xlabel("frequency [Hz]   (dotted: k f$_m$; triangles: largest other peaks; "
                       "circles: sidebands n f$_m$ + k f$_r$ of the faulty gear's rotation)")
    axes[1].set_xscale("log")
    axes[1].set_xlim(max(f[1], fm / 8), min(f[-1], 30000.0))
    axes[0].set_title(f"Welch PSD: Hann, segment {info['segment']} ({float(info['resolution']):.3g} Hz), "
                      f"overlap {info['overlap']}, {info['segments']} segments; f$_m$ = {fm:.4g} Hz", fontsize=9)
    save(fig, prefix, "spectrum")


def poincare(prefix, _args):
    rows = read(prefix + "_poincare.csv")
    sets = col(rows, "set", str)
    d = col(rows, "delta") * 1e3
    v = col(rows, "delta_dot") * 1e3
    fig, ax = plt.subplots(figsize=(7, 5.5))
    for name, color, size in (("stochastic", "C1", 2), ("phase", "C0", 2), ("S1", "k", 6)):
        sel = sets == name
        if sel.any():
            ax.plot(d[sel], v[sel], ".", ms=size, color=color, alpha=0.6 if name != "S1" else 1.0,
                    label={"S1": "S1", "phase": "phase ensemble", "stochastic": "stochastic realizations"}[name])
    ax.axvline(0.05, color="grey", lw=0.5, ls="--")
    ax.set_xlabel("$\\delta$ [mm]  (dashed: b)")
    ax.set_ylabel("$\\dot\\delta$ [mm/s]")
    ax.set_title("Poincaré section: once per mesh period at mesh phase 0", fontsize=9)
    ax.legend(fontsize=8)
    save(fig, prefix, "poincare")


def bifurcation(prefix, args):
    rows = read(prefix + "_bifurcation.csv")
    summary = read(prefix + "_bifurcation_summary.csv")
    param = summary[0]["parameter"]
    label = {"speed": "pinion speed [rpm]", "load": "$\\Phi_0$ [m/s$^2$]", "mu": "$\\mu$",
             "damping": "$\\zeta_{ref}$"}[param]
    x = col(rows, "value")
    d = col(rows, "delta") * 1e3
    v = col(rows, "delta_dot") * 1e3
    ly = read(args.lyapunov + "_lyapunov.csv") if args.lyapunov else None
    n = 3 if ly else 2
    fig, axes = plt.subplots(n, 1, figsize=(9, 3 * n), sharex=True)
    axes[0].plot(x, d, ",", color="k", alpha=0.5)
    axes[0].axhline(0.05, color="C3", lw=0.5, ls="--")
    axes[0].set_ylabel("$\\delta$ at mesh phase 0 [mm]")
    axes[1].plot(x, v, ",", color="k", alpha=0.5)
    axes[1].set_ylabel("$\\dot\\delta$ [mm/s]")
    # regime strip
    sx = col(summary, "value")
    reg = col(summary, "regime", str)
    colors = {"no separation": "C2", "single-sided impacts": "C0", "double-sided impacts": "C3"}
    periodic = np.array([r.startswith("period-") for r in reg])
    for ax in axes[:2]:
        top = ax.get_ylim()[1]
        for key, c in colors.items():
            sel = np.array([key in r for r in reg])
            if sel.any():
                ax.plot(sx[sel], np.full(sel.sum(), top), "|", color=c, ms=6, label=key)
        if periodic.any():
            ax.plot(sx[periodic], np.full(periodic.sum(), ax.get_ylim()[0]), "|", color="C1", ms=6,
                    label="periodic (bottom ticks)")
    axes[0].legend(fontsize=7, loc="lower left", title="contact (top ticks)", title_fontsize=7)
    if ly:
        lx = col(ly, param)
        axes[2].plot(lx, col(ly, "exponent"), ".-", color="C0", ms=3, lw=0.6)
        axes[2].axhline(0, color="grey", lw=0.5)
        axes[2].set_ylabel("largest Lyapunov exponent [1/s]")
    axes[-1].set_xlabel(label)
    if param == "load" and x.min() > 0 and x.max() / x.min() > 20:
        axes[-1].set_xscale("log")
    axes[0].set_title(f"Bifurcation diagram over {param}: {len(summary)} values, Poincaré points after the transient",
                      fontsize=9)
    save(fig, prefix, "bifurcation")


def lyapunov(prefix, _args):
    res = read(prefix + "_lyapunov.csv")
    run = read(prefix + "_lyapunov_running.csv")
    key = list(res[0].keys())[0]
    windows = read(prefix + "_lyapunov_windows.csv") if os.path.exists(prefix + "_lyapunov_windows.csv") else None
    fig, axes = plt.subplots(1, 3 if windows else 2, figsize=(16 if windows else 11, 4.2))
    ids = col(run, "id", int)
    t = col(run, "t")
    r = col(run, "running")
    for i in np.unique(ids):
        sel = ids == i
        axes[0].plot(t[sel], r[sel], lw=0.5, alpha=0.6)
    ex = col(res, "exponent")
    axes[0].axhline(np.median(ex), color="k", lw=1, ls="--", label=f"median {np.median(ex):.0f} 1/s")
    axes[0].set_xlabel("t [s]")
    axes[0].set_ylabel("running estimate [1/s]")
    axes[0].set_ylim(0, max(1.0, 2.5 * np.median(np.abs(ex))))
    axes[0].legend(fontsize=8)
    axes[0].set_title("convergence of the running estimate", fontsize=9)
    axes[1].plot(col(res, key), ex, "o", ms=3)
    axes[1].axhline(0, color="grey", lw=0.5)
    axes[1].set_xlabel("initial mesh phase $\\varphi_0$ [rad]" if key == "phase0" else key)
    axes[1].set_ylabel("largest Lyapunov exponent [1/s]")
    if windows:  # the tangent method: lambda1 per window, median and quartiles over the runs
        start, end, l1 = col(windows, "start"), col(windows, "end"), col(windows, "exponent")
        for a, b in sorted(set(zip(start.tolist(), end.tolist()))):
            x = l1[(start == a) & (end == b)]
            q1, med, q3 = np.percentile(x, [25, 50, 75])
            axes[2].plot([a, b], [med, med], color="C0", lw=2)
            axes[2].fill_between([a, b], [q1, q1], [q3, q3], color="C0", alpha=0.2, lw=0)
        axes[2].axhline(0, color="grey", lw=0.5)
        axes[2].set_xscale("symlog", linthresh=0.1)
        axes[2].set_xlim(left=0)
        axes[2].set_xlabel("window [s]")
        axes[2].set_ylabel("$\\lambda_1$ over the window [1/s]")
        axes[2].set_title("per window: median, quartiles over the runs", fontsize=9)
    save(fig, prefix, "lyapunov")


def safety(prefix, _args):
    s = read(prefix + "_safety.csv")
    km = read(prefix + "_safety_survival.csv")
    pdf = read(prefix + "_pdf.csv")
    fig, axes = plt.subplots(2, 2, figsize=(11, 8))
    t = col(s, "t")
    for key, c, lab in (("joint", "k", "$\\delta \\in I_\\delta \\wedge \\dot\\delta \\in I_v$"),
                        ("delta", "C0", "$\\delta \\in I_\\delta$"), ("velocity", "C1", "$\\dot\\delta \\in I_v$")):
        axes[0, 0].plot(t, col(s, key), color=c, lw=0.8, label=lab)
        axes[0, 0].fill_between(t, col(s, key + "_low"), col(s, key + "_high"), color=c, alpha=0.2, lw=0)
    axes[0, 0].set_xlabel("t [s]")
    axes[0, 0].set_ylabel("probability (95 % Wilson band)")
    axes[0, 0].legend(fontsize=8)
    kt = col(km, "t")
    axes[0, 1].step(kt, col(km, "survival"), where="post", color="k")
    axes[0, 1].fill_between(kt, col(km, "low"), col(km, "high"), step="post", color="k", alpha=0.2, lw=0)
    axes[0, 1].set_xlabel("t [s]")
    axes[0, 1].set_ylabel("Kaplan-Meier S(t): still in the safe set")
    axes[0, 1].set_ylim(0, 1.02)
    var = col(pdf, "variable", str)
    for ax, name, scale, unit in ((axes[1, 0], "delta", 1e3, "mm"), (axes[1, 1], "delta_dot", 1e3, "mm/s")):
        sel = var == name
        x = col(pdf, "x")[sel] * scale
        ax.step(x, col(pdf, "histogram")[sel] / scale, where="post", color="grey", label="histogram")
        bw = float(np.array([r["bandwidth"] for r in pdf])[sel][0]) * scale
        ax.plot(x, col(pdf, "kde")[sel] / scale, color="C3", label=f"Gaussian KDE, Silverman h = {bw:.3g} {unit}")
        sym = "$\\delta$" if name == "delta" else "$\\dot\\delta$"
        ax.set_xlabel(f"{sym} at T [{unit}]")
        ax.set_ylabel(f"density [1/{unit}]")
        ax.legend(fontsize=8)
    save(fig, prefix, "safety")


def stiffness(prefix, _args):
    rows = read(prefix + "_stiffness.csv")
    a = col(rows, "angle[rad]")
    k = col(rows, "stiffness[N/m]")
    fig, ax = plt.subplots(figsize=(10, 3.8))
    ax.plot(np.degrees(a), k / 1e8, lw=0.8, color="k")
    ax.set_xlabel("pinion angle $\\theta_1$ [deg] from the model's $\\theta_1$ = 0")
    ax.set_ylabel("mesh stiffness K [10$^8$ N/m]")
    ax.set_xlim(0, np.degrees(a[-1]))
    ax.grid(alpha=0.3)
    save(fig, prefix, "stiffness")


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("command", choices=["spectrum", "poincare", "bifurcation", "lyapunov", "safety", "stiffness"])
    ap.add_argument("prefix")
    ap.add_argument("--lyapunov", help="prefix of a lyapunov --parameter run to add to a bifurcation diagram")
    args = ap.parse_args()
    globals()[args.command](args.prefix, args)


if __name__ == "__main__":
    main()
