#!/usr/bin/python3
"""The sanitizer cases of the fault suite, run by scripts/test.sh beside the other tests (they build
workspaces of their own, so they are not a catkin test target). Each case is one mode of
scripts/sanitize.sh and fails on any sanitizer report:

  sanitizer_address  core-address: the core library, its gtests and gear_run built with
                     -fsanitize=address,undefined; the core gtests (less four long ones)
                     and a short stochastic gear_run
  sanitizer_thread   core-thread: the same built with -fsanitize=thread against a libtbb built with
                     it too; the batch runner's gtests (TBB, 1 and 2 threads, shards)

--slow (GD_FAULTS_SLOW=1) runs the whole package instead (modes address and thread: every gtest,
the fault scripts, a batch through gear_monte_carlo, the simulator's reconfigure path)."""
import os
import subprocess
import time

import faultlib as fl

REPO = os.path.realpath(os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", ".."))
# The sanitizer workspaces must not chain onto the normal one that scripts/test.sh sourced.
KEEP = ("HOME", "XDG_CACHE_HOME", "LANG", "LC_ALL", "TERM")


def run(suite):
    env = {k: os.environ[k] for k in KEEP if k in os.environ}
    env["PATH"] = "/usr/bin:/bin:/usr/sbin:/sbin"
    modes = ("address", "thread") if suite.args.slow else ("core-address", "core-thread")
    for mode in modes:
        with suite.case("sanitizer_" + mode.split("-")[-1], mode):
            start = time.time()
            p = subprocess.run(["bash", os.path.join(REPO, "scripts", "sanitize.sh"), mode], env=env,
                               stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
            print("\n".join(p.stdout.splitlines()[-15:]))
            print("  scripts/sanitize.sh %s: exit %d after %.0f s" % (mode, p.returncode, time.time() - start))
            assert p.returncode == 0, "scripts/sanitize.sh %s exited %d:\n%s" % (mode, p.returncode, p.stdout[-6000:])


if __name__ == "__main__":
    suite = fl.Suite("sanitizers")
    run(suite)
    raise SystemExit(suite.finish())
