#!/usr/bin/python3
"""gear_dynamics from its install space alone: `catkin_make install` (the install target of the
package's workspace, whose install space is emptied first), then, in a mount namespace of its own
where the source tree and the workspace's src, build and devel folders are hidden under empty
tmpfs mounts, a shell that sources only the install space's setup.bash (no variable of the calling
workspace) runs the main launch (paper.launch, small) to its report and figures and the live node
(simulate.launch) until it publishes states. No installed file may name the hidden folders.

Hiding the folders (unshare --mount, root) instead of building a copy elsewhere tests the same
thing without a second full build of the package, and nothing can fall back on the original tree.
usage: install_test.py JUNIT_XML"""
import os
import shutil
import signal
import socket
import subprocess
import sys
import tempfile
import time

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
from junit_cases import run_cases  # noqa: E402

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
SKIP = {".git", "batches", "report", "node_modules"}


def clean_env(home):
    """The environment of a new login shell: no ROS_*, CMAKE_PREFIX_PATH or library path of the caller."""
    env = {"PATH": "/usr/bin:/bin:/usr/sbin:/sbin", "HOME": home, "LANG": "C.UTF-8"}
    for k in ("CCACHE_DIR", "CCACHE_CONFIGPATH", "TMPDIR"):
        if k in os.environ:
            env[k] = os.environ[k]
    return env


def free_port():
    s = socket.socket()
    s.bind(("", 0))
    port = s.getsockname()[1]
    s.close()
    return port


def reference_workspace():
    """The package's workspace: $GD_WS, else the sourced devel space's parent (catkin_make run_tests)."""
    if os.environ.get("GD_WS"):
        return os.path.abspath(os.environ["GD_WS"])
    for p in os.environ.get("CMAKE_PREFIX_PATH", "").split(":"):
        if os.path.basename(p.rstrip("/")) == "devel" and os.path.exists(os.path.join(p, ".catkin")):
            return os.path.dirname(os.path.abspath(p))
    return ""


class Install:
    def __init__(self):
        self.tmp = tempfile.mkdtemp(prefix="gd_install_")
        self.ws = reference_workspace()
        self.prefix = os.path.join(self.ws, "install")
        self.hidden = sorted({os.path.realpath(ROOT)} | {os.path.join(self.ws, f) for f in ("src", "build", "devel")})
        self.log = []
        self.done = None

    def run(self, cmd, timeout, **kw):
        p = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, timeout=timeout,
                           env=clean_env(os.environ.get("HOME", "/root")), **kw)
        self.log.append(f"$ {cmd if isinstance(cmd, str) else ' '.join(cmd)}\n{p.stdout}")
        return p

    def installed(self):
        """Runs catkin_make install into an empty install space; the problems, empty on success."""
        if self.done is None:
            self.done = self._install()
        return self.done

    def _install(self):
        if not self.ws or not os.path.exists(os.path.join(self.ws, "build", "CMakeCache.txt")):
            return ["no built workspace (source scripts/setup.sh, or run through catkin_make run_tests)"]
        shutil.rmtree(self.prefix, ignore_errors=True)
        start = time.time()
        # The build folder's own install target, as catkin_make install runs it, on the current build.
        p = self.run(["cmake", "--build", os.path.join(self.ws, "build"), "--target", "install", "--", "-j2"],
                     timeout=1500)
        print(f"  install: {time.time() - start:.1f} s")
        if p.returncode != 0:
            return ["catkin_make install failed:\n" + p.stdout[-4000:]]
        return []

    def shell(self, script, timeout):
        """Runs `script` in bash with the source tree and workspace hidden, only the install space
        sourced and a master port of its own."""
        port = free_port()
        hide = "".join(f"mount -t tmpfs gd_hidden {h}; " for h in self.hidden if os.path.isdir(h))
        text = (f"set -e; {hide}source {self.prefix}/setup.bash; export ROS_MASTER_URI=http://localhost:{port}; "
                f"export ROS_HOME={self.tmp}/ros_home; PORT={port}; " + script)
        return self.run(["unshare", "--mount", "--propagation", "private", "bash", "-c", text], timeout=timeout,
                        cwd=self.tmp)


def case_installs(d):
    return d.installed()


