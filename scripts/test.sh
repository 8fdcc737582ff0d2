#!/usr/bin/env bash
# The README's test command: installs what is missing, builds, runs every gtest and rostest,
# and prints the totals. Exits non-zero on any failure.
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/setup.sh"

# Test-only tools (never installed by setup.sh/reproduce.sh): Slurm and munge for test/slurm, sshd
# for test/remote, tf2's Python API for the rostest simulator_joint_tf. Their services are not started by the install (a policy-rc.d that denies them is
# in place while it runs, if the machine has none); the tests start private daemons and say why
# they skip if these are missing.
GD_PACKAGES=(slurm-wlm munge openssh-server python3-tf2-ros python3-pytest qemu-user)  # qemu-user: test/isa
gd_policy=""
if [ ! -e /usr/sbin/policy-rc.d ] && [ "$(id -u)" -eq 0 ]; then
  printf '#!/bin/sh\nexit 101\n' > /usr/sbin/policy-rc.d && chmod 755 /usr/sbin/policy-rc.d && gd_policy=1
fi
(gd_install) || echo "test.sh: could not install ${GD_PACKAGES[*]}; test/slurm and test/remote will say what they skip"
[ -z "$gd_policy" ] || rm -f /usr/sbin/policy-rc.d

rm -rf "$GD_WS/build/test_results"
mkdir -p "$GD_WS/build/test_results/gear_dynamics"
status=0
# The fault suite's sanitizer cases build workspaces of their own, so they run here, not as a target.
# Their builds and runs are CPU work (minutes; bench/README.md §7) while
# the tests below wait on masters, launches, timers and Slurm much of the time: they run beside them
# at the lowest priority (nice 19), taking what CPU the tests leave, and their log follows at the end.
sanitizer_log=$(mktemp)
nice -n 19 /usr/bin/python3 "$GD_REPO/test/faults/sanitizers.py" \
  "$GD_WS/build/test_results/gear_dynamics/faults-sanitizers.xml" >"$sanitizer_log" 2>&1 &
sanitizers=$!
# Every test binary is built first, then setup.sh's build is stamped again: from here on nothing
# builds in the workspace while tests run in it (a documented command that sources setup.sh finds
# the build current and skips catkin_make).
(cd "$GD_WS" && catkin_make tests -j"$(nproc)") || status=$?
gd_build "${gd_build_args[@]}" >/dev/null || status=$?
# Every command line of the docs, as typed (test/docs/run_doc_commands.py), beside catkin's tests:
# both wait much of the time (masters, launches, timers, Slurm), and each block and test has a
# master of its own. Not a catkin target: a documented command may run catkin_make itself. At
# nice 10 the tests come first when both want the CPU; their log follows catkin's.
doc_log=$(mktemp)
nice -n 10 /usr/bin/python3 "$GD_REPO/test/docs/run_doc_commands.py" \
  "$GD_WS/build/test_results/gear_dynamics/doc-commands.xml" >"$doc_log" 2>&1 &
doc_commands=$!
(cd "$GD_WS" && catkin_make run_tests -j"$(nproc)") || status=$?
wait "$doc_commands" || status=1
cat "$doc_log"
rm -f "$doc_log"
# setup.sh's skip of catkin_make when nothing changed, and its rebuild when something did (it runs
# catkin_make, so here too).
/usr/bin/python3 "$GD_REPO/test/setup/build_check.py" "$GD_WS/build/test_results/gear_dynamics/setup-build_check.xml" ||
  status=1
wait "$sanitizers" || status=1
cat "$sanitizer_log"
rm -f "$sanitizer_log"
echo
catkin_test_results --verbose "$GD_WS/build/test_results" || status=1
# The fault suite's table: cases tried and passed per category (test/faults/summary.py).
/usr/bin/python3 "$GD_REPO/test/faults/summary.py" "$GD_WS/build/test_results" || status=1
# What failed, by name, at the end of the log where CI shows it.
/usr/bin/python3 "$GD_REPO/test/list_failures.py" "$GD_WS/build/test_results"
exit $status
