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

Units are SI throughout (m, m/s, m/s^2, s; d in m s^-1/2).
"""
import json as _json

import yaml as _yaml

from gear_dynamics._core import ConfigError, config_dir  # noqa: F401
from gear_dynamics import _core

__all__ = ["ConfigError", "config", "config_dir", "simulate", "Simulation"]


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
