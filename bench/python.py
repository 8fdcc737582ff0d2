#!/usr/bin/python3
"""The Python module against the C++ tools: CPU time of gear_dynamics.simulate and of gear_run on
the same job (S1 + realizations, series at RATE or none), and wall time of read_batch against
rosbag's Python API reading the same bags' summaries and Poincare points.

usage: python.py [--duration T] [--realizations N] [--repeat K] [--batch FOLDER]"""
import argparse
import glob
import os
import resource
import statistics
import subprocess
import time
import warnings

import gear_dynamics as gd


def child_cpu(cmd):
    r0 = resource.getrusage(resource.RUSAGE_CHILDREN)
    subprocess.run(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, check=True)
    r1 = resource.getrusage(resource.RUSAGE_CHILDREN)
    return (r1.ru_utime - r0.ru_utime) + (r1.ru_stime - r0.ru_stime)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--duration", type=float, default=4.0, help="run.duration [s]")
    ap.add_argument("--realizations", type=int, default=63)
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--batch", help="a batch folder for read_batch against rosbag")
    a = ap.parse_args()
    gear = subprocess.check_output(["catkin_find", "--first-only", "gear_dynamics", "gear_run"], text=True).strip()
    sets = {"run.duration": a.duration, "run.window": min(0.05, a.duration)}
    gd.simulate(set={"run.duration": 0.01, "run.window": 0.01, "run.snapshot_times": []})  # first-call costs
    for rate in (0, 1000):
        cmd = [gear, "--realizations", str(a.realizations), "--rate", str(rate), "--output", os.devnull]
        for k, v in sets.items():
            cmd += ["--set", "%s=%r" % (k, v)]
        g, p = [], []
        for _ in range(a.repeat):
            g.append(child_cpu(cmd))
            t = time.process_time()
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                gd.simulate(set=sets, realizations=a.realizations, rate=rate)
            p.append(time.process_time() - t)
        print("rate %4g Hz: gear_run %.3f s CPU (min %.3f), simulate %.3f s CPU (min %.3f), ratio %.3f (min/min %.3f)"
              % (rate, statistics.median(g), min(g), statistics.median(p), min(p),
                 statistics.median(p) / statistics.median(g), min(p) / min(g)))
    if a.batch:
        import rosbag
        t = time.perf_counter()
        b = gd.read_batch(a.batch)
        t_gd = time.perf_counter() - t
        t = time.perf_counter()
        n = 0
        for path in sorted(glob.glob(os.path.join(a.batch, "*.bag"))):
            with rosbag.Bag(path) as bag:
                for _ in bag.read_messages(topics=["/gear/run_info", "/gear/summary", "/gear/poincare"]):
                    n += 1
        t_rb = time.perf_counter() - t
        print("batch of %d runs: read_batch %.2f s wall, rosbag Python API %.2f s wall (%d messages), ratio %.1f"
              % (len(b.runs["name"]), t_gd, t_rb, n, t_rb / t_gd))


if __name__ == "__main__":
    main()
