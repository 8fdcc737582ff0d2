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
ensemble_statistics(files=(), set=(), mu=None, seed=None, realizations=100, rate=1000.0, ...)
    Streaming statistics over time of many realizations (quantiles, histograms, the safety
    probability) without keeping their paths; threads=, progress bar, Ctrl-C.
study(grid, files=(), set=(), ...) -> StudyResult
    The same over the grid of a study (any gear_pair/load keys), one EnsembleStatistics per point.
bifurcation(parameter, values, files=(), set=(), mu=None, duration=2.0, transient=1.0) -> list
    S1's Poincare points, period and regime per parameter value (gear_analyze bifurcation's core).
indicators(signal, shaft_angle, teeth, ...) -> dict
    Condition indicators (RMS, kurtosis, FM4, NA4, ...) per window of whole revolutions.
decompose(tsa, teeth, ...) -> dict; indicator_table() -> list
    A TSA's regular/residual/difference/envelope signals; the indicators' names and units.
read_reference(path) -> dict; assess(signal, shaft_angle, reference, ...) -> dict
    A healthy monitor reference file, and a signal's windows assessed against it (T2, CUSUM, health).
read_batch(folders, series=False) -> Batch
    A Monte Carlo batch folder (or its shards) through the package's reader: runs and their
    statistics as numpy columns (Batch.frame() for a pandas DataFrame), series on request.

Units are SI throughout (m, m/s, m/s^2, s; d in m s^-1/2).
"""
import json as _json

import yaml as _yaml

import math as _math

from gear_dynamics._core import ConfigError, ReferenceError, config_dir  # noqa: F401
from gear_dynamics import _core

__all__ = ["ConfigError", "ReferenceError", "BatchReadError", "ensemble_statistics", "EnsembleStatistics", "study",
           "StudyResult", "bifurcation", "indicators", "decompose", "indicator_table", "read_reference", "assess", "config", "config_dir", "simulate", "Simulation", "spectrum", "tooth_pair_stiffness", "poincare_section", "lyapunov", "read_batch", "Batch"]


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


class _Record(dict):
    """A dict whose keys read as attributes too (result.delta for result["delta"])."""

    def __getattr__(self, name):
        try:
            return self[name]
        except KeyError:
            raise AttributeError(name) from None


class Simulation(_Record):
    """What simulate() returns: a dict with attribute access.

    names: run names, "S1" then "r0", "r1", ... (gear_run's CSV column run)
    t: sample times [s], shape (samples,); shaft_angle: the pinion's angle theta1 there [rad]
    delta, delta_dot, phi, center_distance: shape (runs, samples): the dynamic transmission error
        [m], its rate [m/s], the load Phi [m/s^2] and the instantaneous centre distance d(t)
        over the trailing window [m s^-1/2]; with gear_pair.model: bearings, delta and delta_dot
        are the mesh deflection delta_m and its rate, and further (runs, samples) arrays give
        delta_t (the torsional coordinate) [m], mesh_force [N] and the bearing forces pinion_fx,
        pinion_fy, wheel_fx, wheel_fy [N] (x across the line of action, y along it)
    summary: per-run arrays (runs,): center_distance, delta_range, delta_dot_range,
        steady_state_time, steady_state_time_fine, reached_steady_state (0/1), final_delta,
        final_delta_dot, final_load
    seed, time_step, duration: of the configuration that ran
    """


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


def _progress_bar(progress, description):
    """A callback (done, total) drawing a tqdm bar, or None (progress False, or tqdm missing)."""
    if not progress:
        return None
    try:
        import tqdm
    except ImportError:
        return None
    bar = {}

    def update(done, total):
        if "bar" not in bar:
            bar["bar"] = tqdm.tqdm(total=total, desc=description, unit="step", unit_scale=True, leave=False)
        b = bar["bar"]
        b.update(done - b.n)
        if done >= total:
            b.close()
    return update


class EnsembleStatistics(_Record):
    """One grid point's streaming statistics (what ensemble_statistics() returns; a dict with
    attribute access). Over the recorded times t [s] of the stochastic realizations:

    grid: the point's grid values {key: value}
    delta, delta_dot, center_distance: dicts with edges (bins + 1,), counts (times, bins),
        outside (times, 2: below, above; NaN above) and quantiles (times, len(quantiles)): the
        k-th smallest value, k = max(1, ceil(p n)), placed in its bin by rank (within one bin
        width of the exact order statistic; NaN when it lies outside the bins)
    safety: joint, delta, delta_dot: probability (times,) that the state is inside the safe
        intervals, its Wilson interval low/high and count; realizations (times,)
    s1: S1's own path (delta, delta_dot, phi, center_distance over t) and summary
    summary: per-realization results (realizations,) as Simulation.summary
    """


class StudyResult(_Record):
    """What study() returns: axes (the grid's keys), points (an EnsembleStatistics per point, the
    first axis varying slowest), quantiles, and the run's seed, time_step, duration."""

    def frame(self):
        """Every realization's summary as a pandas DataFrame: one row per (point, realization), the
        grid's keys as columns beside the summary's."""
        import pandas
        frames = []
        for i, p in enumerate(self["points"]):
            f = pandas.DataFrame(p.summary)
            f.insert(0, "realization", range(len(f)))
            for k, v in reversed(list(p["grid"].items())):
                f.insert(0, k, v)
            f.insert(0, "point", i)
            frames.append(f)
        return pandas.concat(frames, ignore_index=True)


