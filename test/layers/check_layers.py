#!/usr/bin/python3
"""The core's layering, checked on the source tree against a declared graph (LAYERS): each core layer
(include/gear_dynamics/<layer>/ and src/<layer>/) includes only headers of its own layer and of the
layers it depends on, directly or through others, and no ROS header (roscpp, rosbag, messages,
dynamic_reconfigure, the package's generated message headers). Each core library's CMake links
must be edges of the same graph, and every folder under include/gear_dynamics/ and src/ must be a
declared layer or one of the ROS-side folders. The core's tests follow their layer's rule (TEST_EXTRA,
TEST_ANY).

usage: check_layers.py JUNIT_XML"""
import os
import re
import sys

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
from junit_cases import run_cases  # noqa: E402

# The core's layers and what each depends on directly (a DAG). A layer may include its own headers
# and those of every layer it reaches; siblings (live, montecarlo, dynamics, analysis) may not
# include each other. maths (statistics, spectra) sits beside model at the bottom, so that live
# and the analysis both use it; batch is the batch folder's contract (manifest, run records) that
# the batch runner writes to and the analysis reads from; report writes every file of the report.
LAYERS = {
    "maths": [],
    "model": [],
    "engine": ["model"],
    "config": ["engine", "maths"],
    "batch": ["config"],
    "live": ["config", "maths"],
    "montecarlo": ["batch"],
    "dynamics": ["config", "maths"],
    "analysis": ["batch", "maths"],
    "report": ["analysis"],
    # The condition monitor's core: indicators on maths, the healthy reference on config's model.
    "monitor": ["config", "maths"],
}
# Folders above the core, allowed ROS: the ROS libraries, the nodes' mains and the CLIs.
OUTSIDE = {"ros", "nodes", "tools"}
ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
INCLUDE = re.compile(r'^\s*#\s*include\s*[<"]([^>"]+)[>"]', re.M)
# Headers that mean ROS: the ROS client libraries and message packages, and the package's own
# generated message and dynamic_reconfigure headers (gear_dynamics/Name.h).
ROS_HEADER = re.compile(r"^(ros|rosbag|roscpp|std_msgs|std_srvs|rosgraph_msgs|geometry_msgs|diagnostic_msgs|diagnostic_updater|"
                        r"dynamic_reconfigure|xmlrpcpp|message_filters)/|^gear_dynamics/[A-Z]\w*\.h$")


def reachable(layer, graph=None):
    """`layer` and every layer it depends on, directly or not; ValueError on a cycle or an
    undeclared dependency."""
    graph = LAYERS if graph is None else graph
    seen, path = [], []

    def visit(node):
        if node in path:
            raise ValueError(f"the layer graph has a cycle: {' -> '.join(path + [node])}")
        if node not in graph:
            raise ValueError(f"layer '{node}' is not declared (declared: {', '.join(graph)})")
        if node in seen:
            return
        path.append(node)
        for below in graph[node]:
            visit(below)
        path.pop()
        seen.append(node)

    visit(layer)
    return seen


def violations(layer, text, graph=None, any_layer=False):
    """The offending includes of one file of `layer`, each with the reason (with any_layer, only
    ROS headers and undeclared layers)."""
    graph = LAYERS if graph is None else graph
    allowed = list(graph) if any_layer else reachable(layer, graph)
    out = []
    for header in INCLUDE.findall(text):
        if ROS_HEADER.search(header):
            out.append(f"{header}: a ROS header in the ROS-free core")
        elif header.startswith("gear_dynamics/"):
            parts = header.split("/")
            other = parts[1] if len(parts) > 2 else "(top level)"
            if other not in graph:
                out.append(f"{header}: '{other}' is not a declared core layer (from '{layer}')")
            elif other not in allowed:
                out.append(f"{header}: layer '{other}' is not below '{layer}' (allowed: {', '.join(sorted(allowed))})")
    return out


# The core's tests (test/core/<layer>/test_<unit>.cpp) follow their layer's rule, plus the one
# header that reads the shipped configuration files the cases are pinned on (the paper's gear is a
# configuration). Tests of layers that must agree with each other are in test/core/integration/,
# which may include any core layer; test/core/support/ holds the tests' helpers.
TEST_EXTRA = {"gear_dynamics/config/config.hpp"}
TEST_ANY = "integration"
TEST_HELPERS = "support"


def test_violations(layer, text, graph=None):
    """The offending includes of one core test file of `layer`."""
    if layer == TEST_ANY:
        return violations(layer, text, graph, any_layer=True)
    stripped = "\n".join(line for line in text.splitlines()
                          if not any(line.strip().endswith(f'"{h}"') for h in TEST_EXTRA))
    return violations(layer, stripped, graph)


def test_files():
    """(layer folder, path) of every core test source."""
    base = os.path.join(ROOT, "test", "core")
    for folder in sorted(os.listdir(base)):
        for dirpath, _, names in os.walk(os.path.join(base, folder)):
            for n in sorted(names):
                if n.endswith((".hpp", ".cpp", ".h")):
                    yield folder, os.path.join(dirpath, n)


def check_tests():
    problems = []
    for folder, path in test_files():
        if folder == TEST_HELPERS:
            continue
        if folder not in LAYERS and folder != TEST_ANY:
            problems.append(f"{os.path.relpath(path, ROOT)}: test/core/{folder} is not a layer (nor {TEST_ANY})")
            continue
        with open(path, encoding="utf-8") as f:
            problems += [f"{os.path.relpath(path, ROOT)}: {v}" for v in test_violations(folder, f.read())]
    return problems


