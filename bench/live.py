#!/usr/bin/env python3
"""The live node's costs, printed as one table; bench/live runs it.

1. The core (LiveSimulation, no ROS; gear_live_bench core): simulated s per CPU s at
   real_time_factor 0, publish_rate 1 kHz and 10 kHz, a sink that only counts.
2. The node gear_simulator (simulate.launch on a master of its own) at real_time_factor 0 for
   --t-end simulated seconds, 1 kHz and 10 kHz, without and with a subscriber on state (a roscpp
   subscriber, gear_live_bench subscribe): the node's CPU (all its threads, /proc/PID/task/*/schedstat,
   from ~unpause to final_state), sim s per CPU s, and CPU per published message.
3. The node at real_time_factor 1 for --wall seconds: CPU % of one core, 1 and 10 kHz, without and
   with the subscriber; and (this build) at 1 kHz with the spectrum topic on at 1 Hz.
The spectrum topic (this build): the core with it on at 1 and 10 Hz (the stepping thread's ns per
step with the samples and the window copies; the two Welch PSDs per update, timed apart, which the node
computes on a worker thread).
The node runs with its defaults otherwise (config/*.yaml: /clock on, throttled to 200 Hz).
"""
import argparse
import glob
import json
import os
import signal
import socket
import subprocess
import sys
import time
import xmlrpc.client


def source_of(devel):
    """The gear_dynamics source folder a devel folder was built from (its CMake package config)."""
    with open(os.path.join(devel, "share/gear_dynamics/cmake/gear_dynamicsConfig.cmake")) as f:
        for line in f:
            if line.startswith("set(gear_dynamics_SOURCE_PREFIX "):
                return os.path.realpath(line.split()[1].rstrip(")"))
    raise RuntimeError(f"{devel}: no gear_dynamics_SOURCE_PREFIX; pass --before-source")


def free_port():
    with socket.socket() as s:
        s.bind(("localhost", 0))
        return s.getsockname()[1]


def cpu_ns(pid):
    total = 0
    for f in glob.glob(f"/proc/{pid}/task/*/schedstat"):
        try:
            with open(f) as fh:
                total += int(fh.read().split()[0])
        except (OSError, ValueError):
            pass
    return total


class Node:
    """simulate.launch with its own master; the gear_simulator's pid."""

    def __init__(self, env, ns, args):
        self.env, self.ns = env, ns
        # By path: with a --before build two source trees hold the package, and roslaunch refuses
        # to pick one of two simulate.launch files by package name.
        launch = os.path.join(env["GD_SOURCE"], "launch", "simulate.launch")
        self.launch = subprocess.Popen(
            ["roslaunch", "--no-summary", launch, f"ns:={ns}",
             "output:=log", "use_sim_time:=false"] + [f"{k}:={v}" for k, v in args.items()],
            env=env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, start_new_session=True)
        master = xmlrpc.client.ServerProxy(env["ROS_MASTER_URI"])
        deadline = time.time() + 60
        self.pid = None
        while time.time() < deadline:
            try:
                code, _, uri = master.lookupNode("/bench", f"/{ns}/gear_simulator")
                if code == 1:
                    code, _, pid = xmlrpc.client.ServerProxy(uri).getPid("/bench")
                    if code == 1:
                        self.pid = pid
                        break
            except (OSError, xmlrpc.client.Fault):
                pass
            time.sleep(0.2)
        if self.pid is None:
            self.stop()
            raise RuntimeError("gear_simulator did not come up")
        # the services are advertised last: wait for them
        while time.time() < deadline:
            code, _, _ = master.lookupService("/bench", f"/{ns}/gear_simulator/unpause")
            if code == 1:
                break
            time.sleep(0.2)

    def call(self, service):
        subprocess.run(["rosservice", "call", f"/{self.ns}/gear_simulator/{service}"], env=self.env,
                       check=True, stdout=subprocess.DEVNULL)

    def stop(self):
        if self.launch.poll() is None:
            os.killpg(self.launch.pid, signal.SIGINT)
            try:
                self.launch.wait(30)
            except subprocess.TimeoutExpired:
                os.killpg(self.launch.pid, signal.SIGKILL)
                self.launch.wait()


