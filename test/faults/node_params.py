#!/usr/bin/python3
"""Bad parameters through the nodes: each node is started with its config files' parameters, one
of them broken (missing, wrong type, NaN, +-inf, a misspelt key), and must exit non-zero, before
doing any work, with the key in its log. The keys come from the config files themselves, and a
node's own top-level keys (gear_aggregator's ~folders, ~wait_timeout, ...) from NODES.

By default every key is broken once, in one of the ways (rotating), through one node that reads it
(the model's keys alternate between gear_simulator and gear_monte_carlo); --slow breaks every key
in every way through every node that reads it.

And a SIGINT while a node starts (node_signal): it interrupts the node's parameter reads from the
master, which must not be taken for missing parameters (no FATAL; gear_simulator exits 0 as after
any Ctrl-C, gear_aggregator 1 with a warning that no report was written)."""
import concurrent.futures
import copy
import os
import signal
import subprocess
import tempfile
import time

import faultlib as fl

MODEL = ("gear_pair.yaml", "load.yaml", "run.yaml")
NODES = {  # executable: (config files, extra parameters)
    "gear_simulator": (MODEL + ("simulator.yaml",), {}),
    "gear_monte_carlo": (MODEL + ("monte_carlo.yaml",), {}),
    # Its own keys as aggregator.launch sets them (plot_script: no figures).
    "gear_aggregator": (("aggregator.yaml",), {"folders": "/nonexistent_batch", "report_folder": "",
                                               "wait_for_batch": False, "batch_node": "/gear_monte_carlo",
                                               "wait_timeout": 0, "series_mu": 0.04, "plot_script": "",
                                               "exit_when_done": True}),
}
# A node's own keys that are required; the others take their default when left out.
REQUIRED_OWN = {"folders"}
NODE_TIMEOUT = 30.0


def breakages(value):
    """(category, description, new value or None to remove) for a parameter's shipped value."""
    out = [("missing", "removed", None)]
    sample = value[0] if isinstance(value, list) and value else value
    if isinstance(sample, bool):
        bad = [("wrong_type", "a string", "maybe")]
    elif isinstance(sample, (int, float)):
        bad = [("wrong_type", "a string", "not_a_number"), ("nan", "NaN", float("nan")),
               ("inf", "+inf", float("inf")), ("inf", "-inf", float("-inf"))]
    else:
        bad = [("wrong_type", "a map", {"a": 1})]
    for category, what, v in bad:
        if isinstance(value, list) and value:
            out.append((category, "[0] = " + what, [v] + value[1:]))
        else:
            out.append((category, what, v))
    return out


def cases(slow):
    """(node, section, key, category, description, params) for every case to run."""
    out = []
    model_keys = [(s, k) for s, keys in fl.load_yaml(*[fl.config_file(f) for f in MODEL]).items() for k in keys]
    for node, (files, extra) in NODES.items():
        params = fl.load_yaml(*[fl.config_file(f) for f in files])
        params.update(extra)
        for section in [s for s in params if isinstance(params[s], dict)]:
            for i, key in enumerate(params[section]):
                if (section, key) in model_keys and not slow and \
                        ["gear_simulator", "gear_monte_carlo"][model_keys.index((section, key)) % 2] != node:
                    continue
                found = breakages(params[section][key])
                chosen = found if slow else [found[(len(out) + i) % len(found)]]
                for category, what, value in chosen:
                    p = copy.deepcopy(params)
                    if value is None:
                        del p[section][key]
                    else:
                        p[section][key] = value
                    out.append((node, section, key, category, what, p))
            p = copy.deepcopy(params)
            first = next(iter(p[section]))
            p[section][first + "x"] = p[section][first]
            out.append((node, section, first + "x", "unknown_key", "a misspelt key", p))
        # The node's own keys, "~key" in its log (section "~").
        own = [k for k in extra if not isinstance(params[k], dict)]
        for i, key in enumerate(own):
            found = [b for b in breakages(params[key]) if b[2] is not None or key in REQUIRED_OWN]
            chosen = found if slow else [found[(len(out) + i) % len(found)]]
            for category, what, value in chosen:
                p = copy.deepcopy(params)
                if value is None:
                    del p[key]
                else:
                    p[key] = value
                out.append((node, "~", key, category, what, p))
        if own:
            p = copy.deepcopy(params)
            p[own[0] + "x"] = p[own[0]]
            out.append((node, "~", own[0] + "x", "unknown_key", "a misspelt key", p))
    return out


