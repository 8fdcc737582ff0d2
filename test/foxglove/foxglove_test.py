#!/usr/bin/python3
"""Bags that Foxglove Studio / Lichtblick open: read_bags.js (Node.js, @foxglove/rosbag with
@foxglove/wasm-lz4, @foxglove/rosmsg, @foxglove/rosmsg-serialization at the versions pinned in
package-lock.json, installed here with npm ci) decodes every GearState, RunInfo, RunSummary and PoincarePoint of

  batch          every bag of a small gear_monte_carlo batch (LZ4 chunks, written by the package),
  record_launch  the bag of simulate.launch record:=true (rosbag record --lz4),
  rosbag_record  a plain `rosbag record` of the live node's topics (uncompressed chunks),

with the message definitions stored in the bags, and compares every field with rosbag's Python
API (py_reference.py), the package's generated C++ classes (cpp_reference bag) and, for the batch,
the package's own batch reader (cpp_reference batch: read_batches' run records and series CSV).

Skipped, with the reason printed, only where node or npm is missing.
usage: foxglove_test.py [JUNIT.xml] [--keep]"""
import glob
import json
import os
import shutil
import signal
import subprocess
import sys
import tempfile
import time
import traceback
import xml.etree.ElementTree as ET

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.dirname(os.path.dirname(HERE))
sys.path.insert(0, os.path.join(REPO, "test", "faults"))
import faultlib as fl  # noqa: E402

T_END = 0.05
LIVE_TOPICS = ["state", "run_info", "delta", "delta_dot", "phi", "center_distance"]


def junit(path, cases):
    if not path:
        return
    suite = ET.Element("testsuite", name="foxglove", tests=str(len(cases)), errors="0",
                       failures=str(sum(c[1] == "FAILED" for c in cases)),
                       skipped=str(sum(c[1] == "skipped" for c in cases)))
    for name, status, message, seconds in cases:
        tc = ET.SubElement(suite, "testcase", classname="foxglove.bags", name=name, time="%.3f" % seconds)
        if status != "ok":
            message = fl.xml_text(message)
            ET.SubElement(tc, "skipped" if status == "skipped" else "failure", message=message[:2000]).text = message
    os.makedirs(os.path.dirname(os.path.abspath(path)), exist_ok=True)
    ET.ElementTree(suite).write(path, encoding="utf-8", xml_declaration=True)


def npm_ci(work):
    """package.json, package-lock.json and read_bags.js in a folder of their own, npm ci there."""
    node_dir = os.path.join(work, "node")
    os.makedirs(node_dir)
    for f in ("package.json", "package-lock.json", "read_bags.js"):
        shutil.copy(os.path.join(HERE, f), node_dir)
    p = subprocess.run(["npm", "ci", "--no-audit", "--no-fund", "--loglevel=error"], cwd=node_dir,
                       capture_output=True, text=True, timeout=300)
    assert p.returncode == 0, "npm ci failed (%d):\n%s%s" % (p.returncode, p.stdout[-2000:], p.stderr[-2000:])
    return node_dir


def batch(work):
    folder = os.path.join(work, "batch")
    params = fl.load_yaml(*[fl.config_file(f) for f in ("gear_pair.yaml", "load.yaml", "run.yaml", "monte_carlo.yaml")]
                          + [os.path.join(REPO, "test", "ros", "small_batch.yaml")])
    params["monte_carlo"].update({"output_dir": folder, "threads": 1})
    code, out = fl.run_node("gear_monte_carlo", fl.node_name("batch"), params, timeout=120)
    assert code == 0, "batch exited %s:\n%s" % (code, out[-3000:])
    return folder, [os.path.join(folder, b) for b in fl.bags(folder)]


def outbound_connections(node, topic):
    import rosgraph
    import xmlrpc.client
    uri = rosgraph.Master("/foxglove_test").lookupNode(node)
    _, _, info = xmlrpc.client.ServerProxy(uri).getBusInfo("/foxglove_test")
    return sum(1 for c in info if c[2] == "o" and c[4] == topic)


def live(work):
    """simulate.launch record:=true and a separate rosbag record, one run of T_END: the two bags."""
    import rospy
    from gear_dynamics.msg import GearState
    sys.path.insert(0, os.path.join(REPO, "test", "ros"))
    from simtest import Collector, ends_at, services, wait_until
    launch_dir = os.path.join(work, "record_launch")
    os.makedirs(launch_dir)
    plain = os.path.join(work, "rosbag_record.bag")
    launch = subprocess.Popen(
        ["roslaunch", "gear_dynamics", "simulate.launch", "record:=true", "record_dir:=" + launch_dir, "paused:=true",
         "t_end:=%r" % T_END, "real_time_factor:=0", "output:=log"],
        stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, start_new_session=True)
    record = subprocess.Popen(["rosbag", "record", "-O", plain, "__name:=plain_record"] +
                              ["/gear/" + t for t in LIVE_TOPICS],
                              stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, start_new_session=True)
    try:
        rospy.init_node("foxglove_test", anonymous=True, disable_signals=True)
        state = Collector("/gear/state", GearState)
        state.wait_connected(30.0)
        # rosbag record and this script listen before the run starts (record:=true writes in-process).
        wait_until(lambda: all(outbound_connections("/gear/gear_simulator", "/gear/" + t) >= (2 if t == "state" else 1)
                               for t in LIVE_TOPICS), 30.0, "rosbag record to subscribe")
        srv = services("/gear/gear_simulator")
        srv["reset"]()
        srv["unpause"]()
        state.wait_for(ends_at(T_END), 30.0, "t_end")
        time.sleep(1.0)  # the recorders write what is on its way
    finally:
        for p in (record, launch):
            try:
                os.killpg(p.pid, signal.SIGINT)
            except ProcessLookupError:
                pass
        for p in (record, launch):
            try:
                p.wait(timeout=30)
            except subprocess.TimeoutExpired:
                os.killpg(p.pid, signal.SIGKILL)
                p.wait()
    launched = glob.glob(os.path.join(launch_dir, "gear_*.bag"))
    assert len(launched) == 1, "record:=true left %s" % os.listdir(launch_dir)
    assert os.path.exists(plain), "rosbag record left no %s (%s)" % (plain, os.listdir(work))
    return launched, [plain]


