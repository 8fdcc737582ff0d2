"""gear_analyze spectrum --signal: a bearing force's PSD against scipy's Welch of the same samples
written by gear_run (an independent implementation), zero across the line of action without
friction, and the refusals naming the allowed outputs."""
import csv
import os
import subprocess

import numpy as np
import pytest

import gear_dynamics
import scipy.signal

from test_gear_dynamics import gear_run_path, read_csv

# The bearings model in contact (1 kN), friction reversing at the pitch point: the force across the
# line of action is a mesh-frequency square wave of +-mu F_m (doc/bearings_friction.md section 3).
SETS = ["gear_pair.model=bearings", "load.initial_mean=20000", "gear_pair.friction_direction=reversing",
        "run.duration=0.2", "run.window=0.05", "run.snapshot_times=[0.2]"]
TRANSIENT = 0.05  # [s]


def sets(extra=()):
    return sum((["--set", s] for s in list(SETS) + list(extra)), [])


def analyze(tmp_path, args):
    tool = os.path.join(os.path.dirname(gear_run_path()), "gear_analyze")
    prefix = str(tmp_path / "spectrum")
    proc = subprocess.run([tool, "spectrum"] + args + ["--output", prefix], capture_output=True, text=True)
    return proc, prefix


def read_rows(path):
    with open(path) as f:
        return list(csv.DictReader(f))


def test_bearing_force_psd_is_scipy_welch_of_gear_runs_samples(tmp_path):
    proc, prefix = analyze(tmp_path, sets() + ["--transient", repr(TRANSIENT), "--signal", "pinion_fx"])
    assert proc.returncode == 0, proc.stderr
    psd = read_rows(prefix + "_psd.csv")
    info = read_rows(prefix + "_spectrum_info.csv")[0]
    fs, segment = float(info["sample_rate"]), int(info["segment"])
    # gear_run samples the same grid steps (every 10 us from t = 0; the transient ends on one).
    run = subprocess.run([gear_run_path(), "--realizations", "0", "--rate", repr(fs), "--output",
                          str(tmp_path / "run.csv")] + sets(), capture_output=True, text=True)
    assert run.returncode == 0, run.stderr
    s1 = read_csv(tmp_path / "run.csv")["S1"]
    x = s1["pinion_fx"][s1["t"] >= TRANSIENT - 1e-9]
    f, p = scipy.signal.welch(x, fs=fs, window="hann", nperseg=segment, noverlap=segment // 2,
                              detrend="constant", scaling="density")
    got = np.array([float(r["pinion_fx_S1"]) for r in psd])
    np.testing.assert_allclose([float(r["frequency"]) for r in psd], f, rtol=1e-12)
    # Two FFTs of the same doubles: rounding, relative to the spectrum's peak.
    np.testing.assert_allclose(got, p, rtol=1e-9, atol=1e-9 * p.max())
    # The friction force reverses once per mesh period: its first harmonic is a marked line.
    peaks = read_rows(prefix + "_peaks.csv")
    first = [r for r in peaks if r["series"] == "pinion_fx_S1" and r["harmonic"] == "1" and r["is_harmonic"] == "1"]
    assert first, "no line at the mesh frequency in the pinion's x force"


def test_no_force_across_the_line_of_action_without_friction(tmp_path):
    proc, prefix = analyze(tmp_path, sets(["gear_pair.friction_coefficient=0"]) +
                           ["--transient", repr(TRANSIENT), "--signal", "wheel_fx"])
    assert proc.returncode == 0, proc.stderr
    assert all(float(r["wheel_fx_S1"]) == 0.0 for r in read_rows(prefix + "_psd.csv"))


