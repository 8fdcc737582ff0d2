"""What the fault-suite scripts share: cases with a category and a JUnit file, a private ROS
master, running this package's executables with private parameters, and reading batch folders."""
import contextlib
import itertools
import os
import shutil
import signal
import socket
import subprocess
import sys
import tempfile
import threading
import time
import traceback
import xml.etree.ElementTree as ET

import yaml

from catkin.find_in_workspaces import find_in_workspaces

# The rostests' helpers (test/ros/simtest.py), shared rather than written again.
sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "ros"))
sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
from junit_cases import xml_text  # noqa: E402,F401  (re-exported for the suites' JUnit writers)
from simtest import read_csv, wait_until  # noqa: E402,F401  (re-exported for the fault scripts)

PACKAGE = "gear_dynamics"


def package_dir():
    import rospkg
    return rospkg.RosPack().get_path(PACKAGE)


def config_file(name):
    return os.path.join(package_dir(), "config", name)


def load_yaml(*paths):
    """The files merged key by key (maps recursively), as roslaunch's rosparam load does."""
    def merge(base, over):
        for k, v in over.items():
            if isinstance(v, dict) and isinstance(base.get(k), dict):
                merge(base[k], v)
            else:
                base[k] = v
    out = {}
    for p in paths:
        with open(p) as f:
            merge(out, yaml.safe_load(f) or {})
    return out


def executable(name):
    found = find_in_workspaces(project=PACKAGE, path=name, first_match_only=True)
    if not found:
        raise RuntimeError("executable %s not found in the catkin workspace (is it built and sourced?)" % name)
    return found[0]


class Suite:
    """Cases grouped by category; prints a table and writes a JUnit file (one testcase per case,
    classname faults.<category>), which test/faults/summary.py totals over the whole suite."""

    def __init__(self, name, argv=None):
        import argparse
        parser = argparse.ArgumentParser(description=name)
        parser.add_argument("xunit", nargs="?", help="JUnit XML file to write")
        parser.add_argument("--slow", action="store_true", default=os.environ.get("GD_FAULTS_SLOW") == "1",
                            help="every case, not only the quick selection (also: GD_FAULTS_SLOW=1)")
        parser.add_argument("--seed", type=int, default=int(os.environ.get("GD_FAULT_SEED", "0")) or None,
                            help="random seed of the fault moments and offsets (default: time-based, printed)")
        self.args = parser.parse_args(argv)
        self.name = name
        self.cases = []  # (category, name, ok, message, seconds)
        import random
        self.seed = self.args.seed or int(time.time() * 1000) % 1000000
        self.random = random.Random(self.seed)
        print("%s: random seed %d (rerun with --seed %d)" % (name, self.seed, self.seed), flush=True)

    @contextlib.contextmanager
    def case(self, category, name):
        start = time.time()
        try:
            yield
            status, message = "ok", ""
        except Exception as e:  # a failed check or anything unexpected: the case fails, the suite goes on
            status = "FAILED"
            message = str(e) if isinstance(e, AssertionError) else "%s: %s" % (type(e).__name__, e)
            traceback.print_exc()
        self._add(category, name, status, message, time.time() - start)

    def skip(self, category, name, reason):
        """A case that cannot run here (e.g. it needs root): shown, counted apart, never passed."""
        self._add(category, name, "skipped", reason, 0.0)

    def _add(self, category, name, status, message, seconds):
        self.cases.append((category, name, status, message, seconds))
        print("[%s] %s/%s (%.1f s)%s" % (status, category, name, seconds, ": " + message if message else ""),
              flush=True)

    def finish(self):
        by_category = {}
        for category, _, status, _, _ in self.cases:
            counts = by_category.setdefault(category, {"tried": 0, "ok": 0, "skipped": 0})
            if status == "skipped":
                counts["skipped"] += 1
            else:
                counts["tried"] += 1
                counts["ok"] += status == "ok"
        print("\n%s: cases per category" % self.name)
        print("  %-28s %6s %6s %8s" % ("category", "tried", "passed", "skipped"))
        for category in sorted(by_category):
            c = by_category[category]
            print("  %-28s %6d %6d %8d" % (category, c["tried"], c["ok"], c["skipped"]))
        if self.args.xunit:
            suite = ET.Element("testsuite", name=self.name, tests=str(len(self.cases)),
                               failures=str(sum(c[2] == "FAILED" for c in self.cases)), errors="0",
                               skipped=str(sum(c[2] == "skipped" for c in self.cases)))
            for category, name, status, message, seconds in self.cases:
                tc = ET.SubElement(suite, "testcase", classname="faults." + category, name=name,
                                   time="%.3f" % seconds)
                if status != "ok":
                    tag = "skipped" if status == "skipped" else "failure"
                    text = xml_text(message)
                    ET.SubElement(tc, tag, message=text[:2000]).text = text
            os.makedirs(os.path.dirname(os.path.abspath(self.args.xunit)), exist_ok=True)
            ET.ElementTree(suite).write(self.args.xunit, encoding="utf-8", xml_declaration=True)
        tried = [c for c in self.cases if c[2] != "skipped"]
        return 1 if not tried or any(c[2] == "FAILED" for c in tried) else 0


