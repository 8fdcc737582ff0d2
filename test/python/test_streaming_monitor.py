"""Streaming ensemble statistics, study grids, the bifurcation scan and the condition indicators of
the Python module, against independent computations on held paths (simulate) and closed forms."""
import math
import os
import signal
import threading
import time

import numpy as np
import pytest

import gear_dynamics

pytestmark = pytest.mark.filterwarnings("ignore::UserWarning")  # the dropped snapshot times

SHORT = {"run.duration": 0.04, "run.window": 0.02}
BINS = dict(delta_bins=(-2e-4, 2e-4, 2e-6), delta_dot_bins=(-0.2, 0.2, 0.002),
            center_distance_bins=(0.0, 4e-3, 2e-5))


def bin_counts(x, spec):
    """numpy's histogram with the core's edges (numpy.linspace), and the values outside."""
    lo, hi, w = spec
    edges = np.linspace(lo, hi, int(round((hi - lo) / w)) + 1)
    counts, _ = np.histogram(x, edges)
    return counts, int(np.sum(x < lo)), int(np.sum(~(x <= hi)))


def test_streaming_statistics_equal_those_of_held_paths():
    held = gear_dynamics.simulate(set=SHORT, seed=5, realizations=24, deterministic=True, rate=1000.0)
    ps = (0.1, 0.5, 0.9)
    s = gear_dynamics.ensemble_statistics(set=SHORT, seed=5, realizations=24, rate=1000.0, quantiles=ps,
                                          progress=False, **BINS)
    assert np.array_equal(s.t, held.t)
    # S1's path and every realization's result are the engine's own numbers: bit for bit.
    assert np.array_equal(s.s1.delta, held.delta[0])
    assert np.array_equal(s.summary.center_distance, held.summary.center_distance[1:])
    for name, spec in (("delta", BINS["delta_bins"]), ("delta_dot", BINS["delta_dot_bins"]),
                       ("center_distance", BINS["center_distance_bins"])):
        paths = held[name][1:]
        stat = s[name]
        for j in range(len(s.t)):
            counts, below, above = bin_counts(paths[:, j], spec)
            assert np.array_equal(stat.counts[j], counts), (name, j)  # integer counts: exact
            assert list(stat.outside[j]) == [below, above]
            if below or above:
                continue
            x = np.sort(paths[:, j])
            for k, p in enumerate(ps):
                # The k-th order statistic lies in the bin the estimate is placed in: within one width.
                exact = x[max(1, math.ceil(p * len(x))) - 1]
                assert abs(stat.quantiles[j, k] - exact) <= spec[2], (name, j, p)
    lo, hi = s.safety.delta.count, None
    d_in = (held.delta[1:] >= 4.0e-5) & (held.delta[1:] <= 5.5e-5)  # the aggregator's Table 4 intervals
    v_in = np.abs(held.delta_dot[1:]) <= 0.016
    assert np.array_equal(lo, d_in.sum(axis=0))
    assert np.array_equal(s.safety.joint.count, (d_in & v_in).sum(axis=0))
    assert np.allclose(s.safety.joint.probability, (d_in & v_in).mean(axis=0), rtol=0, atol=1e-15)
    assert np.all(s.safety.joint.low <= s.safety.joint.probability + 1e-15)


def test_streaming_statistics_do_not_depend_on_threads_or_blocks():
    kw = dict(set=SHORT, seed=3, realizations=20, progress=False, **BINS)
    a = gear_dynamics.ensemble_statistics(threads=1, block_lanes=8, **kw)
    b = gear_dynamics.ensemble_statistics(threads=2, block_lanes=3, **kw)
    for name in ("delta", "delta_dot", "center_distance"):
        assert np.array_equal(a[name].counts, b[name].counts)
        assert np.array_equal(a[name].quantiles, b[name].quantiles, equal_nan=True)
    assert np.array_equal(a.safety.joint.count, b.safety.joint.count)
    assert np.array_equal(a.summary.center_distance, b.summary.center_distance)


def test_streaming_statistics_ctrl_c_raises_keyboard_interrupt_quickly():
    sent = []

    def interrupt():
        sent.append(time.monotonic())
        os.kill(os.getpid(), signal.SIGINT)

    timer = threading.Timer(0.5, interrupt)
    timer.start()
    with pytest.raises(KeyboardInterrupt):
        # Minutes of work: 1000 realizations of 20 s.
        gear_dynamics.ensemble_statistics(set={"run.duration": 20.0, "run.window": 0.05}, realizations=1000,
                                          rate=100.0, progress=False)
    late = time.monotonic() - sent[0]
    timer.join()
    # The main thread looks every 50 ms; the blocks stop at their next recorded time (1/100 s
    # simulated, 4000 steps of 32 lanes: tens of ms). 0.5 s leaves room for a loaded machine.
    assert late < 0.5, late


def test_progress_callback_is_called_and_can_be_turned_off(monkeypatch):
    calls = []
    monkeypatch.setattr(gear_dynamics, "_progress_bar", lambda progress, d: (lambda a, b: calls.append((a, b))) if progress else None)
    gear_dynamics.ensemble_statistics(set=SHORT, realizations=4, progress=True)
    assert calls and calls[-1][0] == calls[-1][1] > 0
    calls.clear()
    gear_dynamics.ensemble_statistics(set=SHORT, realizations=4, progress=False)
    assert calls == []