def case_nothing_names_the_build(d):
    """No installed file names the source tree or the build or devel folder (a path fixed at build time)."""
    if d.installed():
        return ["not installed"]
    problems = []
    for folder, _, files in os.walk(d.prefix):
        for name in files:
            path = os.path.join(folder, name)
            # Bytecode caches copied with the generated modules name where they were compiled (for
            # tracebacks only); Python reads the installed sources beside them.
            # catkin's chaining lists (_setup_util.py's parent workspaces, the Config.cmake's library
            # search path) hold the CMAKE_PREFIX_PATH of the configure, the devel space when it was
            # sourced; they are searched after the install space, which finds_installed_package checks.
            if os.path.islink(path) or name.endswith(".pyc") or name == "_setup_util.py" or name.endswith("Config.cmake"):
                continue
            with open(path, "rb") as f:
                text = f.read()
            problems += [f"{os.path.relpath(path, d.prefix)} names the hidden folder {h}"
                         for h in d.hidden if h.encode() in text]
    for rel in ("lib/gear_dynamics/end_launch.py", "share/gear_dynamics/scripts/plot_report.py",
                "share/gear_dynamics/LICENSE", "share/gear_dynamics/launch/paper.launch",
                "share/gear_dynamics/config/gear_pair.yaml", "lib/gear_dynamics/gear_aggregator"):
        if not os.path.exists(os.path.join(d.prefix, rel)):
            problems.append(f"{rel} is not installed")
    return problems


def case_finds_installed_package(d):
    """In the shell of the runs: the source tree and workspace folders are empty, and rospack finds the
    installed package only."""
    if d.installed():
        return ["not installed"]
    p = d.shell("rospack find gear_dynamics; echo \"RPP=$ROS_PACKAGE_PATH\"; echo \"visible=$(find "
                + " ".join(d.hidden) + " -mindepth 1 | wc -l)\"", timeout=60)
    lines = p.stdout.splitlines()
    expect = os.path.join(d.prefix, "share", "gear_dynamics")
    problems = [] if p.returncode == 0 and lines and lines[0] == expect else \
        [f"rospack find gear_dynamics gave {p.stdout!r}, expected {expect}"]
    if "visible=0" not in lines:
        problems.append(f"the hidden folders {d.hidden} are not empty in the runs' shell: {p.stdout}")
    if any(h in p.stdout for h in d.hidden):
        problems.append(f"the install space's ROS_PACKAGE_PATH names a hidden folder: {p.stdout}")
    return problems


def case_main_launch(d):
    """paper.launch (gear_monte_carlo, gear_aggregator with the figure script, end_launch.py) to its end."""
    if d.installed():
        return ["not installed"]
    batch = os.path.join(d.tmp, "batch")
    report = os.path.join(batch, "report")
    p = d.shell(f"roslaunch -p $PORT gear_dynamics paper.launch output_dir:={batch} realizations:=2 threads:=2",
                timeout=300)
    problems = []
    if p.returncode != 0 or "process has finished cleanly" not in p.stdout:
        problems.append(f"paper.launch exited {p.returncode}:\n{p.stdout[-4000:]}")
    for name in ("report.md", "fig06_delta.png"):
        if not os.path.exists(os.path.join(report, name)):
            have = sorted(os.listdir(report)) if os.path.isdir(report) else []
            problems.append(f"{report}/{name} missing (have {have})")
    return problems


def case_live_node(d):
    """simulate.launch tf:=true (gear_run's parse-time check and URDF, the node, at real time until
    stopped) publishes states, and robot_description holds the gear's joints."""
    if d.installed():
        return ["not installed"]
    script = ("roslaunch -p $PORT gear_dynamics simulate.launch tf:=true & launch=$!; "
              "timeout 60 bash -c 'until rostopic echo -n 1 /gear/state/header/seq; do sleep 0.5; done'; rc=$?; "
              "[ $rc -ne 0 ] || rosparam get /gear/robot_description | grep -q wheel_joint || rc=3; "
              "kill -INT $launch; wait $launch || true; exit $rc")
    p = d.shell(script, timeout=120)
    return [] if p.returncode == 0 else [f"no /gear/state or robot_description from the installed package "
                                         f"(exit {p.returncode}):\n{p.stdout[-4000:]}"]


def main():
    d = Install()
    cases = [("installs", case_installs), ("nothing_names_the_build", case_nothing_names_the_build),
             ("finds_installed_package", case_finds_installed_package), ("main_launch", case_main_launch),
             ("live_node", case_live_node)]
    failures = run_cases("install", [(name, lambda check=check: check(d)) for name, check in cases],
                         sys.argv[1] if len(sys.argv) > 1 else None)
    if failures:
        print(f"(kept: {d.tmp})")
        print("\n".join(d.log)[-8000:])
    else:
        shutil.rmtree(d.tmp, ignore_errors=True)
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
