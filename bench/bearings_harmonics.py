#!/usr/bin/python3
"""RMS and mesh-harmonic amplitudes of a gear_run CSV of the bearings model (bench/README.md §14).

usage: bearings_harmonics.py CSV [--from 0.31] [--to 0.4] [--mesh-frequency 333.333...]
Per run: over [from, to) (a whole number of mesh periods, so that the harmonics fall on DFT bins),
the RMS about zero and about the mean, and the amplitudes of harmonics 1-4 of the mesh frequency,
of delta_m, F_m and the bearing forces of both bodies across (x) and along (y) the line of action."""
import argparse
import csv
import math

import numpy as np

COLUMNS = ["delta", "mesh_force", "pinion_fx", "pinion_fy", "wheel_fx", "wheel_fy"]


def main():
    p = argparse.ArgumentParser()
    p.add_argument("csv")
    p.add_argument("--from", dest="t0", type=float, default=0.31)
    p.add_argument("--to", dest="t1", type=float, default=0.4)
    p.add_argument("--mesh-frequency", type=float, default=104.71975511965977 / (2 * math.pi / 20))
    a = p.parse_args()
    runs = {}
    with open(a.csv) as f:
        for row in csv.DictReader(f):
            t = float(row["t"])
            if a.t0 <= t < a.t1:
                runs.setdefault(row["run"], []).append([t] + [float(row[c]) for c in COLUMNS])
    for name, rows in runs.items():
        x = np.array(rows)
        t = x[:, 0]
        print(f"{name}: {len(t)} samples over [{a.t0}, {a.t1}) s, mesh frequency {a.mesh_frequency:.3f} Hz")
        print("  quantity      mean          RMS           RMS-about-mean  |A1|          |A2|          |A3|          |A4|")
        for j, c in enumerate(COLUMNS):
            y = x[:, j + 1]
            amps = [2.0 * abs(np.mean(y * np.exp(-2j * math.pi * k * a.mesh_frequency * t))) for k in (1, 2, 3, 4)]
            label = "delta_m [m]" if c == "delta" else c + " [N]"
            print(f"  {label:<13} {np.mean(y):<13.6g} {math.sqrt(np.mean(y * y)):<13.6g} {np.std(y):<15.6g} "
                  + " ".join(f"{v:<13.6g}" for v in amps))


if __name__ == "__main__":
    main()
