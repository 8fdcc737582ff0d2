"""The Python module gear_dynamics against the C++ tools: gear_run's CSV bit for bit, gear_run's
refusal text, Ctrl-C, the GIL and memory over many calls."""
import csv
import os
import signal
import subprocess
import threading
import time
import warnings

import numpy as np
import pytest

import gear_dynamics
from gear_dynamics import _core


def gear_run_path():
    """gear_run beside the module: <prefix>/lib/python3/dist-packages/gear_dynamics/_core*.so ->
    <prefix>/lib/gear_dynamics/gear_run (devel space and install alike)."""
    lib = os.path.dirname(os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(_core.__file__)))))
    path = os.path.join(lib, "gear_dynamics", "gear_run")
    assert os.access(path, os.X_OK), path
    return path


def run_gear_run(args, tmp_path):
    out = tmp_path / "run.csv"
    proc = subprocess.run([gear_run_path(), "--output", str(out)] + args, capture_output=True, text=True)
    return proc, out


def read_csv(path):
    """gear_run's CSV as {run: {column: array}}; its 17 significant digits read back exactly."""
    runs = {}
    with open(path) as f:
        for row in csv.DictReader(f):
            cols = runs.setdefault(row["run"], {})
            for k, v in row.items():
                if k != "run":
                    cols.setdefault(k, []).append(float(v))
    return {r: {k: np.array(v) for k, v in cols.items()} for r, cols in runs.items()}


@pytest.mark.parametrize("sets,mu,seed,realizations,rate", [
    (["run.duration=0.02", "run.window=0.01"], None, 7, 3, 1000.0),
    (["run.duration=0.01", "run.window=0.004", "load.sigma=20"], 0.1, 123, 5, 20000.0),
    # The bearings model: its every output, gear_run's extra columns, the same bits.
    (["run.duration=0.01", "run.window=0.004", "gear_pair.model=bearings", "gear_pair.friction_direction=reversing"],
     0.04, 11, 3, 20000.0),
])
def test_simulate_equals_gear_run_bit_for_bit(tmp_path, sets, mu, seed, realizations, rate):
    args = sum((["--set", s] for s in sets), []) + ["--seed", str(seed), "--realizations", str(realizations),
                                                    "--rate", repr(rate)]
    if mu is not None:
        args += ["--mu", repr(mu)]
    proc, out = run_gear_run(args, tmp_path)
    assert proc.returncode == 0, proc.stderr
    ref = read_csv(out)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the dropped snapshot times, as gear_run's notice
        sim = gear_dynamics.simulate(set=sets, mu=mu, seed=seed, realizations=realizations, rate=rate)
    assert sim.names == list(ref)
    for i, name in enumerate(sim.names):
        # Exact equality: the same engine, the same doubles (printed with 17 digits, read back exactly).
        np.testing.assert_array_equal(sim.t, ref[name]["t"])
        np.testing.assert_array_equal(sim.delta[i], ref[name]["delta"])
        np.testing.assert_array_equal(sim.delta_dot[i], ref[name]["delta_dot"])
        np.testing.assert_array_equal(sim.phi[i], ref[name]["phi"])
        np.testing.assert_array_equal(sim.center_distance[i], ref[name]["center_distance"])
        for column in ("delta_t", "mesh_force", "pinion_fx", "pinion_fy", "wheel_fx", "wheel_fy"):
            if column in ref[name]:
                np.testing.assert_array_equal(sim[column][i], ref[name][column], err_msg=column)
    # The last sample is t = T: the summary's final state is the series' last value.
    np.testing.assert_array_equal(sim.summary.final_delta, sim.delta[:, -1])
    assert sim.t[-1] == pytest.approx(sim.duration, abs=0.5e-9)


def test_realization_does_not_depend_on_its_neighbours():
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        one = gear_dynamics.simulate(set={"run.duration": 0.01, "run.window": 0.01}, realizations=1, deterministic=False)
        four = gear_dynamics.simulate(set={"run.duration": 0.01, "run.window": 0.01}, realizations=4)
    np.testing.assert_array_equal(one.delta[0], four.delta[1])  # r0 alone and after S1 in a block of 5


@pytest.mark.parametrize("override", ["load.sigma=-1", "load.sigmaa=1", "gear_pair.friction_coefficient=0.5",
                                      "run.time_step=0"])
