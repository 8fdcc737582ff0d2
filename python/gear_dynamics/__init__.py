"""gear_dynamics: the stochastic spur-gear model's C++ engine from Python.

The configuration is the package's own: the defaults of its config/ folder (gear_pair.yaml,
load.yaml, run.yaml), YAML files overlaid on them and single overrides in gear_run's --set form
("run.duration=0.1"). A value the package refuses raises ConfigError with the text gear_run
prints: the parameter, the value and the allowed range.

Functions
---------
config(files=(), set=(), mu=None, seed=None) -> dict
    The validated configuration in effect, as nested dicts.
simulate(files=(), set=(), mu=None, seed=None, realizations=2, deterministic=True, rate=1000.0)
    S1 and stochastic realizations into numpy arrays, bit for bit gear_run's numbers.
config_dir() -> str
    The folder the defaults are read from.
tooth_pair_stiffness(pinion_tooth=0, wheel_tooth=0, files=(), set=(), points=101) -> dict
    One tooth pair's stiffness by the potential-energy method along the line of action, a crack
    or spall of the configuration included (the mesh stiffness of a cracked tooth).
spectrum(x, sample_rate, segment=8192, overlap=0.5) -> dict
    Welch's one-sided power spectral density of a series, as gear_analyze computes it.
poincare_section(files=(), set=(), mu=None, transient=0.2) -> dict
    S1's Poincare section once per mesh period at mesh phase 0.
lyapunov(files=(), set=(), mu=None, duration=1.2, orthonormalise_every=100) -> dict
    S1's Lyapunov spectrum (lambda1, lambda2) and the Jacobian's mean trace.
read_batch(folders, series=False) -> Batch
    A Monte Carlo batch folder (or its shards) through the package's reader: runs and their
    statistics as numpy columns (Batch.frame() for a pandas DataFrame), series on request.

Units are SI throughout (m, m/s, m/s^2, s; d in m s^-1/2).
"""
import json as _json

import yaml as _yaml

from gear_dynamics._core import ConfigError, config_dir  # noqa: F401
from gear_dynamics import _core

__all__ = ["ConfigError", "BatchReadError", "config", "config_dir", "simulate", "Simulation", "spectrum", "tooth_pair_stiffness", "poincare_section", "lyapunov", "read_batch", "Batch"]


def _listed(value):
    """A tuple of strings from one string or an iterable of them."""
    if value is None:
        return []
    if isinstance(value, str):
        return [value]
    return [str(v) for v in value]


def _sets(set):
    """gear_run's --set strings from a list of "SECTION.KEY=VALUE" or a dict {"run.duration": 0.1}."""
    if isinstance(set, dict):
        # JSON is YAML: a float as its shortest round-trip text, a list as a flow sequence.
        return ["%s=%s" % (k, _json.dumps(v)) for k, v in set.items()]
    return _listed(set)


def config(files=(), set=(), mu=None, seed=None):
    """The validated model configuration (sections gear_pair, load, run) as nested dicts.

    files: YAML files overlaid on the defaults in order (gear_run --config).
    set: overrides, a list of "SECTION.KEY=VALUE" strings or a dict {"SECTION.KEY": value}
        (gear_run --set).
    mu: the friction coefficient (gear_run --mu); seed: run.seed (gear_run --seed).
    Raises ConfigError naming the parameter, the value and the allowed range.
    """
    return _yaml.safe_load(_core.config_text(_listed(files), _sets(set), mu, seed))


class Simulation(dict):
    """What simulate() returns: a dict with attribute access.

    names: run names, "S1" then "r0", "r1", ... (gear_run's CSV column run)
    t: sample times [s], shape (samples,)
    delta, delta_dot, phi, center_distance: shape (runs, samples): the dynamic transmission error
        [m], its rate [m/s], the load Phi [m/s^2] and the instantaneous centre distance d(t)
        over the trailing window [m s^-1/2]
    summary: per-run arrays (runs,): center_distance, delta_range, delta_dot_range,
        steady_state_time, steady_state_time_fine, reached_steady_state (0/1), final_delta,
        final_delta_dot, final_load
    seed, time_step, duration: of the configuration that ran
    """

    def __getattr__(self, name):
        try:
            return self[name]
        except KeyError:
            raise AttributeError(name) from None


def simulate(files=(), set=(), mu=None, seed=None, realizations=2, deterministic=True, rate=1000.0):
    """Runs S1 and stochastic realizations 0..realizations-1 as gear_run does; a Simulation.

    The arguments are gear_run's: files (--config), set (--set, strings or a dict), mu (--mu),
    seed (--seed), realizations (--realizations), deterministic (False: --no-deterministic) and
    rate, the sample rate of the series in simulated Hz (0: no series, the summary only). The
    numbers equal gear_run's CSV bit for bit for the same configuration and seed.

    The engine runs without the GIL; Ctrl-C (SIGINT) stops it within a few thousand steps and
    raises KeyboardInterrupt. Raises ConfigError for a value the package refuses, ValueError for
    a bad realizations or rate.
    """
    out = _core.simulate(_listed(files), _sets(set), mu, seed, int(realizations), bool(deterministic),
                         float(rate))
    return Simulation(out, summary=Simulation(out["summary"]))