def test_signal_refusals_name_the_allowed_outputs(tmp_path):
    proc, _ = analyze(tmp_path, ["--signal", "pinion_fx", "--duration", "0.2"])
    assert proc.returncode != 0
    assert "--signal pinion_fx is not an output of the torsional model" in proc.stderr
    assert "allowed: mesh_force" in proc.stderr
    proc, _ = analyze(tmp_path, sets() + ["--signal", "pinion_f"])
    assert proc.returncode != 0
    assert "allowed: mesh_force, delta_t, pinion_fx, pinion_fy, wheel_fx, wheel_fy" in proc.stderr


def test_poincare_of_the_bearings_model_samples_its_mesh_deflection(tmp_path):
    """The section of S1 at mesh phase 0 is gear_run's (delta_m, delta_m_dot) and, with --signal,
    its bearing force at those grid times, bit for bit; the torsional model's section there differs
    (the bodies move on their bearings)."""
    tool = os.path.join(os.path.dirname(gear_run_path()), "gear_analyze")
    sections = {}
    for model, signal in (("bearings", "pinion_fy"), ("torsional", "mesh_force")):
        prefix = str(tmp_path / model)
        proc = subprocess.run([tool, "poincare", "--set", "gear_pair.model=" + model, "--set", "load.initial_mean=20000",
                               "--duration", "0.06", "--transient", "0.02", "--phases", "1", "--signal", signal,
                               "--output", prefix], capture_output=True, text=True)
        assert proc.returncode == 0, proc.stderr
        sections[model] = [r for r in read_rows(prefix + "_poincare.csv") if r["set"] == "S1"]
    run = subprocess.run([gear_run_path(), "--realizations", "0", "--rate", "1000", "--output", str(tmp_path / "run.csv"),
                          "--set", "gear_pair.model=bearings", "--set", "load.initial_mean=20000",
                          "--set", "run.duration=0.06", "--set", "run.window=0.01", "--set", "run.snapshot_times=[0.06]"],
                         capture_output=True, text=True)
    assert run.returncode == 0, run.stderr
    s1 = read_csv(tmp_path / "run.csv")["S1"]
    assert len(sections["bearings"]) >= 10
    for p in sections["bearings"]:
        assert p["on_grid"] == "1"
        i = int(np.argmin(np.abs(s1["t"] - float(p["t"]))))
        assert abs(s1["t"][i] - float(p["t"])) < 1e-9
        assert float(p["delta"]) == s1["delta"][i] and float(p["delta_dot"]) == s1["delta_dot"][i], p
        assert float(p["pinion_fy"]) == s1["pinion_fy"][i], p
    assert [p["delta"] for p in sections["bearings"]] != [p["delta"] for p in sections["torsional"]]
    # The torsional model's mesh force at its points, computed here from (delta, delta_dot) in
    # contact: F = K (delta - b) + alpha |delta - b| delta_dot with the paper's mesh at 1000 rpm.
    assert all(float(p["mesh_force"]) > 0 for p in sections["torsional"])


def test_poincare_signal_of_a_phase_member_converges_to_its_grid_value(tmp_path):
    """Phase member 1 of 7 reaches mesh phase 0 at 6/7 T_m + k T_m: off the grid at h = 2.5 us,
    where its ten-component state is interpolated inside the step; on the grid at h = T_m / 1197,
    exact. Mesh phase 0 is a stiffness switch, where the accelerations jump, so the interpolated
    rates, and with them the bearing force k_b y + c y_dot, are first-order accurate only
    (doc/nonlinear-dynamics.md section 3): measured 0.21 N and 0.14 N from the grid value at
    h = 2.5 and 1.25 us, of 1003 N. Asserted: within 3e-4 of the force, and closer at h / 2."""
    tool = os.path.join(os.path.dirname(gear_run_path()), "gear_analyze")

    def member_1(h):
        prefix = str(tmp_path / ("h" + h))
        proc = subprocess.run([tool, "poincare", "--set", "gear_pair.model=bearings", "--set", "load.initial_mean=20000",
                               "--set", "run.time_step=" + h, "--duration", "0.03", "--transient", "0.02", "--phases", "7",
                               "--signal", "pinion_fy", "--output", prefix], capture_output=True, text=True)
        assert proc.returncode == 0, proc.stderr
        assert "period 1 (of the whole state)" in proc.stdout
        rows = [r for r in read_rows(prefix + "_poincare.csv") if r["run"] == "1"]
        assert rows
        return rows

    exact = member_1(repr(3e-3 / 1197))
    assert all(r["on_grid"] == "1" for r in exact)
    errors = []
    for h in ("2.5e-6", "1.25e-6"):
        rows = member_1(h)
        assert all(r["on_grid"] == "0" for r in rows)
        assert [float(r["t"]) for r in rows] == pytest.approx([float(r["t"]) for r in exact], abs=1e-15)
        errors.append(max(abs(float(a["pinion_fy"]) - float(b["pinion_fy"])) for a, b in zip(rows, exact)))
    assert errors[0] < 3e-4 * 1003, errors
    assert errors[1] < 0.8 * errors[0], errors