def free_port():
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


class Master:
    """A private rosmaster on a free port, with its own ROS_HOME; the environment of the
    processes started through it (and of this script's rosparam/rospy calls) points there."""

    def __init__(self):
        self.home = tempfile.mkdtemp(prefix="gd_faults_ros_")
        port = free_port()
        os.environ["ROS_MASTER_URI"] = "http://127.0.0.1:%d" % port
        os.environ["ROS_HOME"] = self.home
        os.environ["ROS_LOG_DIR"] = os.path.join(self.home, "log")
        os.environ.pop("ROS_NAMESPACE", None)
        self.process = subprocess.Popen(["rosmaster", "--core", "-p", str(port)], stdout=subprocess.DEVNULL,
                                        stderr=subprocess.DEVNULL)
        import rosgraph
        deadline = time.time() + 20
        while not rosgraph.is_master_online():
            if time.time() > deadline or self.process.poll() is not None:
                raise RuntimeError("rosmaster did not start on port %d" % port)
            time.sleep(0.1)

    def close(self):
        self.process.send_signal(signal.SIGINT)
        try:
            self.process.wait(10)
        except subprocess.TimeoutExpired:
            self.process.kill()
        shutil.rmtree(self.home, ignore_errors=True)

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()


_node_numbers = itertools.count(1)  # next() is atomic: names are unique across threads


def node_name(prefix):
    return "%s_%d" % (prefix, next(_node_numbers))


_param_lock = threading.Lock()  # one master connection at a time (xmlrpc proxies are not thread-safe)


def set_params(name, params):
    """Puts `params` (a dict of sections) into the private namespace of node /name."""
    import rosparam
    with _param_lock:
        rosparam.upload_params("/" + name, params)


def start_node(executable_name, name, params, extra_args=(), preexec_fn=None, output=None):
    """Starts this package's executable as node /name with private parameters `params`. Its
    stdout and stderr go to `output` (a file object) or are captured."""
    set_params(name, params)
    cmd = [executable(executable_name), "__name:=" + name] + list(extra_args)
    return subprocess.Popen(cmd, stdout=output or subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
                            preexec_fn=preexec_fn, start_new_session=True)


def run_node(executable_name, name, params, timeout=60, extra_args=()):
    """Runs the node to its end: (exit code, output)."""
    p = start_node(executable_name, name, params, extra_args)
    try:
        out, _ = p.communicate(timeout=timeout)
    except subprocess.TimeoutExpired:
        os.killpg(p.pid, signal.SIGKILL)
        out, _ = p.communicate()
        raise AssertionError("%s did not end within %g s; output:\n%s" % (executable_name, timeout, out[-3000:]))
    return p.returncode, out


def bags(folder):
    return sorted(f for f in os.listdir(folder) if f.endswith(".bag"))


def read_bag(path):
    """The messages of a run bag as (topic, raw bytes) in bag order; raises if it is unreadable."""
    import rosbag
    with rosbag.Bag(path) as bag:
        return [(topic, msg[1]) for topic, msg, _ in bag.read_messages(raw=True)]


def check_run_bag(path):
    """A finished run bag: readable, run_info first, summary last and once."""
    messages = read_bag(path)
    topics = [t for t, _ in messages]
    assert topics and topics[0] == "/gear/run_info" and topics.count("/gear/run_info") == 1, \
        "%s: run_info is not the one first message" % path
    assert topics[-1] == "/gear/summary" and topics.count("/gear/summary") == 1, \
        "%s: summary is not the one last message" % path
    return messages


def summaries(folder):
    """{bag name: raw bytes of its RunSummary} of the finished bags of a folder."""
    return {b: [m for t, m in check_run_bag(os.path.join(folder, b)) if t == "/gear/summary"][0]
            for b in bags(folder)}


def run_aggregator(folder, report, joint_times, timeout=120):
    """gear_aggregator on `folder` without figures, the joint densities at `joint_times` (among the
    batch's snapshot times): (exit code, output, {run name: runs.csv row}, [inputs.csv rows])."""
    params = load_yaml(config_file("aggregator.yaml"))
    params["analysis"]["joint_times"] = joint_times
    params.update({"folders": folder, "report_folder": report, "exit_when_done": True, "plot_script": ""})
    code, out = run_node("gear_aggregator", node_name("aggregator"), params, timeout=timeout)
    runs, inputs = {}, []
    if code == 0:
        runs = {r["name"]: r for r in read_csv(os.path.join(report, "runs.csv"))}
        inputs = read_csv(os.path.join(report, "inputs.csv"))
    return code, out, runs, inputs


def died_of_signal(code):
    return code is not None and code < 0


def main(run):
    """Runs `run(suite)` inside a Suite with a private master; exits with the suite's status."""
    name = os.path.splitext(os.path.basename(sys.argv[0]))[0]
    suite = Suite(name)
    with Master():
        try:
            run(suite)
        except Exception:  # a broken harness must fail the suite, not vanish
            traceback.print_exc()
            suite._add("harness", "setup", "FAILED", traceback.format_exc(), 0.0)
    sys.exit(suite.finish())