def subscriber(bench, env, topic, seconds):
    p = subprocess.Popen([bench, "subscribe", topic, str(seconds)], env=env, stdout=subprocess.PIPE, text=True)
    time.sleep(1.5)  # connected
    return p


def end_subscriber(p):
    p.send_signal(signal.SIGINT)
    out, _ = p.communicate(timeout=30)
    return json.loads(out.strip().splitlines()[-1])


def wait_finished(env, ns, timeout):
    # final_state is latched and published once at t_end
    subprocess.run(["rostopic", "echo", "-n", "1", f"/{ns}/final_state/t"], env=env, check=True,
                   stdout=subprocess.DEVNULL, timeout=timeout)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("bench", help="path of gear_live_bench")
    ap.add_argument("--t-end", type=float, default=5.0, help="simulated s of the real_time_factor 0 runs")
    ap.add_argument("--wall", type=float, default=10.0, help="wall s of the real-time runs")
    ap.add_argument("--core-only", action="store_true")
    ap.add_argument("--json", help="also write the figures here")
    ap.add_argument("--before", metavar="DEVEL",
                    help="a copy of another build's devel folder: every case runs with it too, side by side")
    ap.add_argument("--before-source", metavar="DIR",
                    help="the source tree of the --before build (default: the one its CMake config names)")
    a = ap.parse_args()

    env = dict(os.environ)
    env["ROS_MASTER_URI"] = f"http://localhost:{free_port()}"
    env["ROS_HOME"] = env.get("ROS_HOME", os.path.expanduser("~/.ros"))
    env["GD_SOURCE"] = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    builds = [("this", env, a.bench)]
    if a.before:
        before = dict(env)
        before["CMAKE_PREFIX_PATH"] = a.before + ":" + env.get("CMAKE_PREFIX_PATH", "")
        before["LD_LIBRARY_PATH"] = a.before + "/lib:" + env.get("LD_LIBRARY_PATH", "")
        # Its own launch and config files (their keys must match its binaries): the source tree the
        # build was made from, first on ROS_PACKAGE_PATH.
        source = a.before_source or source_of(a.before)
        before["ROS_PACKAGE_PATH"] = source + ":" + env.get("ROS_PACKAGE_PATH", "")
        before["GD_SOURCE"] = source
        before["GEAR_DYNAMICS_CONFIG_DIR"] = os.path.join(source, "config")  # for its gear_run
        builds.append(("before", before, os.path.join(a.before, "lib/gear_dynamics/gear_live_bench")))

    figures = {"core": [], "fast": [], "realtime": []}
    print("1. The core (LiveSimulation, counting sink, real_time_factor 0), best of 3:")
    for rate in (1000, 10000):
        for name, e, bench in builds:
            r = json.loads(subprocess.run([bench, "core", "--rate", str(rate), "--t-end", "2", "--repeat", "3"],
                                          check=True, capture_output=True, text=True, env=e).stdout)
            r["build"] = name
            figures["core"].append(r)
            print(f"   {name:>6} build {rate:>6} Hz: {r['sim_s_per_cpu_s']:6.1f} sim-s per CPU-s "
                  f"({r['ns_per_step']:.1f} ns per step)")
    name, e, bench = builds[0]
    for updates in (1, 10):
        r = json.loads(subprocess.run([bench, "core", "--rate", "1000", "--t-end", "2", "--repeat", "3",
                                       "--spectrum", str(updates)],
                                      check=True, capture_output=True, text=True, env=e).stdout)
        r["build"], r["spectrum_rate"] = name, updates
        figures["core"].append(r)
        print(f"   {name:>6} build   1000 Hz, spectrum at {updates:>2} Hz: {r['sim_s_per_cpu_s']:6.1f} sim-s per CPU-s "
              f"({r['ns_per_step']:.1f} ns per step, with a copy of the {r['spectrum_window_samples']}-sample window "
              f"of {r['copy_us_per_spectrum']:.0f} us per update); the two PSDs {r['psd_ms_per_spectrum']:.2f} ms "
              f"per update")
    if a.core_only:
        return
    print(f"2. The node at real_time_factor 0, t_end {a.t_end:g} s (CPU of all its threads, ~unpause to t_end):")
    print("   build   rate [Hz]  subscriber  node CPU [s]  sim-s per CPU-s  messages  CPU per message [us]  received/dropped")
    k = 0
    for rate, sub, (name, env, _) in [(r, s, b) for r in (1000, 10000) for s in (False, True) for b in builds]:
            k += 1
            node = Node(env, f"bench{k}", {"publish_rate": rate, "t_end": a.t_end, "paused": "true",
                                            "real_time_factor": 0})
            try:
                s = subscriber(a.bench, env, f"/bench{k}/state", 3600) if sub else None
                c0 = cpu_ns(node.pid)
                node.call("unpause")
                wait_finished(env, f"bench{k}", 600)
                c1 = cpu_ns(node.pid)
                got = end_subscriber(s) if s else None
            finally:
                node.stop()
            cpu = (c1 - c0) * 1e-9
            messages = int(round(a.t_end * rate))
            row = {"build": name, "rate": rate, "subscriber": sub, "cpu_s": cpu, "sim_s_per_cpu_s": a.t_end / cpu,
                   "messages": messages, "us_per_message": cpu / messages * 1e6, "subscriber_got": got}
            figures["fast"].append(row)
            recv = f"{got['received']}/{got['dropped']}" if got else "-"
            print(f"   {name:>6}  {rate:>9}  {'yes' if sub else 'no':>10}  {cpu:12.3f}  {a.t_end / cpu:15.1f}  {messages:8d}"
                  f"  {cpu / messages * 1e6:20.2f}  {recv}")
    by = {(r["build"], r["rate"], r["subscriber"]): r for r in figures["fast"]}
    for rate in (1000, 10000):
        for name, _, _ in builds:
            extra = (by[(name, rate, True)]["cpu_s"] - by[(name, rate, False)]["cpu_s"]) / \
                by[(name, rate, True)]["messages"] * 1e6
            print(f"   {name:>6} build, {rate} Hz: the subscriber adds {extra:.2f} us of node CPU per published message")
            figures.setdefault("marginal_us_per_message", {})[f"{name} {rate}"] = extra

    print(f"3. The node at real_time_factor 1 ({a.wall:g} s of wall time after start-up): CPU % of one core")
    for rate, sub, (name, env, _) in [(r, s, b) for r in (1000, 10000) for s in (False, True) for b in builds]:
            k += 1
            node = Node(env, f"bench{k}", {"publish_rate": rate, "real_time_factor": 1})
            try:
                s = subscriber(a.bench, env, f"/bench{k}/state", 3600) if sub else None
                time.sleep(1.0)
                c0, w0 = cpu_ns(node.pid), time.monotonic()
                time.sleep(a.wall)
                c1, w1 = cpu_ns(node.pid), time.monotonic()
                got = end_subscriber(s) if s else None
            finally:
                node.stop()
            pct = (c1 - c0) * 1e-9 / (w1 - w0) * 100
            figures["realtime"].append({"build": name, "rate": rate, "subscriber": sub, "cpu_percent": pct})
            print(f"   {name:>6} build  {rate:>6} Hz  subscriber {'yes' if sub else 'no ':<3}  {pct:5.1f} %")
    name, env, _ = builds[0]
    k += 1
    node = Node(env, f"bench{k}", {"publish_rate": 1000, "real_time_factor": 1, "spectrum_rate": 1})
    try:
        time.sleep(1.0)
        c0, w0 = cpu_ns(node.pid), time.monotonic()
        time.sleep(a.wall)
        c1, w1 = cpu_ns(node.pid), time.monotonic()
    finally:
        node.stop()
    pct = (c1 - c0) * 1e-9 / (w1 - w0) * 100
    figures["realtime"].append({"build": name, "rate": 1000, "subscriber": False, "spectrum_rate": 1, "cpu_percent": pct})
    print(f"   {name:>6} build    1000 Hz  subscriber no   spectrum 1 Hz  {pct:5.1f} %")
    if a.json:
        with open(a.json, "w") as fh:
            json.dump(figures, fh, indent=1)


if __name__ == "__main__":
    sys.exit(main())
