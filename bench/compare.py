#!/usr/bin/python3
"""Runs the four implementations on one workload, cross-checks them and prints the table.
Called by bench/run, which builds gear_bench first and passes its options on (--help)."""
import argparse
import json
import os
import subprocess
import sys
import tempfile

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
# Fields of the implementations' JSON that are arrays (Octave writes a 1-element one as a number).
ARRAYS = ("seconds", "cpu_seconds", "delta", "velocity", "check_delta", "check_velocity")


def measure(command, work):
    """Runs command; returns its peak resident memory [MiB]. GNU time forks it from a small
    process: a child spawned from this Python would inherit Python's high-water mark."""
    rss = os.path.join(work, "rss")
    if subprocess.run(["/usr/bin/time", "-f", "%M", "-o", rss] + command).returncode != 0:
        sys.exit(f"bench: {' '.join(command)} failed")
    return int(open(rss).read().split()[-1]) / 1024.0  # KiB


def sd_standard_error(x):
    """Standard error of the sample sd without assuming normality: Var(s^2) ~ (m4 - s^4) / n."""
    m2, m4 = np.mean((x - x.mean()) ** 2), np.mean((x - x.mean()) ** 4)
    return np.sqrt(max(m4 - m2 * m2, 0.0) / len(x)) / (2.0 * np.sqrt(m2))


def agree_in_distribution(a, b, z=4.0):
    """Means and sds of a and b agree within z combined standard errors."""
    se_mean = np.hypot(a.std(ddof=1) / np.sqrt(len(a)), b.std(ddof=1) / np.sqrt(len(b)))
    se_sd = np.hypot(sd_standard_error(a), sd_standard_error(b))
    return (abs(a.mean() - b.mean()) <= z * se_mean and
            abs(a.std(ddof=1) - b.std(ddof=1)) <= z * se_sd)


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("gear_bench", help="path of the built gear_bench")
    parser.add_argument("--realizations", type=int, default=64)
    parser.add_argument("--duration", type=float, default=0.05, help="simulated time [s]")
    parser.add_argument("--check-duration", type=float, default=0.02,
                        help="deterministic run compared path by path [s]; keep it well before "
                             "the chaotic separation (~0.1 s)")
    parser.add_argument("--block", type=int, default=32,
                        help="lanes per engine block: 64 realizations make one block per thread")
    parser.add_argument("--skip-octave", action="store_true")
    parser.add_argument("--numpy-ratios", default="64,512,4096", metavar="R,R,...",
                        help="also time the engine (1 and 2 threads) and numpy at these realization "
                             "counts (same duration) and print the ratios; empty: none "
                             "(default %(default)s)")
    args = parser.parse_args()
    ratio_counts = [int(r) for r in args.numpy_ratios.split(",") if r.strip()]

    load = os.getloadavg()[0]
    with tempfile.TemporaryDirectory(prefix="gear_bench.") as work:
        results = run_all(args, work)
        ratios = [run_ratio(args, r, results, work) for r in ratio_counts]
    report(args, results, load, ratios)


def steps_per_second(data):
    """Realization-steps per second of the best (shortest wall time) repetition."""
    return data["realizations"] * data["steps"] / data["seconds"].min()


def run_ratio(args, realizations, results, work):
    """(R, engine 2T, engine 1T, numpy) in realization-steps/s; the main table's runs when R matches."""
    if realizations == args.realizations:
        return (realizations, steps_per_second(results[0][2]), steps_per_second(results[1][2]), steps_per_second(results[3][2]))
    workload = ["--realizations", str(realizations), "--duration", str(args.duration),
                "--check-duration", "0.001", "--check-every", "0.001"]
    out = os.path.join(work, f"ratio-{realizations}.json")
    rates = []
    for threads, repeat in ((2, 10), (1, 5)):
        print(f"bench: engine at R = {realizations}, {threads} thread(s), {repeat} run(s) ...", file=sys.stderr,
              flush=True)
        measure([args.gear_bench, "engine", "--block", str(args.block), "--threads", str(threads),
                 "--repeat", str(repeat), "--output", out] + workload, work)
        rates.append(steps_per_second({k: np.atleast_1d(v) if k in ARRAYS else v for k, v in json.load(open(out)).items()}))
    params = os.path.join(work, "params.json")
    repeat = 3 if realizations <= 512 else 1
    print(f"bench: numpy at R = {realizations}, {repeat} run(s) ...", file=sys.stderr, flush=True)
    measure([os.path.join(HERE, "gear_numpy.py"), params, out, "--repeat", str(repeat)] + workload, work)
    rates.append(steps_per_second({k: np.atleast_1d(v) if k in ARRAYS else v for k, v in json.load(open(out)).items()}))
    return (realizations, *rates)


def print_ratios(ratios):
    if not ratios:
        return
    print("\nthe engine against numpy by realization count (best wall time of each; numpy gains with R):\n")
    print("| realizations | engine 2T [steps/s] | engine 1T [steps/s] | numpy [steps/s] | engine 2T / numpy "
          "| engine 1T / numpy |")
    print("|--------------|---------------------|---------------------|-----------------|-------------------"
          "|-------------------|")
    for r, two, one, numpy in ratios:
        print(f"| {r:12d} | {two:19.3e} | {one:19.3e} | {numpy:15.3e} | {two / numpy:17.1f} | {one / numpy:17.1f} |")


