"""read_batch against the aggregator: a small batch made by gear_monte_carlo, read by the Python
module and by gear_aggregator, whose runs.csv must hold the same runs and numbers."""
import math
import os
import sys

import numpy as np
import pytest

import gear_dynamics

sys.path.insert(0, os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), "faults"))
import faultlib as fl  # noqa: E402

# 2 mu x (S1 + 3 realizations), short runs, every run's series recorded.
OVERLAY = {
    "run": {"duration": 0.05, "window": 0.02, "snapshot_times": [0.03, 0.05]},
    "monte_carlo": {"mu": [0.0, 0.04], "realizations": 3, "phase_ensemble": False, "record_rate": 2000.0,
                    "record_realizations": 3, "sparse_record_rate": 1000.0, "block_lanes": 2, "threads": 1},
}


# runs.csv's columns (the report's units) and read_batch's (SI) with the factor between them.
COLUMNS = [("mu", "mu", 1), ("index", "index", 1), ("d[mm*s^-1/2]", "center_distance", 1e3),
           ("t_ss[s]", "steady_state_time", 1), ("t_ss_fine[s]", "steady_state_time_fine", 1),
           ("reached_steady_state", "reached_steady_state", 1), ("delta_T[mm]", "final_delta", 1e3),
           ("delta_dot_T[mm/s]", "final_delta_dot", 1e3), ("phi_T[mm/s^2]", "final_phi", 1e3)]


@pytest.fixture(scope="module")
def batch(tmp_path_factory):
    folder = str(tmp_path_factory.mktemp("batch"))
    report = str(tmp_path_factory.mktemp("report"))
    p = fl.load_yaml(*[fl.config_file(f) for f in ("gear_pair.yaml", "load.yaml", "run.yaml", "monte_carlo.yaml")])
    for section, values in OVERLAY.items():
        p[section].update(values)
    p["monte_carlo"]["output_dir"] = folder
    with fl.Master():
        code, out = fl.run_node("gear_monte_carlo", fl.node_name("batch"), p, timeout=120)
        assert code == 0, out[-3000:]
        code, out, runs, _ = fl.run_aggregator(folder, report, OVERLAY["run"]["snapshot_times"])
        assert code == 0, out[-3000:]
    return folder, runs


def test_read_batch_equals_the_aggregators_runs_csv(batch):
    folder, report_runs = batch
    b = gear_dynamics.read_batch(folder)
    assert b.expected_runs == 8 and len(b.runs["name"]) == 8 and not b.skipped and not b.missing
    assert sorted(b.runs["name"]) == sorted(report_runs)
    for i, name in enumerate(b.runs["name"]):
        row = report_runs[name]
        assert row["kind"] == b.runs["kind"][i]
        for column, key, scale in COLUMNS:
            # runs.csv prints 10 significant digits: half a unit of the last is <= 5e-10 relative.
            assert math.isclose(b.runs[key][i] * scale, float(row[column]), rel_tol=1e-9, abs_tol=1e-12), \
                (name, column, row[column], b.runs[key][i])
    # Grid times n h, as the bags carry them (0.03 is 12000 h, 0.030000000000000002 in binary).
    np.testing.assert_allclose(b.snapshot_times, OVERLAY["run"]["snapshot_times"], rtol=1e-15)


def test_read_batch_series_on_request(batch):
    folder, _ = batch
    b = gear_dynamics.read_batch(folder, series=True)
    assert len(b.series) == 8  # every run recorded (record_realizations = realizations)
    b1 = gear_dynamics.read_batch(folder, series=["mu0.0400_S1"])
    assert list(b1.series) == ["mu0.0400_S1"]
    name, s = next(iter(b1.series.items()))
    np.testing.assert_array_equal(s["delta"], b.series[name]["delta"])
    i = list(b.runs["name"]).index(name)
    assert s["delta"][-1] == b.runs["final_delta"][i]  # the last sample is the state at T
    assert np.all(np.diff(s["t"]) > 0)


def test_read_batch_refusals(tmp_path):
    with pytest.raises(gear_dynamics.BatchReadError) as err:
        gear_dynamics.read_batch(str(tmp_path / "nowhere"))
    assert "nowhere" in str(err.value)
    with pytest.raises(gear_dynamics.BatchReadError) as err:
        gear_dynamics.read_batch(str(tmp_path))
    assert "manifest" in str(err.value)