def _statistics(grid, files, set, mu, seed, realizations, rate, quantiles, delta_bins, delta_dot_bins,
                center_distance_bins, delta_interval, delta_dot_interval, threads, block_lanes, progress):
    sweep = _json.dumps({str(k): (list(v) if not isinstance(v, dict) else v) for k, v in grid.items()}) if grid else ""
    out = _core.ensemble_statistics(
        _listed(files), _sets(set), mu, seed, sweep, int(realizations), float(rate), int(threads or 0),
        int(block_lanes), [float(q) for q in quantiles], delta_bins, delta_dot_bins, list(center_distance_bins),
        delta_interval, delta_dot_interval, _progress_bar(progress, "gear_dynamics"))
    points = [EnsembleStatistics(p, delta=Simulation(p["delta"]), delta_dot=Simulation(p["delta_dot"]),
                                 center_distance=Simulation(p["center_distance"]),
                                 safety=Simulation({k: (Simulation(v) if isinstance(v, dict) else v)
                                                    for k, v in p["safety"].items()}),
                                 s1=Simulation(p["s1"]), summary=Simulation(p["summary"]))
              for p in out["points"]]
    return StudyResult(out, points=points)


_STATISTICS_DOC = """
    files, set, mu, seed: the configuration as for simulate(). realizations: 0..R-1 per point.
    rate: the recorded times [simulated Hz] (must divide the integration grid, as a batch's).
    quantiles: probabilities of the quantiles over time. delta_bins, delta_dot_bins,
    center_distance_bins: (lo, hi, width) [SI] of the histograms the quantiles come from (delta,
    delta_dot default to the aggregator's Figs. 11/12 bins). delta_interval, delta_dot_interval:
    the safe set (default: the aggregator's Table 4 intervals).
    threads: worker threads (None: all cores); block_lanes: realizations stepped together. The
    numbers are the same, bit for bit, whatever threads and block_lanes.
    progress: a tqdm bar while it runs (when tqdm is importable); False for none.

    Memory is that of the histograms (times x bins), not of the paths. The engine runs without
    the GIL; Ctrl-C stops it at the blocks' next recorded time and raises KeyboardInterrupt.
    Raises ConfigError for a value the package refuses, ValueError for a bad option.
"""


def ensemble_statistics(files=(), set=(), mu=None, seed=None, realizations=100, rate=1000.0,
                        quantiles=(0.05, 0.25, 0.5, 0.75, 0.95), delta_bins=None, delta_dot_bins=None,
                        center_distance_bins=(0.0, 4.0e-3, 1.0e-5), delta_interval=None, delta_dot_interval=None,
                        threads=None, block_lanes=32, progress=True):
    """Streaming statistics over time of S1 and `realizations` stochastic realizations, their
    paths folded into histograms as they are stepped (the Monte Carlo batch's runner); an
    EnsembleStatistics.
    """
    return _statistics({}, files, set, mu, seed, realizations, rate, quantiles, delta_bins, delta_dot_bins,
                       center_distance_bins, delta_interval, delta_dot_interval, threads, block_lanes,
                       progress).points[0]


ensemble_statistics.__doc__ += _STATISTICS_DOC


