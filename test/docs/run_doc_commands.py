#!/usr/bin/python3
"""Runs every command line of the documentation as typed: each ```bash block of README.md,
doc/*.md, bench/README.md and test/README.md, one JUnit case per block, from the repository root
in a bash with the package's workspace sourced and a private ROS master.

A block whose info string is `bash background` is started and left running while the next block
runs (e.g. a launch that a rostopic command then watches), and is stopped after it. A block that
is the test command itself (it would run this test again) is reported as a visible skip.

usage: run_doc_commands.py JUNIT_XML [FILE.md ...]"""
import glob
import os
import re
import signal
import socket
import subprocess
import sys
import time
import xml.etree.ElementTree as ET

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
from junit_cases import xml_text  # noqa: E402

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
BLOCK = re.compile(r"^```(bash[^\n]*)\n(.*?)^```", re.M | re.S)
TIMEOUT = 600  # s per block: the longest documented command is realizations:=1000
# Lines that start this very test suite again.
SELF = {"bash scripts/test.sh", "bash .ci/run"}


def blocks(path):
    with open(path, encoding="utf-8") as f:
        text = f.read()
    for m in BLOCK.finditer(text):
        line = text.count("\n", 0, m.start()) + 1
        yield line, m.group(1).split()[1:], m.group(2)


def free_port():
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def stop(proc):
    if proc.poll() is None:
        os.killpg(proc.pid, signal.SIGINT)
        try:
            proc.wait(20)
        except subprocess.TimeoutExpired:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.wait()


def main():
    xml_path = sys.argv[1]
    files = sys.argv[2:] or ([os.path.join(ROOT, "README.md")] + sorted(glob.glob(os.path.join(ROOT, "doc", "*.md"))) +
                             [os.path.join(ROOT, "bench", "README.md"), os.path.join(ROOT, "test", "README.md")])
    env = dict(os.environ)
    port = free_port()
    env["ROS_MASTER_URI"] = f"http://localhost:{port}"
    master = subprocess.Popen(["roscore", "-p", str(port)], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                              env=env, start_new_session=True)
    suite = ET.Element("testsuite", name="doc_commands")
    counts = {"tests": 0, "failures": 0, "skipped": 0}
    background = []
    try:
        time.sleep(3)
        for path in files:
            if not os.path.exists(path):
                continue
            rel = os.path.relpath(path, ROOT)
            for line, flags, body in blocks(path):
                name = f"{rel}:{line}"
                counts["tests"] += 1
                case = ET.SubElement(suite, "testcase", classname="doc_commands", name=name)
                commands = [c for c in body.splitlines() if c.strip() and not c.lstrip().startswith("#")]
                if any(c.strip() in SELF for c in commands):
                    reason = "the test command itself (this test runs inside it)"
                    ET.SubElement(case, "skipped", message=reason)
                    counts["skipped"] += 1
                    print(f"SKIP {name}: {reason}", flush=True)
                    continue
                script = "set -eo pipefail\n" + body
                start = time.time()
                if "background" in flags:
                    proc = subprocess.Popen(["bash", "-c", script], cwd=ROOT, env=env, start_new_session=True,
                                            stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
                    time.sleep(5)
                    ok = proc.poll() in (None, 0)
                    out = "" if proc.poll() is None else proc.stdout.read()
                    background.append(proc)
                else:
                    try:
                        res = subprocess.run(["bash", "-c", script], cwd=ROOT, env=env, timeout=TIMEOUT,
                                             stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
                        ok, out = res.returncode == 0, res.stdout
                    except subprocess.TimeoutExpired as e:
                        ok, out = False, f"timed out after {TIMEOUT} s\n{e.stdout or ''}"
                    for p in background:
                        stop(p)
                    background.clear()
                case.set("time", f"{time.time() - start:.1f}")
                print(f"{'ok  ' if ok else 'FAIL'} {name} ({time.time() - start:.1f} s): {commands[0][:90]}", flush=True)
                if not ok:
                    counts["failures"] += 1
                    failure = ET.SubElement(case, "failure", message=f"{name} failed")
                    failure.text = xml_text(body + "\n---\n" + out[-4000:])
                    print(out[-4000:], flush=True)
    finally:
        for p in background:
            stop(p)
        stop(master)
    for k, v in counts.items():
        suite.set(k, str(v))
    suite.set("errors", "0")
    os.makedirs(os.path.dirname(xml_path), exist_ok=True)
    ET.ElementTree(suite).write(xml_path, encoding="utf-8", xml_declaration=True)
    print(f"doc commands: {counts['tests'] - counts['failures'] - counts['skipped']} passed, "
          f"{counts['failures']} failed, {counts['skipped']} skipped")
    return 1 if counts["failures"] else 0


if __name__ == "__main__":
    sys.exit(main())
