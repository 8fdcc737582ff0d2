#!/usr/bin/env bash
# The README's main command: installs what is missing, builds, and reproduces the paper's §3:
# the default Monte Carlo batch, then the aggregator's report (launch/paper.launch).
#   GD_OUTPUT  batch folder (default: batches/paper in the repository); re-running resumes it
#   GD_REPORT  report folder (default: report/ in the repository)
# Extra arguments go to roslaunch, e.g. realizations:=1000, or study:=noise (a study of config/studies/)
# or study:=my_study.yaml (a file of your own).
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/setup.sh"

# study:=NAME runs config/studies/NAME.yaml (doc/studies.md) into batches/study-NAME and report/study-NAME;
# study:=PATH (containing / or ending in .yaml) runs your own study file, named after its base name.
study=
own=
args=()
for a in "$@"; do
  case $a in
    study:=*)
      study=${a#study:=}
      if [[ $study == */* || $study == *.yaml ]]; then
        [ -f "$study" ] || { echo "reproduce: no study file $study" >&2; exit 2; }
        own=$(cd "$(dirname "$study")" && pwd)/$(basename "$study")  # roslaunch runs elsewhere
        a="study:=$own"
        study=$(basename "$study" .yaml)
      fi ;;
  esac
  args+=("$a")
done
set -- "${args[@]+"${args[@]}"}"
if [ -n "$study" ]; then
  [ -n "$own" ] || [ -f "$GD_REPO/config/studies/$study.yaml" ] ||
    { echo "reproduce: no study config/studies/$study.yaml (or give a path to your own file)" >&2; exit 2; }
  batch=${GD_OUTPUT:-$GD_REPO/batches/study-$study}
  report=${GD_REPORT:-$GD_REPO/report/study-$study}
else
  batch=${GD_OUTPUT:-$GD_REPO/batches/paper}
  report=${GD_REPORT:-$GD_REPO/report}
fi
mkdir -p "$batch" "$report"
# A master of our own on a free port: never another user's roscore (and its node names).
port=$(/usr/bin/python3 -c 'import socket; s = socket.socket(); s.bind(("", 0)); print(s.getsockname()[1])')
export ROS_MASTER_URI=http://localhost:$port
rm -f "$report/report.md"
start=$(date +%s)
log=$(mktemp)
trap 'rm -f "$log"' EXIT
# roslaunch 1.15 exits 0 when a node fails, and the aggregator reads whatever complete bags the
# folder holds: the command succeeds only if the batch node ended with exit code 0 (roslaunch says
# "finished cleanly"), not after a refusal (exit 2), a stop (128 + n) or a crash.
# SETUPTOOLS_USE_DISTUTILS=stdlib: roslaunch imports rosclean, which imports distutils, and
# setuptools' distutils hook answers that by importing all of setuptools (about 40 % of roslaunch's
# start-up CPU); Python's own distutils serves rosclean the same.
SETUPTOOLS_USE_DISTUTILS=stdlib roslaunch -p "$port" gear_dynamics paper.launch output_dir:="$batch" report_folder:="$report" "$@" 2>&1 | tee "$log"
if ! grep -q '\[gear_monte_carlo-[0-9]*\] process has finished cleanly' "$log"; then
  echo "reproduce: gear_monte_carlo did not finish cleanly (see above); $report holds no report of this run" >&2
  rm -f "$report/report.md"
  exit 1
fi
[ -f "$report/report.md" ] || { echo "reproduce: no report was written (see the log above)" >&2; exit 1; }
echo "reproduce: report $report/report.md, figures $report/fig*.png ($(( $(date +%s) - start )) s)"