def study(grid, files=(), set=(), mu=None, seed=None, realizations=100, rate=1000.0,
          quantiles=(0.05, 0.25, 0.5, 0.75, 0.95), delta_bins=None, delta_dot_bins=None,
          center_distance_bins=(0.0, 4.0e-3, 1.0e-5), delta_interval=None, delta_dot_interval=None,
          threads=None, block_lanes=32, progress=True):
    """ensemble_statistics() at every point of a study grid (doc/studies.md), expanded and
    validated by the core's study machinery as a batch's monte_carlo.sweep; a StudyResult.

    grid: {key: values} over gear_pair.* and load.* keys: a list of values or a range
    {"from": a, "to": b, "count": n[, "scale": "log"]}; gear_pair.friction_coefficient is the
    friction axis. Points are the Cartesian product, the first axis varying slowest; they share
    run.* and the seed (common random numbers). StudyResult.frame() is a pandas DataFrame.
    """
    return _statistics(dict(grid), files, set, mu, seed, realizations, rate, quantiles, delta_bins, delta_dot_bins,
                       center_distance_bins, delta_interval, delta_dot_interval, threads, block_lanes, progress)


study.__doc__ += _STATISTICS_DOC


def bifurcation(parameter, values, files=(), set=(), mu=None, duration=2.0, transient=1.0, block_lanes=8,
                max_period=16, tolerance=1e-3):
    """A bifurcation scan of S1 (doc/nonlinear-dynamics.md section 5), the core function behind
    gear_analyze bifurcation: for each value of `parameter` ("speed" [rpm], "load" [m/s^2], "mu",
    "damping") a run of `duration` [s], the points before `transient` [s] dropped, and the
    Poincare points once per mesh period.

    Returns a list, one dict per value: value, period (smallest p <= max_period with
    x_{k+p} = x_k to `tolerance` times (b, v_ref); 0: none), regime ("period-1, no separation",
    ...), min_gap [m], min_delta [m], and the points t [s], delta [m], delta_dot [m/s].
    """
    return _core.bifurcation(_listed(files), _sets(set), mu, str(parameter), [float(v) for v in values],
                             float(duration), float(transient), int(block_lanes), int(max_period), float(tolerance))


def _array(x):
    import numpy
    return numpy.ascontiguousarray(x, dtype=float)


def indicators(signal, shaft_angle, teeth, revolution_angle=2 * _math.pi, load=None, revolutions=1,
               samples_per_revolution=640, shaft_orders=2, sideband_orders=1, envelope_band=0,
               baseline_residual_variance=float("nan")):
    """Condition indicators (doc/monitor.md) of a sampled signal per window of `revolutions` whole
    revolutions of the monitored gear, as the condition monitor computes them: the signal's
    time-synchronous average over the window (resampled by `shaft_angle` [rad] at
    `samples_per_revolution` points per `revolution_angle`, aligned to angle 0), decomposed by
    orders of a gear with `teeth` teeth, and every indicator of indicator_table().

    load: the load samples (their mean per window is reported); baseline_residual_variance: NA4*'s
    healthy variance (NaN: NA4* is NaN). A sample whose angle does not increase restarts the
    windows. Returns a dict of arrays, one value per window: each indicator by name, start_angle,
    mean_load, window; and restarts.
    """
    return _core.indicators(_array(signal), _array(shaft_angle), None if load is None else _array(load), int(teeth),
                            float(revolution_angle), int(revolutions), int(samples_per_revolution), int(shaft_orders),
                            int(sideband_orders), int(envelope_band), float(baseline_residual_variance))


def decompose(tsa, teeth, shaft_orders=2, sideband_orders=1, envelope_band=0):
    """The signals of one revolution's TSA (doc/monitor.md): regular (mesh harmonics), residual,
    difference, envelope, each as long as `tsa`, and amplitude, the single-sided amplitude of
    orders 0 .. len(tsa)/2; mesh_order = teeth."""
    return _core.decompose(_array(tsa), int(teeth), int(shaft_orders), int(sideband_orders), int(envelope_band))


def indicator_table():
    """The indicators the package computes, in order: a list of {name, unit, description}."""
    return _core.indicator_table()


def read_reference(path):
    """A healthy monitor reference file (gear_monitor_reference's output): its indicators, per load
    band the windows, mean, sd and thresholds, the CUSUM threshold. Raises ReferenceError (an
    OSError) naming the file and the reason when it cannot be read or breaks the schema."""
    return _core.read_reference(str(path))


def assess(signal, shaft_angle, reference, load=None, files=(), set=()):
    """A signal's windows assessed against the healthy reference file `reference`, as the condition
    monitor node does: the reference's window settings and gear revolution, indicators with the
    run's trends, Hotelling's T2, its normal score, the CUSUM and the health ("OK", "WARN",
    "ERROR") per window. With files or set, the reference is first checked against that gear
    (ReferenceError if it was made for another). Returns a dict of arrays, one value per window.
    """
    return _core.assess(_array(signal), _array(shaft_angle), None if load is None else _array(load), str(reference),
                        _listed(files), _sets(set))


class Batch(_Record):
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
