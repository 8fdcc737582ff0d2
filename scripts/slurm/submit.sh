#!/usr/bin/env bash
# Submits a sharded gear_monte_carlo batch to Slurm as a job array (one shard per task) and the
# aggregator as a job that starts when every task has succeeded (--dependency=afterok). Run it on
# the login node with the workspace sourced (source scripts/setup.sh); the batch folder must be on
# a filesystem every compute node sees. Running it again with the same arguments resumes: finished
# bags are kept, unfinished ones (*.bag.active of a failed or cancelled task) are redone.
#
#   scripts/slurm/submit.sh STUDY.yaml --shards 16 [options] [-- extra sbatch options]
#     STUDY.yaml        YAML overlaid on config/*.yaml for the batch (sections run, monte_carlo, ...);
#                       "" for the package's defaults
#     --shards N        array tasks (shards), default 16
#     --cpus N          threads per task (--cpus-per-task), default 1
#     --output DIR      batch folder (shared), default ./batches/<study name>
#     --report DIR      report folder, default <output>/report
#     --analysis FILE   YAML overlaid on config/aggregator.yaml (analysis section)
#     --time T          time limit of each task (sbatch --time), default 01:00:00
#     --mem M           memory of each task (sbatch --mem), default: the partition's
#     --no-plot         no figures (the aggregator's plot:=false)
#     --logs DIR        where the job logs go, default <output>/../<name>_slurm_logs
# Prints the two job ids ("array JOBID" and "aggregate JOBID").
set -euo pipefail
usage() { sed -n '2,20p' "$0" | sed 's/^# \{0,1\}//'; exit "${1:-2}"; }

[ $# -ge 1 ] || usage
case $1 in -h|--help) usage 0 ;; esac
study=$1; shift
shards=16 cpus=1 output="" report="" analysis="" time=01:00:00 mem="" plot=true logs=""
extra=()
while [ $# -gt 0 ]; do
  case $1 in
    --shards) shards=$2; shift 2 ;;
    --cpus) cpus=$2; shift 2 ;;
    --output) output=$2; shift 2 ;;
    --report) report=$2; shift 2 ;;
    --analysis) analysis=$2; shift 2 ;;
    --time) time=$2; shift 2 ;;
    --mem) mem=$2; shift 2 ;;
    --no-plot) plot=false; shift ;;
    --logs) logs=$2; shift 2 ;;
    --) shift; extra=("$@"); break ;;
    -h|--help) usage 0 ;;
    *) echo "submit: unknown argument '$1'" >&2; usage ;;
  esac
done
[[ $shards =~ ^[1-9][0-9]*$ ]] || { echo "submit: --shards must be a positive integer" >&2; exit 2; }
[[ $cpus =~ ^[1-9][0-9]*$ ]] || { echo "submit: --cpus must be a positive integer" >&2; exit 2; }
abs() { [ -z "$1" ] && return; (cd "$(dirname "$1")" && echo "$(pwd)/$(basename "$1")"); }
if [ -n "$study" ]; then
  [ -f "$study" ] || { echo "submit: no file '$study'" >&2; exit 2; }
  study=$(abs "$study")
fi
if [ -n "$analysis" ]; then
  [ -f "$analysis" ] || { echo "submit: no file '$analysis'" >&2; exit 2; }
  analysis=$(abs "$analysis")
fi
name=$(basename "${study:-default}" .yaml)
output=${output:-$PWD/batches/$name}
mkdir -p "$output"
output=$(cd "$output" && pwd)
# Not created here: a folder inside the batch folder before any manifest would make the first shard
# refuse it ("not empty and holds no manifest"); the aggregator job creates it.
report=${report:-$output/report}
[[ $report = /* ]] || report=$PWD/$report
logs=${logs:-$(dirname "$output")/${name}_slurm_logs}
mkdir -p "$logs"
logs=$(cd "$logs" && pwd)

command -v sbatch > /dev/null || { echo "submit: sbatch not found (run on the cluster's login node)" >&2; exit 2; }
# The tasks source the same workspace as this shell (the first entry of CMAKE_PREFIX_PATH, the
# devel or install space that `source .../setup.bash` put there), so they do not depend on
# sbatch's environment export.
setup=""
if [ -n "${CMAKE_PREFIX_PATH:-}" ] && [ -f "${CMAKE_PREFIX_PATH%%:*}/setup.bash" ]; then
  setup=${CMAKE_PREFIX_PATH%%:*}/setup.bash
fi
command -v roslaunch > /dev/null && [ -n "$setup" ] ||
  { echo "submit: source the workspace first (source scripts/setup.sh)" >&2; exit 2; }

here=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
export GD_OUTPUT=$output GD_REPORT=$report GD_CONFIG=$study GD_ANALYSIS=$analysis GD_SHARDS=$shards \
  GD_SETUP=$setup GD_PLOT=$plot
common=(--parsable --export=ALL --time="$time")
[ -n "$mem" ] && common+=(--mem="$mem")
array=$(sbatch "${common[@]}" --array=0-$((shards - 1)) --cpus-per-task="$cpus" \
  --output="$logs/batch_%A_%a.log" "${extra[@]}" "$here/batch_task.sbatch")
array=${array%%;*}
aggregate=$(sbatch "${common[@]}" --cpus-per-task=1 --dependency=afterok:"$array" --kill-on-invalid-dep=yes \
  --output="$logs/aggregate_%j.log" "${extra[@]}" "$here/aggregate.sbatch")
aggregate=${aggregate%%;*}
echo "array $array"
echo "aggregate $aggregate"
echo "submit: $shards shards of '${study:-defaults}' into $output, report $report, logs $logs" >&2
