#!/usr/bin/env bash
# Sanitizer builds and runs. Each sanitizer builds the package in a workspace of its own, next to
# the normal one (<workspace>-asan, -tsan; CMake option GEAR_DYNAMICS_SANITIZE), and any report
# ends the process that made it, so it fails the run.
#
#   scripts/sanitize.sh           address, then thread
#   scripts/sanitize.sh address   ASan + UBSan: every gtest, then the fault suite's scripts
#                                 (test/faults: faults in a small batch, damaged bags read by the
#                                 aggregator, bad parameters through every node, reconfigure)
#   scripts/sanitize.sh thread    TSan (with an instrumented libtbb, see below): the TBB batch
#                                 runner's gtests, a batch through gear_monte_carlo on 2 threads,
#                                 the simulator's reconfigure path
#   scripts/sanitize.sh core-address, core-thread
#                                 what CI runs (test/faults/sanitizers.py): the core's gtests and a
#                                 short gear_run under ASan + UBSan; the batch runner's under TSan
set -euo pipefail
repo=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)

export ASAN_OPTIONS="abort_on_error=1:detect_leaks=1:strict_string_checks=1:detect_stack_use_after_return=1"
export UBSAN_OPTIONS="print_stacktrace=1:halt_on_error=1"
export TSAN_OPTIONS="halt_on_error=1:second_deadlock_stack=1:ignore_noninstrumented_modules=1"

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

# Debian's libtbb is not instrumented: TSan cannot see TBB's own synchronization (task hand-over,
# the join) and reports races on everything a task touches (78 reports in test_core's batch tests).
# So the TSan runs use oneTBB built from the Debian source of the installed libtbb12, with
# -fsanitize=thread (once, about a minute; fetched by apt-get from the system's repositories through
# a private source list, the system's apt configuration is not changed). ignore_noninstrumented_modules
# keeps TSan from reporting on memory that the uninstrumented ROS libraries touch (roscpp's shared
# buffers) while it still checks every access made by our code.
instrumented_tbb() {
  local package version dir
  package=$(dpkg-query -W -f='${source:Package}' libtbb12)
  version=$(dpkg-query -W -f='${Version}' libtbb12)
  dir=${XDG_CACHE_HOME:-$HOME/.cache}/gear_dynamics/tbb-tsan-$version
  if [ ! -e "$dir/lib/libtbb.so.12" ]; then
    echo "sanitize: building $package $version with -fsanitize=thread into $dir" >&2
    rm -rf "$dir"
    mkdir -p "$dir/apt/lists/partial" "$dir/apt/sources.list.d" "$dir/src" "$dir/build"
    # The system's own repositories (its mirror or snapshot), as source repositories.
    local f
    for f in /etc/apt/sources.list /etc/apt/sources.list.d/*.list; do
      if [ -e "$f" ]; then sed -nE 's/^deb (.*)/deb-src \1/p' "$f" >> "$dir/apt/sources.list"; fi
    done
    for f in /etc/apt/sources.list.d/*.sources; do
      if [ -e "$f" ]; then sed -E 's/^Types:.*/Types: deb-src/' "$f" > "$dir/apt/sources.list.d/${f##*/}"; fi
    done
    local apt=(apt-get -q -o Dir::Etc::SourceList="$dir/apt/sources.list"
               -o Dir::Etc::SourceParts="$dir/apt/sources.list.d" -o Dir::State::Lists="$dir/apt/lists")
    "${apt[@]}" update >&2
    (cd "$dir/src" && "${apt[@]}" source --download-only "$package=$version" >&2 &&
       dpkg-source -x ./*.dsc tbb >&2)
    cmake -S "$dir/src/tbb" -B "$dir/build" -DCMAKE_BUILD_TYPE=RelWithDebInfo -DTBB_TEST=OFF \
      -DTBB_EXAMPLES=OFF -DTBBMALLOC_BUILD=OFF -DTBB_STRICT=OFF -DTBB_SANITIZE=thread >&2
    make -C "$dir/build" -j"$(nproc)" tbb >&2
    mkdir -p "$dir/lib"
    cp -P "$dir"/build/*/libtbb.so* "$dir/lib/"
  fi
  echo "$dir/lib"
}

thread() {
  (
    tbb=$(instrumented_tbb)
    build thread -tsan test_core test_live_simulation test_batch_io gear_monte_carlo gear_aggregator gear_simulator \
      gear_dynamics_generate_messages_py
    export LD_LIBRARY_PATH=$tbb${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}
    "$GD_WS/devel/lib/gear_dynamics/test_core" --gtest_filter='Batch*'
    "$GD_WS/devel/lib/gear_dynamics/test_batch_io"
    "$GD_WS/devel/lib/gear_dynamics/test_live_simulation"
    small_batch
    "$repo/test/faults/reconfigure.py"
    echo "sanitize: TSan clean"
  )
}

# What CI runs (test/faults/sanitizers.py, from scripts/test.sh): the core alone, about 3 minutes
# each from scratch on 2 cores (the instrumented libtbb included).
core_address() {
  (
    build address,undefined -asan test_core test_live_simulation gear_run
    "$GD_WS/devel/lib/gear_dynamics/test_live_simulation"
    # Less four long tests (2 minutes here under ASan): two sampling tests and two study tests, whose
    # code the others step too (the batch runner, the sweep).
    "$GD_WS/devel/lib/gear_dynamics/test_core" \
      --gtest_filter='-Analytic.LoadProcessMoments:Batch.LoadStatisticsAtTheSnapshotTimes:Study.KeyWithoutEffectGivesIdenticalResults:Study.LoadAxesShiftPhiAsTheSdePredicts'
    "$GD_WS/devel/lib/gear_dynamics/gear_run" --set run.duration=0.05 --set run.window=0.01 \
      --set "run.snapshot_times=[0.05]" --realizations 4 --rate 0
    echo "sanitize: ASan + UBSan clean (the core)"
  )
}

core_thread() {
  (
    tbb=$(instrumented_tbb)
    build thread -tsan test_batch_runner test_live_simulation
    LD_LIBRARY_PATH=$tbb${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH} \
      "$GD_WS/devel/lib/gear_dynamics/test_batch_runner"
    # The live simulation's hand-off between a caller and its loop thread.
    "$GD_WS/devel/lib/gear_dynamics/test_live_simulation"
    echo "sanitize: TSan clean (the core's batch runner and the live loop)"
  )
}

[ $# -gt 0 ] || set -- address thread
for mode in "$@"; do
  case $mode in
    address) address ;;
    thread) thread ;;
    core-address) core_address ;;
    core-thread) core_thread ;;
    *) echo "usage: $0 [address | thread | core-address | core-thread]..." >&2; exit 2 ;;
  esac
done
