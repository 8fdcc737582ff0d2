#!/usr/bin/env python3
"""Streaming statistics against held paths: the quantiles over time of delta of R realizations
(0.1 s, series at 20 kHz) by gear_dynamics.ensemble_statistics (histograms, one thread) or by
simulate + numpy.quantile on the held paths. Prints the process's CPU time, wall time and peak RSS.

Usage: /usr/bin/python3 bench/python_streaming.py {stream|hold} REALIZATIONS
"""
import resource
import sys
import time
import warnings

import numpy as np

import gear_dynamics as gd

warnings.simplefilter("ignore")  # the default snapshot times after 0.1 s are dropped
mode, realizations = sys.argv[1], int(sys.argv[2])
config = {"run.duration": 0.1, "run.window": 0.05}
cpu, wall = time.process_time(), time.monotonic()
if mode == "stream":
    s = gd.ensemble_statistics(set=config, realizations=realizations, rate=20000.0, threads=1, progress=False)
    q = s.delta.quantiles
elif mode == "hold":
    s = gd.simulate(set=config, realizations=realizations, rate=20000.0)
    q = np.quantile(s.delta[1:], [0.05, 0.25, 0.5, 0.75, 0.95], axis=0)
else:
    sys.exit("mode must be stream or hold")
print("%s R=%d: CPU %.1f s, wall %.1f s, peak RSS %.0f MiB" % (
    mode, realizations, time.process_time() - cpu, time.monotonic() - wall,
    resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024))