def test_refusal_text_equals_gear_run(tmp_path, override):
    proc, _ = run_gear_run(["--set", override], tmp_path)
    assert proc.returncode == 1
    with pytest.raises(gear_dynamics.ConfigError) as err:
        gear_dynamics.config(set=[override])
    assert proc.stderr.strip() == "gear_run: " + str(err.value).strip()
    key = override.split("=")[0]
    assert key in str(err.value)
    with pytest.raises(ValueError):  # ConfigError is a ValueError
        gear_dynamics.simulate(set=[override])


def test_config_reads_overrides_and_files(tmp_path):
    overlay = tmp_path / "o.yaml"
    overlay.write_text("load:\n  sigma: 2.5\n")
    c = gear_dynamics.config(files=[str(overlay)], set={"load.drift": 3.0}, mu=0.07, seed=11)
    assert c["load"]["sigma"] == 2.5 and c["load"]["drift"] == 3.0
    assert c["gear_pair"]["friction_coefficient"] == 0.07 and c["run"]["seed"] == 11


def test_ctrl_c_raises_keyboard_interrupt_quickly():
    # A run of minutes: 200 s simulated, 16 lanes, no series.
    sent = []

    def interrupt():
        sent.append(time.monotonic())
        os.kill(os.getpid(), signal.SIGINT)

    timer = threading.Timer(0.5, interrupt)
    timer.start()
    with pytest.raises(KeyboardInterrupt):
        gear_dynamics.simulate(set={"run.duration": 200.0, "run.window": 0.05}, realizations=15, rate=0)
    late = time.monotonic() - sent[0]
    timer.join()
    # The engine comes back every 2000 steps (well under 10 ms of CPU for 16 lanes); 0.5 s leaves
    # room for a loaded machine.
    assert late < 0.5, late


def test_gil_released_while_the_engine_runs():
    count = [0]
    stop = threading.Event()

    def spin():
        while not stop.is_set():
            count[0] += 1

    th = threading.Thread(target=spin)
    th.start()
    try:
        start = time.monotonic()
        gear_dynamics.simulate(set={"run.duration": 10.0, "run.window": 0.05}, realizations=7, rate=0)
        elapsed = time.monotonic() - start
    finally:
        stop.set()
        th.join()
    # With the GIL held for the whole run the thread would not count at all; with it released,
    # it counts through the run (millions of increments per second, thousands at the least).
    assert elapsed > 0.05 and count[0] > 1000, (elapsed, count[0])


def rss_kib():
    with open("/proc/self/status") as f:
        for line in f:
            if line.startswith("VmRSS:"):
                return int(line.split()[1])
    raise RuntimeError("no VmRSS")


@pytest.mark.filterwarnings("ignore::UserWarning")  # the dropped snapshot times
def test_no_memory_growth_over_many_calls():
    kw = dict(set={"run.duration": 0.01, "run.window": 0.005}, realizations=3, rate=20000.0)
    for _ in range(20):  # warm-up: allocator pools, the first imports
        gear_dynamics.simulate(**kw)
        try:
            gear_dynamics.config(set=["load.sigma=-1"])
        except gear_dynamics.ConfigError:
            pass
    before = rss_kib()
    for _ in range(500):
        s = gear_dynamics.simulate(**kw)
        try:
            gear_dynamics.config(set=["load.sigma=-1"])
        except gear_dynamics.ConfigError:
            pass
    growth = rss_kib() - before
    # One call's arrays are 4 x 4 x 201 doubles (26 KiB): 500 leaked calls would add > 12 MiB;
    # 4 MiB allows the allocator's own slack.
    assert growth < 4096, growth
    assert s.delta.shape == (4, 201)


