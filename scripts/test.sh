#!/usr/bin/env bash
# The README's test command: installs what is missing, builds, runs every gtest and rostest,
# and prints the totals. Exits non-zero on any failure.
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/setup.sh"

rm -rf "$GD_WS/build/test_results"
status=0
(cd "$GD_WS" && catkin_make run_tests -j"$(nproc)") || status=$?
echo
catkin_test_results --verbose "$GD_WS/build/test_results" || status=1
exit $status