def run(suite):
    with tempfile.TemporaryDirectory(prefix="gd_node_params_") as cwd:
        todo = cases(suite.args.slow)
        for node, section, key, category, what, params in todo:
            if node == "gear_monte_carlo" and key != "output_dir":
                params["monte_carlo"]["output_dir"] = os.path.join(cwd, "batch")  # never written: refused first

        def start(case):
            node, _, _, _, _, params = case
            return fl.run_node(node, fl.node_name(node), params, timeout=NODE_TIMEOUT)

        # A node that refuses its parameters spends its time registering with the master, not on a
        # core: several at once.
        with concurrent.futures.ThreadPoolExecutor(4) as pool:
            results = list(pool.map(start, todo))
        for (node, section, key, category, what, _), (code, out) in zip(todo, results):
            with suite.case("node_" + category, "%s__%s" % (node, key if section == "~" else section + "_" + key)):
                path = "~" + key if section == "~" else "%s.%s" % (section, key)
                assert code not in (0, None) and not fl.died_of_signal(code), \
                    "%s with %s = %s: exit %s (expected an error exit):\n%s" % (node, path, what, code, out[-3000:])
                assert path in out, "%s with %s = %s: the log does not name %s:\n%s" % (
                    node, path, what, path, out[-3000:])
        with suite.case("node_missing", "gear_monte_carlo__no_batch_folder_created"):
            assert not os.path.exists(os.path.join(cwd, "batch")), "a refused batch created its folder"
        startup_signals(suite, cwd)


def startup_signals(suite, cwd):
    """SIGINT 5-50 ms after start (about when the parameters are read here; the handler is set a few
    ms in: -SIGINT before it) and, for the aggregator, once while it waits for a batch that never comes."""
    for node, delays in (("gear_simulator", [0.005 + 0.005 * i for i in range(10)]),
                         ("gear_aggregator", [0.005 + 0.005 * i for i in range(10)] + [1.5])):
        files, extra = NODES[node]
        params = fl.load_yaml(*[fl.config_file(f) for f in files])
        params.update(extra)
        if node == "gear_aggregator":  # waits for ever on an empty folder unless stopped
            os.makedirs(os.path.join(cwd, "empty"), exist_ok=True)
            params.update({"folders": os.path.join(cwd, "empty"), "wait_for_batch": True, "wait_timeout": 0})
        stopped = 0 if node == "gear_simulator" else 1
        for delay in delays:
            with suite.case("node_signal", "%s__sigint_at_%.3fs" % (node, delay)):
                # As from a terminal: a test run started in the background (`cmd &` in a script)
                # inherits SIGINT ignored, and a SIGINT before the node's handler would be lost.
                p = fl.start_node(node, fl.node_name(node), params,
                                  preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
                time.sleep(delay)
                p.send_signal(signal.SIGINT)
                try:
                    out, _ = p.communicate(timeout=NODE_TIMEOUT)
                except subprocess.TimeoutExpired:
                    os.killpg(p.pid, signal.SIGKILL)
                    raise AssertionError("%s did not stop within %g s of SIGINT" % (node, NODE_TIMEOUT))
                assert p.returncode in (stopped, -signal.SIGINT), \
                    "%s: exit %s after SIGINT at %g s (expected %d):\n%s" % (node, p.returncode, delay, stopped, out[-3000:])
                assert "FATAL" not in out, "%s: SIGINT at %g s was reported as an error:\n%s" % (node, delay, out[-3000:])
                if p.returncode == 1:
                    assert "no report" in out, "%s: exit 1 without saying why:\n%s" % (node, out[-3000:])


if __name__ == "__main__":
    fl.main(run)