def tooth_pair_stiffness(pinion_tooth=0, wheel_tooth=0, files=(), set=(), points=101, fillet_foundation=True):
    """The stiffness of pinion tooth `pinion_tooth` meshing with wheel tooth `wheel_tooth` by the
    potential-energy method (doc/model.md section 3) for the configured gear, its root crack
    (gear_pair.crack_*) and spall included, at `points` contact points evenly over the line of
    action [x_a, x_e].

    files, set: the configuration as for simulate(). fillet_foundation=False leaves out the
    fillet foundation's compliance (the known overestimate).
    Returns a dict: x [m] from C1 along the line of action, stiffness [N/m], the compliance terms
    hertz, bending, shear, axial, foundation [m/N] (pinion and wheel summed), x_a, x_e and
    base_pitch [m].
    """
    return _core.tooth_pair_stiffness(_listed(files), _sets(set), int(pinion_tooth), int(wheel_tooth), int(points),
                                      bool(fillet_foundation))


def spectrum(x, sample_rate, segment=8192, overlap=0.5):
    """Welch's one-sided power spectral density of the series `x` sampled at `sample_rate` [Hz]:
    periodic Hann segments of `segment` samples overlapping by the fraction `overlap`, each
    segment's mean removed (scipy.signal.welch's defaults with nperseg=segment).

    Returns a dict: frequency [Hz] (0 .. sample_rate/2), density [unit^2/Hz], resolution [Hz],
    enbw (the window's equivalent noise bandwidth) [Hz], segments. Raises ValueError when x is
    shorter than one segment or an option is out of range.
    """
    return _core.spectrum([float(v) for v in x], float(sample_rate), int(segment), float(overlap))


def poincare_section(files=(), set=(), mu=None, transient=0.2):
    """S1's Poincare section (doc/nonlinear-dynamics.md): (delta, delta_dot) once per mesh period
    at mesh phase 0, from `transient` [s] to run.duration, as gear_analyze poincare and the
    batch's /gear/poincare take it (interpolated between grid points unless on one).

    files, set, mu: the configuration as for simulate(). Returns a dict: t [s], delta [m],
    delta_dot [m/s], on_grid (0/1), mesh_period [s].
    """
    return _core.poincare(_listed(files), _sets(set), mu, float(transient))


def lyapunov(files=(), set=(), mu=None, duration=1.2, orthonormalise_every=100):
    """S1's Lyapunov spectrum over [0, duration] by QR of the tangent map (doc/nonlinear-dynamics.md),
    in gear_analyze's norm (delta in units of b, delta_dot of sqrt(2 Phi b)).

    Returns a dict: exponents (lambda1, lambda2) [1/s], trace (the time average of the Jacobian's
    trace, lambda1 + lambda2 by Liouville up to RK4's own dissipation) [1/s], and the running
    estimate of lambda1: time [s], running [1/s].
    """
    return _core.lyapunov(_listed(files), _sets(set), mu, float(duration), int(orthonormalise_every))


class Batch(dict):
    """What read_batch() returns: a dict with attribute access.

    runs: columns of the runs, one entry per usable bag: name, kind ("S1", "phase",
        "stochastic"), mu, index (realization or phase member), point (study point),
        center_distance [m s^-1/2], steady_state_time, steady_state_time_fine [s],
        reached_steady_state (0/1), final_delta [m], final_delta_dot [m/s], final_phi [m/s^2]
    snapshot_times (times,) [s]; snapshot_delta, snapshot_delta_dot (runs, times) [m], [m/s]
    series: {run name: {t, delta, delta_dot, phi}} of the runs asked for
    folders, expected_runs, skipped [(file, reason)], missing [run or note]
    axes, points: the study grid (axis 0 is gear_pair.friction_coefficient)
    config_text: the batch's model configuration as YAML
    """

    def __getattr__(self, name):
        try:
            return self[name]
        except KeyError:
            raise AttributeError(name) from None

    def frame(self):
        """The runs as a pandas DataFrame (needs pandas), one row per run."""
        import pandas
        return pandas.DataFrame(self["runs"])


def read_batch(folders, series=False):
    """Reads Monte Carlo batch folders (one or several shards of one batch) with the package's own
    reader: the manifests' checks, bags left out with their reason, runs missing.

    folders: a folder or a list of folders.
    series: False (none), True (every recorded run) or a list of run names: their /gear/state
        series into Batch.series.
    Raises BatchReadError (an OSError) when the batch cannot be read at all.
    """
    from gear_dynamics import _batch
    if isinstance(series, (bool, int)):
        all_series, names = bool(series), []
    else:
        all_series, names = False, _listed(series)
    out = _batch.read_batch(_listed(folders), all_series, names)
    return Batch(out, runs={k: v for k, v in out["runs"].items()})


def __getattr__(name):
    # BatchReadError from the ROS-side module, loaded only when asked for.
    if name == "BatchReadError":
        from gear_dynamics._batch import BatchReadError
        return BatchReadError
    raise AttributeError(name)
