#!/usr/bin/python3
"""The core's layering, checked on the source tree: each core layer (include/gear_dynamics/<layer>/
and src/<layer>/) includes only headers of its own layer and the layers below it, and no ROS header
(roscpp, rosbag, messages, dynamic_reconfigure, the package's generated message headers).

usage: check_layers.py JUNIT_XML"""
import os
import re
import sys
import time
import xml.etree.ElementTree as ET

# Bottom to top; a layer may include its own headers and those of every layer before it.
LAYERS = ["model", "engine", "config", "live", "montecarlo", "analysis", "dynamics"]
ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
INCLUDE = re.compile(r'^\s*#\s*include\s*[<"]([^>"]+)[>"]', re.M)
# Headers that mean ROS: the ROS client libraries and message packages, and the package's own
# generated message and dynamic_reconfigure headers (gear_dynamics/Name.h).
ROS_HEADER = re.compile(r"^(ros|rosbag|roscpp|std_msgs|std_srvs|rosgraph_msgs|diagnostic_msgs|diagnostic_updater|"
                        r"dynamic_reconfigure|xmlrpcpp|message_filters)/|^gear_dynamics/[A-Z]\w*\.h$")


def violations(layer, text):
    """The offending includes of one file of `layer`, each with the reason."""
    allowed = LAYERS[:LAYERS.index(layer) + 1]
    out = []
    for header in INCLUDE.findall(text):
        if ROS_HEADER.search(header):
            out.append(f"{header}: a ROS header in the ROS-free core")
        elif header.startswith("gear_dynamics/"):
            parts = header.split("/")
            other = parts[1] if len(parts) > 2 else "(top level)"
            if other not in allowed:
                out.append(f"{header}: layer '{other}' is not below '{layer}' (allowed: {', '.join(allowed)})")
    return out


def files_of(layer):
    for folder in (os.path.join(ROOT, "include", "gear_dynamics", layer), os.path.join(ROOT, "src", layer)):
        for dirpath, _, names in os.walk(folder):
            for n in sorted(names):
                if n.endswith((".hpp", ".cpp", ".h")):
                    yield os.path.join(dirpath, n)


def self_check():
    """The checker must catch what it is for: an upward include and a ROS header."""
    assert violations("engine", '#include "gear_dynamics/config/config.hpp"\n'), "upward include not caught"
    assert violations("analysis", "#include <ros/ros.h>\n"), "ROS header not caught"
    assert violations("config", '#include "gear_dynamics/GearState.h"\n'), "message header not caught"
    assert not violations("analysis", '#include "gear_dynamics/model/gear_pair.hpp"\n#include <vector>\n')
    return []


def main():
    suite = ET.Element("testsuite", name="layers")
    failures = 0
    cases = [("checker_catches_violations", self_check)]
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
    for name, check in cases:
        start = time.time()
        try:
            problems = check()
        except AssertionError as e:
            problems = [str(e)]
        case = ET.SubElement(suite, "testcase", classname="layers", name=name, time=f"{time.time() - start:.3f}")
        status = "ok" if not problems else "FAILED"
        print(f"layers.{name}: {status}")
        if problems:
            failures += 1
            ET.SubElement(case, "failure", message=problems[0]).text = "\n".join(problems)
            for p in problems:
                print("  " + p)
    suite.set("tests", str(len(cases)))
    suite.set("failures", str(failures))
    suite.set("errors", "0")
    if len(sys.argv) > 1:
        os.makedirs(os.path.dirname(sys.argv[1]), exist_ok=True)
        ET.ElementTree(suite).write(sys.argv[1], encoding="utf-8", xml_declaration=True)
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
