#!/usr/bin/env bash
# roslaunch's env-loader for a <machine> (launch/remote_simulator.launch): sources the workspace
# this repository was built into by scripts/setup.sh on THIS machine (the same default path:
# GD_WS, or ~/.cache/gear_dynamics/ws-<hash of the repository path>), then runs its arguments
# (roslaunch's child process). roslaunch runs it over SSH in a login-less environment, so it may
# rely on nothing but this file. On a machine with another layout, write your own two lines:
#   source /path/to/workspace/devel/setup.bash
#   exec "$@"
repo=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd -P)
ws=${GD_WS:-${XDG_CACHE_HOME:-$HOME/.cache}/gear_dynamics/ws-$(echo -n "$repo" | md5sum | cut -c1-12)}
if [ ! -f "$ws/devel/setup.bash" ]; then
  echo "remote_env.sh: no workspace at $ws (run scripts/setup.sh on $(hostname) first)" >&2
  exit 1
fi
export PATH=/usr/bin:/bin:/usr/sbin:/sbin:$PATH  # Debian's python3 for catkin's tools (as setup.sh)
# shellcheck disable=SC1091
source "$ws/devel/setup.bash"
exec "$@"