def run_all(args, work):
    params = os.path.join(work, "params.json")
    measure([args.gear_bench, "params", "--output", params], work)
    workload = ["--realizations", str(args.realizations), "--duration", str(args.duration),
                "--check-duration", str(args.check_duration), "--check-every", "0.001"]
    engine = [args.gear_bench, "engine", "--block", str(args.block)] + workload
    # (label, threads, repetitions, command(output, repetitions)); the best repetition counts.
    runs = [("engine (run_batch, SIMD lanes)", 2, 20,
             lambda out, k: engine + ["--threads", "2", "--repeat", str(k), "--output", out]),
            ("engine (run_batch, SIMD lanes)", 1, 10,
             lambda out, k: engine + ["--threads", "1", "--repeat", str(k), "--output", out]),
            ("plain scalar C++ loop", 1, 5,
             lambda out, k: [args.gear_bench, "scalar", "--repeat", str(k), "--output", out] + workload),
            ("numpy, vectorised", 1, 3,
             lambda out, k: [os.path.join(HERE, "gear_numpy.py"), params, out, "--repeat", str(k)]
             + workload)]
    if not args.skip_octave:
        runs.append(("Octave, vectorised", 1, 1, lambda out, k: [
            "octave-cli", "--norc", "--no-history", "--quiet", "--path", HERE, "--eval",
            f"gear_octave('{params}', '{out}', {args.realizations}, {args.duration}, "
            f"{args.check_duration}, 0.001, {k})"]))

    results = []
    for label, threads, repeat, command in runs:
        out = os.path.join(work, f"{len(results)}.json")
        print(f"bench: {label}, {threads} thread(s), {repeat} run(s) ...", file=sys.stderr, flush=True)
        rss = measure(command(out, repeat), work)
        data = {k: np.atleast_1d(np.asarray(v, dtype=float)) if k in ARRAYS else v
                for k, v in json.load(open(out)).items()}
        results.append((label, threads, data, rss))
    return results


def report(args, results, load_before, ratios):
    reference = results[0][2]
    rate_ref = steps_per_second(reference)
    cpus = os.cpu_count()
    h_us = 1e6 * args.duration / reference['steps']
    print(f"\nworkload: {args.realizations} realizations x {args.duration} s = "
          f"{args.realizations * reference['steps']:.3g} realization-steps of h = {h_us:.3g} us, mu and load "
          f"from config/, engine blocks of {args.block} lanes; {cpus} CPUs, load average "
          f"{load_before:.2f} before, {os.getloadavg()[0]:.2f} after")
    if load_before > 0.25 * cpus:
        print("warning: the machine was busy: other processes' time slices inflate the timings, "
              "unevenly across rows; rerun on an idle machine")
    print()
    # CPU / wall of the best run: about the thread count when nothing else ran.
    print(f"| {'implementation':30s} | threads | best wall time [s] (of n) | CPU/wall "
          f"| realization-steps/s | engine(2T) is x faster | peak RSS [MiB] |")
    print(f"|{'-' * 32}|---------|---------------------------|----------|---------------------|"
          f"------------------------|----------------|")
    for label, threads, data, rss in results:
        best = int(np.argmin(data["seconds"]))
        wall = data["seconds"][best]
        rate = data["realizations"] * data["steps"] / wall
        print(f"| {label:30s} | {threads:7d} | {wall:12.4f} ({len(data['seconds']):2d}){'':7s} "
              f"| {data['cpu_seconds'][best] / wall:8.2f} | {rate:19.3e} | {rate_ref / rate:22.1f} "
              f"| {rss:14.1f} |")

    print(f"\ncross-checks against the engine at 2 threads:")
    ok = True
    for label, threads, data, _ in results[1:]:
        checks = []
        # Deterministic S1, path by path up to --check-duration: relative to the largest value.
        for key in ("check_delta", "check_velocity"):
            a, b = reference[key], data[key]
            err = np.max(np.abs(a - b)) / np.max(np.abs(a)) if a.shape == b.shape else np.inf
            checks.append((f"S1 {key[6:]} rel. error {err:.1e} <= 1e-9", err <= 1e-9))
        # End states of the stochastic runs: in distribution (independent RNGs for numpy/Octave).
        for key in ("delta", "velocity"):
            a, b = reference[key], data[key]
            same = a.shape == b.shape and np.array_equal(a, b)
            checks.append((f"{key}(T) mean/sd within 4 SE" + (" (identical paths)" if same else ""),
                           agree_in_distribution(a, b)))
        ok &= all(passed for _, passed in checks)
        print(f"  {label} ({threads}T): " + "; ".join(
            f"{text} {'ok' if passed else 'FAILED'}" for text, passed in checks))
    print(f"\nend state, engine: delta(T) = {1e3 * reference['delta'].mean():.5f} +- "
          f"{1e3 * reference['delta'].std(ddof=1):.5f} mm, delta_dot(T) = "
          f"{1e3 * reference['velocity'].mean():.3f} +- {1e3 * reference['velocity'].std(ddof=1):.3f}"
          f" mm/s (mean +- sd over realizations)")
    print_ratios(ratios)
    sys.exit(0 if ok else 1)


if __name__ == "__main__":
    main()