def test_study_grid_points_equal_single_runs():
    grid = {"load.sigma": [0.0, 20.0]}
    r = gear_dynamics.study(grid, set=SHORT, seed=2, realizations=6, progress=False)
    assert r.axes == ["gear_pair.friction_coefficient", "load.sigma"]
    assert [p.grid["load.sigma"] for p in r.points] == [0.0, 20.0]
    for p, sigma in zip(r.points, grid["load.sigma"]):
        one = gear_dynamics.simulate(set=dict(SHORT, **{"load.sigma": sigma}), seed=2, realizations=6, rate=0)
        assert np.array_equal(p.summary.center_distance, one.summary.center_distance[1:])
    # The noise changes the realizations: the grid really sets the key.
    assert not np.array_equal(r.points[0].summary.center_distance, r.points[1].summary.center_distance)
    with pytest.raises(gear_dynamics.ConfigError, match="load.sigma"):
        gear_dynamics.study({"load.sigma": [-1.0]}, set=SHORT, realizations=2, progress=False)


def test_study_frame_has_a_row_per_realization():
    pandas = pytest.importorskip("pandas")  # a declared test dependency (package.xml)
    r = gear_dynamics.study({"load.sigma": [0.0, 5.0]}, set=SHORT, realizations=3, progress=False)
    f = r.frame()
    assert isinstance(f, pandas.DataFrame) and len(f) == 6
    assert list(f["load.sigma"]) == [0.0] * 3 + [5.0] * 3


def test_bifurcation_matches_poincare_section():
    # One value of the load equal to the configuration's: the scan's points are S1's section.
    c = gear_dynamics.config()
    load = c["load"]["initial_mean"]
    r = gear_dynamics.bifurcation("load", [load], duration=0.3, transient=0.1)
    sec = gear_dynamics.poincare_section(set={"run.duration": 0.3}, transient=0.1)
    assert len(r) == 1 and r[0]["value"] == load
    keep = sec["t"] >= r[0]["t"][0] - 1e-12
    assert np.allclose(r[0]["delta"], sec["delta"][keep], rtol=0, atol=1e-12 * c["gear_pair"]["backlash"] / 1e-6)
    assert isinstance(r[0]["regime"], str) and r[0]["regime"]
    with pytest.raises(ValueError, match="transient"):
        gear_dynamics.bifurcation("load", [load], duration=0.3, transient=0.5)


def test_indicators_of_a_sine_and_decompose():
    # A pure mesh-order sine: kurtosis 1.5 and crest factor sqrt(2) in closed form, no residual.
    teeth, n = 20, 640
    theta = np.linspace(0, 3 * 2 * np.pi, 3 * n, endpoint=False)
    x = np.sin(teeth * theta)
    r = gear_dynamics.indicators(x, theta, teeth=teeth, samples_per_revolution=n)
    # A window completes once its last TSA point, (n - 1)/n of a revolution, is passed: 3 windows.
    assert len(r["kurtosis"]) == 3 and list(r["window"]) == [0, 1, 2]
    assert np.allclose(r["kurtosis"], 1.5, atol=1e-9)
    assert np.allclose(r["crest_factor"], np.sqrt(2), atol=1e-3)  # the TSA's grid hits the peak to 1e-3
    d = gear_dynamics.decompose(x[:n], teeth=teeth)
    assert np.allclose(d["regular"], x[:n], atol=1e-12) and np.max(np.abs(d["residual"])) < 1e-12
    assert abs(d["amplitude"][teeth] - 1.0) < 1e-12
    names = [i["name"] for i in gear_dynamics.indicator_table()]
    assert set(names) <= set(r) and "fm4" in names
    with pytest.raises(ValueError, match="same length"):
        gear_dynamics.indicators(x, theta[:-1], teeth=teeth)


def test_read_reference_refuses_a_bad_file(tmp_path):
    bad = tmp_path / "ref.yaml"
    bad.write_text("format: something_else\n")
    with pytest.raises(gear_dynamics.ReferenceError, match=str(bad)):
        gear_dynamics.read_reference(bad)


def test_assess_against_a_reference_of_gear_monitor_reference(tmp_path):
    import subprocess
    from test_gear_dynamics import gear_run_path
    tool = os.path.join(os.path.dirname(gear_run_path()), "gear_monitor_reference")
    ref = tmp_path / "ref.yaml"
    # 20 healthy windows: the smallest reference the tool accepts at a false-alarm rate of 0.25.
    subprocess.run([tool, "--output", str(ref), "--realizations", "20", "--false-alarm", "0.25", "--samples", "256"],
                   check=True, capture_output=True)
    r = gear_dynamics.read_reference(ref)
    assert r["indicators"] == [i["name"] for i in gear_dynamics.indicator_table()]
    assert r["monitor"]["samples_per_revolution"] == 256 and len(r["bands"]) == 1
    s = gear_dynamics.simulate(set={"run.duration": 0.2, "run.window": 0.05}, realizations=1, deterministic=False,
                               rate=40000.0)
    a = gear_dynamics.assess(s.delta[0], s.shaft_angle, ref, load=s.phi[0], set={"run.duration": 0.2})
    # The assessed windows' indicators are indicators() of the same windows with the reference's
    # settings and baseline (NA4*): the same tracker, so the same numbers.
    teeth = gear_dynamics.config()["gear_pair"]["pinion_teeth"]
    i = gear_dynamics.indicators(s.delta[0], s.shaft_angle, teeth=teeth, load=s.phi[0], samples_per_revolution=256,
                                 baseline_residual_variance=r["bands"][0]["baseline_residual_variance"])
    assert len(a["health"]) == len(i["rms"]) >= 2
    for name in r["indicators"]:
        assert np.array_equal(a[name], i[name], equal_nan=True), name
    assert set(a["health"]) <= {"OK", "WARN", "ERROR"} and np.all(np.isfinite(a["t2"]))
    # A reference made for another gear is refused, naming the key.
    with pytest.raises(gear_dynamics.ReferenceError, match="backlash"):
        gear_dynamics.assess(s.delta[0], s.shaft_angle, ref, set={"gear_pair.backlash": 3.3e-5})
