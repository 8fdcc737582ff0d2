#!/usr/bin/python3
"""scripts/setup.sh skips catkin_make only when nothing changed (scripts/setup.sh, gd_build_current):
sourced twice, the second time skips; after touching a doc it runs catkin_make again; after touching
a node's source it recompiles and relinks that node; the skip then comes back. Uses the workspace
of the repository (run by scripts/test.sh after catkin, like the doc commands: it runs catkin_make).

usage: build_check.py JUNIT_FILE
"""
import os
import subprocess
import sys
import time
import xml.etree.ElementTree as ET

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
from junit_cases import xml_text  # noqa: E402

REPO = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
SKIPPED = "setup: nothing changed since the last build"


def setup():
    """The output of sourcing scripts/setup.sh in a fresh bash."""
    p = subprocess.run(["bash", "-c", "source scripts/setup.sh"], cwd=REPO, stdout=subprocess.PIPE,
                       stderr=subprocess.STDOUT, text=True, timeout=1800)
    if p.returncode != 0:
        raise AssertionError("setup.sh failed:\n" + p.stdout[-3000:])
    return p.stdout


def touch(relative):
    os.utime(os.path.join(REPO, relative))


def skips():
    setup()  # whatever the state (tests built since, ...): afterwards the workspace is current
    out = setup()
    assert SKIPPED in out, "the second setup.sh in a row ran catkin_make:\n" + out[-2000:]


def doc_edit_rebuilds():
    touch("README.md")
    out = setup()
    assert SKIPPED not in out and "make -j" in out, "a touched README.md did not run catkin_make:\n" + out[-2000:]
    assert SKIPPED in setup(), "no skip after the rebuild"


def source_edit_recompiles():
    touch("src/nodes/gear_aggregator.cpp")
    out = setup()
    assert "gear_aggregator.cpp.o" in out and "Linking CXX executable" in out, \
        "a touched src/nodes/gear_aggregator.cpp was not recompiled:\n" + out[-2000:]
    assert SKIPPED in setup(), "no skip after the rebuild"


def main():
    suite = ET.Element("testsuite", name="setup_build_check")
    failures = 0
    for case in (skips, doc_edit_rebuilds, source_edit_recompiles):
        start = time.time()
        element = ET.SubElement(suite, "testcase", classname="setup.build_check", name=case.__name__)
        try:
            case()
            print("ok   %s (%.1f s)" % (case.__name__, time.time() - start), flush=True)
        except (AssertionError, subprocess.TimeoutExpired) as e:
            failures += 1
            ET.SubElement(element, "failure", message=case.__name__ + " failed").text = xml_text(str(e))
            print("FAIL %s: %s" % (case.__name__, e), flush=True)
        element.set("time", "%.1f" % (time.time() - start))
    suite.set("tests", "3")
    suite.set("failures", str(failures))
    suite.set("errors", "0")
    os.makedirs(os.path.dirname(os.path.abspath(sys.argv[1])), exist_ok=True)
    ET.ElementTree(suite).write(sys.argv[1], encoding="utf-8", xml_declaration=True)
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
