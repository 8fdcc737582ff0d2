#!/usr/bin/env bash
# Sanitizer builds and runs. Each sanitizer builds the package in a workspace of its own, next to
# the normal one (<workspace>-asan, -tsan; CMake option GEAR_DYNAMICS_SANITIZE), and any report
# ends the process that made it, so it fails the run.
#
#   scripts/sanitize.sh           address, then thread
#   scripts/sanitize.sh address   ASan + UBSan: every gtest, then the fault suite's scripts
#                                 (test/faults: faults in a small batch, damaged bags read by the
#                                 aggregator, bad parameters through every node, reconfigure)
#   scripts/sanitize.sh thread    TSan: the TBB batch runner's gtests, a batch through
#                                 gear_monte_carlo on 2 threads, the simulator's reconfigure path
#   scripts/sanitize.sh --small   what CI runs: ASan + UBSan on the core only (gear_run: S1 and 4
#                                 stochastic realizations; the model's bad-configuration refusals)
set -euo pipefail
repo=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
supp=$repo/scripts/sanitizers

export ASAN_OPTIONS="abort_on_error=1:detect_leaks=1:strict_string_checks=1:detect_stack_use_after_return=1"
export LSAN_OPTIONS="suppressions=$supp/lsan.supp:print_suppressions=0"
export UBSAN_OPTIONS="print_stacktrace=1:halt_on_error=1"
export TSAN_OPTIONS="halt_on_error=1:second_deadlock_stack=1:suppressions=$supp/tsan.supp"

# Builds the sanitizer's workspace (targets: the rest of the arguments) and sources it, in the
# calling (sub)shell.
build() {
  local sanitizer=$1 suffix=$2
  shift 2
  GD_WS_SUFFIX=$suffix GD_BUILD_ARGS="-DGEAR_DYNAMICS_SANITIZE=$sanitizer $*" source "$repo/scripts/setup.sh"
}

# A batch of 2 mu x (S1 + 8 realizations), T = 0.05 s, on 2 threads, then the aggregator on it.
small_batch() {
  /usr/bin/python3 - "$repo/test/faults" <<'EOF'
import sys, tempfile
sys.path.insert(0, sys.argv[1])
import faultlib as fl
with tempfile.TemporaryDirectory() as d, fl.Master():
    p = fl.load_yaml(*[fl.config_file(f) for f in ("gear_pair.yaml", "load.yaml", "run.yaml", "monte_carlo.yaml")])
    p["run"].update({"duration": 0.05, "window": 0.01, "snapshot_times": [0.05]})
    p["monte_carlo"].update({"mu": [0.0, 0.04], "realizations": 8, "phase_ensemble": False, "threads": 2,
                             "block_lanes": 4, "record_rate": 10000.0, "output_dir": d + "/batch"})
    code, out = fl.run_node("gear_monte_carlo", "sanitized_batch", p, timeout=600)
    print(out[-2000:])
    assert code == 0, "gear_monte_carlo exited %s" % code
    code, out, runs, _ = fl.run_aggregator(d + "/batch", d + "/report", [0.05], timeout=600)
    print(out[-2000:])
    assert code == 0 and len(runs) == 18, "gear_aggregator exited %s with %d runs" % (code, len(runs))
EOF
}

address() {
  (
    build address,undefined -asan all tests
    cd "$GD_WS"
    rm -rf build/test_results
    catkin_make run_tests_gear_dynamics_gtest run_tests_gear_dynamics_faults -j1
    small_batch
    catkin_test_results --verbose build/test_results
    echo "sanitize: ASan + UBSan clean"
  )
}

thread() {
  (
    build thread -tsan test_core test_batch_io gear_monte_carlo gear_aggregator gear_simulator
    "$GD_WS/devel/lib/gear_dynamics/test_core" --gtest_filter='Batch*'
    "$GD_WS/devel/lib/gear_dynamics/test_batch_io"
    small_batch
    "$repo/test/faults/reconfigure.py"
    echo "sanitize: TSan clean"
  )
}

small() {
  (
    build address,undefined -asan gear_run test_bad_config
    "$GD_WS/devel/lib/gear_dynamics/gear_run" --set run.duration=0.05 --set run.window=0.01 --set "run.snapshot_times=[0.05]" \
      --realizations 4 --rate 0
    "$GD_WS/devel/lib/gear_dynamics/test_bad_config"
    echo "sanitize: ASan + UBSan clean (small: the core)"
  )
}

[ $# -gt 0 ] || set -- address thread
for mode in "$@"; do
  case $mode in
    address) address ;;
    thread) thread ;;
    --small) small ;;
    *) echo "usage: $0 [address] [thread] | --small" >&2; exit 2 ;;
  esac
done