def main():
    args = [a for a in sys.argv[1:] if not a.startswith("--")]
    xunit = args[0] if args else None
    keep = "--keep" in sys.argv
    cases = []
    missing = [p for p in ("node", "npm") if not shutil.which(p)]
    if missing:
        reason = "Node.js is not installed here (no %s on PATH)" % " ".join(missing)
        print("foxglove_test: SKIPPED: " + reason, flush=True)
        junit(xunit, [("bags", "skipped", reason, 0.0)])
        return 0
    print("foxglove_test: node %s, npm %s" % (subprocess.run(["node", "--version"], capture_output=True, text=True).stdout.strip(),
                                             subprocess.run(["npm", "--version"], capture_output=True, text=True).stdout.strip()))
    work = tempfile.mkdtemp(prefix="gd_foxglove_")
    start = time.time()
    try:
        node_dir = npm_ci(work)
        print("foxglove_test: npm ci in %.1f s" % (time.time() - start), flush=True)
        with fl.Master():
            folder, batch_bags = batch(work)
            launch_bags, plain_bags = live(work)
        groups = {"batch": batch_bags, "record_launch": launch_bags, "rosbag_record": plain_bags}
        cpp = fl.executable("foxglove_cpp_reference")
        job = {"groups": []}
        for name, bags in groups.items():
            py_json, cpp_json = os.path.join(work, name + ".python.json"), os.path.join(work, name + ".cpp.json")
            subprocess.run(["/usr/bin/python3", os.path.join(HERE, "py_reference.py"), py_json] + bags, check=True)
            dumps = {}
            for b in bags:
                p = subprocess.run([cpp, "bag", b], capture_output=True, text=True)
                assert p.returncode == 0, "cpp_reference bag %s: %s" % (b, p.stderr)
                dumps[b] = json.loads(p.stdout)
            with open(cpp_json, "w") as f:
                json.dump(dumps, f)
            job["groups"].append({"name": name, "bags": bags, "references": {"python_rosbag": py_json, "cpp_classes": cpp_json}})
        records = os.path.join(work, "batch.reader.json")
        series = os.path.join(work, "series.csv")
        subprocess.run([cpp, "batch", folder, series, records], stdout=subprocess.DEVNULL, check=True)
        job["package_reader"] = {"group": "batch", "records": records, "series_csv": series}
        job_file = os.path.join(work, "job.json")
        with open(job_file, "w") as f:
            json.dump(job, f)
        p = subprocess.run(["node", os.path.join(node_dir, "read_bags.js"), job_file], cwd=node_dir,
                           capture_output=True, text=True, timeout=300)
        lines = p.stdout.strip().splitlines()
        print("\n".join(lines[:-1]), p.stderr, flush=True)
        result = json.loads(lines[-1]) if lines else {"failures": ["read_bags.js printed nothing: " + p.stderr[-2000:]]}
        for name in groups:
            g = result.get("groups", {}).get(name)
            mine = [f for f in result.get("failures", []) if f.startswith(name) or any(b in f for b in groups[name])]
            if name == "batch":
                mine += [f for f in result.get("failures", []) if "package reader" in f or "series.csv" in f]
            status = "FAILED" if mine or not g or not g["messages"] else "ok"
            message = "; ".join(mine[:5]) if mine else ("" if g else "not read")
            cases.append(("%s" % name, status, message, 0.0))
            if g:
                print("foxglove_test: %s: %s" % (name, json.dumps(g)), flush=True)
        pr = result.get("package_reader")
        print("foxglove_test: package reader: %s" % json.dumps(pr), flush=True)
        other = [f for f in result.get("failures", []) if not any(c[2] and f in c[2] for c in cases)]
        if p.returncode != 0 and all(c[1] == "ok" for c in cases):
            cases.append(("read_bags", "FAILED", "read_bags.js exited %d: %s" % (p.returncode, "; ".join(other[:5])), 0.0))
    except Exception:
        traceback.print_exc()
        cases.append(("harness", "FAILED", traceback.format_exc()[-2000:], time.time() - start))
    finally:
        if keep:
            print("foxglove_test: kept %s" % work)
        else:
            shutil.rmtree(work, ignore_errors=True)
    for name, status, message, _ in cases:
        print("[%s] foxglove/%s%s" % (status, name, ": " + message if message else ""), flush=True)
    junit(xunit, cases)
    return 1 if any(c[1] == "FAILED" for c in cases) else 0


if __name__ == "__main__":
    sys.exit(main())
