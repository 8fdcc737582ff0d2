#!/usr/bin/env bash
# The README's main command: installs what is missing, builds, and runs the main job with the
# defaults in config/.
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/setup.sh"

out=${GD_OUTPUT:-$GD_REPO/report}
mkdir -p "$out"
rosrun gear_dynamics gear_run --output "$out/gear_run.csv" "$@"
echo "series written to $out/gear_run.csv"