def test_poincare_signal_refusals(tmp_path):
    tool = os.path.join(os.path.dirname(gear_run_path()), "gear_analyze")
    proc = subprocess.run([tool, "poincare", "--duration", "0.01", "--signal", "wheel_fx", "--output",
                           str(tmp_path / "p")], capture_output=True, text=True)
    assert proc.returncode != 0
    assert "--signal wheel_fx is not an output of the torsional model" in proc.stderr


def largest_exponent(tmp_path, sets_):
    tool = os.path.join(os.path.dirname(gear_run_path()), "gear_analyze")
    prefix = str(tmp_path / "lyapunov")
    proc = subprocess.run([tool, "lyapunov", "--method", "pairs", "--phases", "1", "--duration", "0.5", "--transient",
                           "0.1", "--set", "load.initial_mean=20000", "--output", prefix] +
                          sum((["--set", s] for s in sets_), []), capture_output=True, text=True)
    assert proc.returncode == 0, proc.stderr
    return float(read_rows(prefix + "_lyapunov.csv")[0]["exponent"])


def test_largest_exponent_of_the_bearings_state_tends_to_the_torsional_one(tmp_path):
    """In contact (1 kN) the orbit is periodic and damped: every exponent is negative. The bearings
    model's largest, of its whole ten-state state, is its slowest-decaying mode's: a bearing mode
    on soft bearings (about zeta_b sqrt(k_b / m_wheel): -399 1/s at 1e8 N/m), the mesh's as the
    bearings stiffen, so it tends to the torsional model's exponent (-6277 1/s measured; within
    0.7 % at 1e11 N/m, 2 % asserted; at 1e10 N/m a bearing mode still decays slower, -3994 1/s)."""
    torsional = largest_exponent(tmp_path, [])
    soft = largest_exponent(tmp_path, ["gear_pair.model=bearings", "gear_pair.friction_coefficient=0"])
    stiffer = largest_exponent(tmp_path, ["gear_pair.model=bearings", "gear_pair.bearing_stiffness=1e10"])
    rigid = largest_exponent(tmp_path, ["gear_pair.model=bearings", "gear_pair.bearing_stiffness=1e11"])
    assert torsional < soft < 0 and torsional < stiffer < 0
    # Without friction the wheel's motion across the line of action is a lone damped oscillator on
    # its bearing, decaying at zeta_b sqrt(k_b / m_wheel) (m_wheel = rho pi r2^2 L): no slower than it.
    m_wheel = 7800.0 * np.pi * 0.08 ** 2 * 0.01
    assert soft >= -0.05 * np.sqrt(1e8 / m_wheel) * 1.0001
    assert abs(rigid - torsional) < 0.02 * abs(torsional)
    assert abs(stiffer - torsional) > abs(rigid - torsional)