def link_violations(cmake_text, graph=None):
    """Links of a core library (target_link_libraries(${PROJECT_NAME}_<layer> ...)) to another
    layer's library that the graph does not declare as a direct dependency."""
    graph = LAYERS if graph is None else graph
    out = []
    for layer, args in re.findall(r"target_link_libraries\(\$\{PROJECT_NAME\}_(\w+)\s([^)]*)\)", cmake_text):
        if layer not in graph:
            continue
        for other in re.findall(r"\$\{PROJECT_NAME\}_(\w+)", args):
            if other in OUTSIDE or other not in graph:
                out.append(f"gear_dynamics_{layer} links gear_dynamics_{other}, which is not a core layer")
            elif other not in graph[layer]:
                out.append(f"gear_dynamics_{layer} links gear_dynamics_{other}: not a declared dependency "
                           f"(declared: {', '.join(graph[layer]) or 'none'})")
    return out


def undeclared_folders():
    """Folders of include/gear_dynamics/ and src/ that are neither a declared layer nor outside the core."""
    out = []
    for base in (os.path.join(ROOT, "include", "gear_dynamics"), os.path.join(ROOT, "src")):
        for name in sorted(os.listdir(base)):
            if os.path.isdir(os.path.join(base, name)) and name not in LAYERS and name not in OUTSIDE:
                out.append(f"{os.path.relpath(os.path.join(base, name), ROOT)}: not a declared layer (LAYERS)")
    return out


def files_of(layer):
    for folder in (os.path.join(ROOT, "include", "gear_dynamics", layer), os.path.join(ROOT, "src", layer)):
        for dirpath, _, names in os.walk(folder):
            for n in sorted(names):
                if n.endswith((".hpp", ".cpp", ".h")):
                    yield os.path.join(dirpath, n)


def self_check():
    """The checker must catch what it is for: an upward, a sibling's or an undeclared layer's include,
    a ROS header, a link outside the graph, a cycle."""
    assert violations("engine", '#include "gear_dynamics/config/config.hpp"\n'), "upward include not caught"
    assert violations("live", '#include "gear_dynamics/montecarlo/batch.hpp"\n'), "sibling include not caught"
    assert violations("analysis", '#include "gear_dynamics/live/live_simulation.hpp"\n'), "sibling include not caught"
    assert violations("config", '#include "gear_dynamics/plots/x.hpp"\n'), "undeclared layer not caught"
    assert violations("analysis", '#include "gear_dynamics/report/report.hpp"\n'), "upward include not caught"
    assert violations("analysis", '#include "gear_dynamics/dynamics/poincare.hpp"\n'), "sibling include not caught"
    assert violations("analysis", "#include <ros/ros.h>\n"), "ROS header not caught"
    assert violations("config", '#include "gear_dynamics/GearState.h"\n'), "message header not caught"
    assert not violations("analysis", '#include "gear_dynamics/model/gear_pair.hpp"\n#include <vector>\n')
    assert not violations("dynamics", '#include "gear_dynamics/engine/observers.hpp"\n')
    assert link_violations("target_link_libraries(${PROJECT_NAME}_analysis PUBLIC ${PROJECT_NAME}_montecarlo)"), \
        "undeclared link not caught"
    assert link_violations("target_link_libraries(${PROJECT_NAME}_config PUBLIC ${PROJECT_NAME}_ros)"), \
        "link to the ROS layer not caught"
    assert not link_violations("target_link_libraries(${PROJECT_NAME}_live PUBLIC ${PROJECT_NAME}_config)")
    assert test_violations("maths", '#include "gear_dynamics/engine/ensemble.hpp"\n'), "upward test include not caught"
    assert test_violations("dynamics", '#include "gear_dynamics/montecarlo/batch.hpp"\n'), \
        "sibling test include not caught"
    assert not test_violations("engine", '#include "gear_dynamics/config/config.hpp"\n')
    assert test_violations("engine", '#include "gear_dynamics/config/batch_settings.hpp"\n'), \
        "a test's upward include beyond config.hpp not caught"
    assert not test_violations(TEST_ANY, '#include "gear_dynamics/montecarlo/batch.hpp"\n')
    assert test_violations(TEST_ANY, "#include <ros/ros.h>\n"), "ROS header in a test not caught"
    try:
        reachable("a", {"a": ["b"], "b": ["a"]})
        raise AssertionError("cycle not caught")
    except ValueError:
        pass
    return []


def check_graph():
    """The declared graph itself: acyclic, every dependency declared; the folders and the links."""
    problems = []
    for layer in LAYERS:
        try:
            reachable(layer)
        except ValueError as e:
            problems.append(str(e))
    problems += undeclared_folders()
    with open(os.path.join(ROOT, "CMakeLists.txt"), encoding="utf-8") as f:
        problems += link_violations(f.read())
    return problems


def main():
    cases = [("checker_catches_violations", self_check), ("graph_folders_and_links", check_graph)]
    for layer in LAYERS:
        def check(layer=layer):
            problems, n = [], 0
            for path in files_of(layer):
                n += 1
                with open(path, encoding="utf-8") as f:
                    problems += [f"{os.path.relpath(path, ROOT)}: {v}" for v in violations(layer, f.read())]
            if n == 0:
                problems.append(f"layer '{layer}' has no files")
            return problems
        cases.append((f"layer_{layer}", check))
    cases.append(("core_tests", check_tests))
    return 1 if run_cases("layers", cases, sys.argv[1] if len(sys.argv) > 1 else None) else 0


if __name__ == "__main__":
    sys.exit(main())
