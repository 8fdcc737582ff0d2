#!/usr/bin/env bash
# The shipped nonlinear-dynamics figures (doc/nonlinear-dynamics.md §8): bifurcation diagrams over
# pinion speed (250-3000 rpm) and mean load (50-5000 m/s^2, two decades) with the largest Lyapunov
# exponent along each, the Lyapunov exponents of S1 over the phase ensemble at h and h/2, the spectra,
# the Poincare section and safety over time. CSV and PNG into $1 (default ./nonlinear).
# Run in a sourced workspace (source scripts/setup.sh).
set -euo pipefail
OUT=${1:-nonlinear}
mkdir -p "$OUT"
PLOT="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)/plot_dynamics.py"
ga() { echo "+ gear_analyze $*"; rosrun gear_dynamics gear_analyze "$@"; }

ga bifurcation --parameter speed --from 250 --to 3000 --values 400 --duration 2 --transient 1 --output "$OUT/speed"
ga lyapunov --parameter speed --from 250 --to 3000 --values 100 --duration 2 --transient 1 --output "$OUT/speed_ly"
/usr/bin/python3 "$PLOT" bifurcation "$OUT/speed" --lyapunov "$OUT/speed_ly"

# The same speed range at 100x the paper's load (Phi0 = 2000 m/s^2), where the motion is periodic.
ga bifurcation --parameter speed --from 250 --to 3000 --values 400 --duration 2 --transient 1 \
   --set load.initial_mean=2000 --output "$OUT/speed_load2000"
ga lyapunov --parameter speed --from 250 --to 3000 --values 100 --duration 2 --transient 1 \
   --set load.initial_mean=2000 --output "$OUT/speed_load2000_ly"
/usr/bin/python3 "$PLOT" bifurcation "$OUT/speed_load2000" --lyapunov "$OUT/speed_load2000_ly"

ga bifurcation --parameter load --from 50 --to 5000 --values 400 --log --duration 2 --transient 1 --output "$OUT/load"
ga lyapunov --parameter load --from 50 --to 5000 --values 100 --log --duration 2 --transient 1 --output "$OUT/load_ly"
/usr/bin/python3 "$PLOT" bifurcation "$OUT/load" --lyapunov "$OUT/load_ly"

# Both exponents from the tangent flow over the start-up windows and the later regime, at h and h/2,
# and the two-trajectory cross-check at h.
windows=0,0.1,0.2,0.4,1,2,4
ga lyapunov --phases 64 --duration 4 --transient 1 --windows $windows --output "$OUT/lyapunov_h" --png
ga lyapunov --phases 64 --duration 4 --transient 1 --windows $windows --step-divisor 2 --output "$OUT/lyapunov_h2" --png
ga lyapunov --method pairs --phases 64 --duration 4 --transient 1 --output "$OUT/lyapunov_pairs_h"

ga spectrum --realizations 32 --set run.duration=1.0 --output "$OUT/spectrum" --png
ga spectrum --set load.initial_mean=5000 --set run.duration=1.0 --output "$OUT/spectrum_contact" --png
ga poincare --phases 64 --realizations 32 --output "$OUT/poincare" --png
ga safety --realizations 100 --output "$OUT/safety" --png