def test_tangent_lyapunov_of_the_bearings_model(tmp_path):
    """The tangent flow of the bearings model's ten-component state, from the tool and from Python:
    ten exponents whose sum is the mean trace of the Jacobian to RK4's accuracy (under 1e-4 of it at
    h = 2.5 us, 3.3e-5 measured), and in contact at 1 kN a damped orbit (lambda1 < 0)."""
    tool = os.path.join(os.path.dirname(gear_run_path()), "gear_analyze")
    sets_ = ["gear_pair.model=bearings", "load.initial_mean=20000"]
    prefix = str(tmp_path / "tangent")
    proc = subprocess.run([tool, "lyapunov", "--phases", "1", "--duration", "0.2", "--transient", "0.1", "--output",
                           prefix] + sum((["--set", s] for s in sets_), []), capture_output=True, text=True)
    assert proc.returncode == 0, proc.stderr
    assert "sum of the 10 exponents - mean trace" in proc.stdout
    row = read_rows(prefix + "_lyapunov.csv")[0]
    assert float(row["exponent"]) < 0
    assert abs(float(row["liouville_error"])) < 1e-4 * abs(float(row["trace"]))
    r = gear_dynamics.lyapunov(set=sets_, duration=0.2)
    assert len(r["exponents"]) == 10
    assert abs(sum(r["exponents"]) - r["trace"]) < 1e-4 * abs(r["trace"])


def bifurcation(tmp_path, sets_, args):
    tool = os.path.join(os.path.dirname(gear_run_path()), "gear_analyze")
    prefix = str(tmp_path / "bifurcation")
    proc = subprocess.run([tool, "bifurcation"] + args + ["--output", prefix] + sum((["--set", s] for s in sets_), []),
                          capture_output=True, text=True)
    assert proc.returncode == 0, proc.stderr
    return read_rows(prefix + "_bifurcation.csv"), read_rows(prefix + "_bifurcation_summary.csv")


def test_bifurcation_of_the_bearings_model(tmp_path):
    """The scan's points of the bearings model are its Poincare section's (delta_m, delta_m_dot),
    bit for bit; at the paper's light load its regime follows the bearings as doc/bearings_friction.md
    section 1 found from the batches: the rattle ends on damped bearings (zeta_b = 0.05, 1e8 N/m),
    survives undamped ones, and on near-rigid bearings (1e11 N/m) is the torsional model's regime."""
    points, summary = bifurcation(tmp_path, ["gear_pair.model=bearings"],
                                  ["--parameter", "load", "--values", "1", "--from", "20000", "--to", "20000",
                                   "--duration", "0.06", "--transient", "0.02"])
    assert summary[0]["regime"] == "period-1, no separation"
    tool = os.path.join(os.path.dirname(gear_run_path()), "gear_analyze")
    prefix = str(tmp_path / "section")
    proc = subprocess.run([tool, "poincare", "--set", "gear_pair.model=bearings", "--set", "load.initial_mean=20000",
                           "--duration", "0.06", "--transient", "0.02", "--phases", "1", "--output", prefix],
                          capture_output=True, text=True)
    assert proc.returncode == 0, proc.stderr
    section = read_rows(prefix + "_poincare.csv")
    assert len(points) == len(section) >= 10
    for p, q in zip(points, section):
        assert (p["t"], p["delta"], p["delta_dot"]) == (q["t"], q["delta"], q["delta_dot"])

    def regime(sets_):
        return bifurcation(tmp_path, sets_, ["--parameter", "load", "--values", "1", "--from", "20", "--to", "20",
                                             "--duration", "0.3", "--transient", "0.2"])[1][0]["regime"]

    torsional = regime([])
    assert torsional == "aperiodic, single-sided impacts"
    assert regime(["gear_pair.model=bearings"]) == "period-1, no separation"
    assert regime(["gear_pair.model=bearings", "gear_pair.bearing_damping_ratio=0"]) == torsional
    assert regime(["gear_pair.model=bearings", "gear_pair.bearing_stiffness=1e11"]) == torsional