def test_tooth_pair_stiffness_hertz_and_crack():
    healthy = gear_dynamics.tooth_pair_stiffness(points=41)
    c = gear_dynamics.config()["gear_pair"]
    # Hertz's compliance of two steel teeth (Yang & Lin): 4 (1 - nu^2) / (pi E L), the same at every x.
    hertz = 4 * (1 - c["poisson_ratio"] ** 2) / (np.pi * c["youngs_modulus"] * c["face_width"])
    np.testing.assert_allclose(healthy["hertz"], hertz, rtol=1e-14)
    terms = sum(healthy[k] for k in ("hertz", "bending", "shear", "axial", "foundation"))
    np.testing.assert_allclose(1 / terms, healthy["stiffness"], rtol=1e-14)  # the terms in series
    assert healthy["x"][0] == healthy["x_a"] and healthy["x"][-1] == pytest.approx(healthy["x_e"], rel=1e-15)
    crack = {"gear_pair.mesh_stiffness": "potential_energy", "gear_pair.crack_gear": "pinion"}
    shallow = gear_dynamics.tooth_pair_stiffness(points=41, set=dict(crack, **{"gear_pair.crack_depth": 0.5e-3}))
    deep = gear_dynamics.tooth_pair_stiffness(points=41, set=dict(crack, **{"gear_pair.crack_depth": 1.5e-3}))
    # A crack takes section from the tooth: the pair is softer everywhere, the deeper crack more so;
    # the Hertz term does not see it.
    assert np.all(shallow["stiffness"] < healthy["stiffness"]) and np.all(deep["stiffness"] < shallow["stiffness"])
    np.testing.assert_array_equal(deep["hertz"], healthy["hertz"])
    # Another tooth of the pinion is not cracked.
    other = gear_dynamics.tooth_pair_stiffness(points=41, pinion_tooth=1, set=dict(crack, **{"gear_pair.crack_depth": 1.5e-3}))
    np.testing.assert_array_equal(other["stiffness"], healthy["stiffness"])


def test_spectrum_equals_scipy_welch():
    from scipy import signal
    rng = np.random.default_rng(3)
    fs = 10000.0
    t = np.arange(20000) / fs
    x = np.sin(2 * np.pi * 440.0 * t) + 0.1 * rng.standard_normal(t.size) + 2.0
    p = gear_dynamics.spectrum(x, fs, segment=1024, overlap=0.5)
    f, d = signal.welch(x, fs, window="hann", nperseg=1024, noverlap=512, detrend="constant", scaling="density")
    np.testing.assert_allclose(p["frequency"], f, rtol=1e-15)
    # Two FFTs of the same segments (kissfft, pocketfft): rounding only, 1e-9 of the peak.
    np.testing.assert_allclose(p["density"], d, rtol=1e-9, atol=1e-9 * d.max())
    assert abs(f[np.argmax(p["density"])] - 440.0) <= fs / 1024
    with pytest.raises(ValueError):
        gear_dynamics.spectrum(x[:100], fs, segment=1024)


def test_poincare_section_matches_simulate():
    # S1 at mesh phase 0: at the grid points of the section, the state equals simulate's S1 there
    # (GearLanes steps with the Ensemble's arithmetic, bit for bit for a lane without noise).
    cfg = {"run.duration": 0.05, "run.window": 0.05, "run.snapshot_times": []}
    sec = gear_dynamics.poincare_section(set=cfg, transient=0.0)
    sim = gear_dynamics.simulate(set=cfg, realizations=0, rate=400000.0)  # every grid step
    assert len(sec["t"]) > 0
    np.testing.assert_allclose(np.diff(sec["t"]), sec["mesh_period"], rtol=1e-9)
    on = sec["on_grid"] == 1
    idx = np.rint(sec["t"][on] / sim.time_step).astype(int)
    np.testing.assert_array_equal(sec["delta"][on], sim.delta[0][idx])
    # Off the grid: interpolated between the neighbouring grid states, so within their range.
    for t, d in zip(sec["t"][~on], sec["delta"][~on]):
        i = int(t / sim.time_step)
        lo, hi = sorted((sim.delta[0][i], sim.delta[0][i + 1]))
        assert lo - 1e-12 <= d <= hi + 1e-12


def test_lyapunov_exponents_sum_to_the_mean_trace():
    r = gear_dynamics.lyapunov(duration=0.2)
    c = gear_dynamics.config()
    assert c["run"]["time_step"] == 2.5e-6
    # Liouville up to RK4's dissipation, at most omega_max^6 h^5 / 72 = 0.13 1/s at h = 2.5 us
    # (test/core/dynamics/test_lyapunov.cpp derives the bound).
    assert abs(sum(r["exponents"]) - r["trace"]) <= 0.13
    assert r["trace"] < 0 and r["exponents"][0] >= r["exponents"][1]
    assert len(r["running"]) == len(r["time"]) > 0
