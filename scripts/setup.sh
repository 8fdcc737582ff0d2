#!/usr/bin/env bash
# Installs the Debian packages gear_dynamics needs (only the missing ones) and builds the catkin
# workspace out of the source tree (GD_WS, default ~/.cache/gear_dynamics/<repo path hash>), then
# sources it. Sourced by reproduce.sh and test.sh, or by a user's interactive shell, whose options
# it restores at the end (a failing command must not close that shell afterwards).
gd_shell_options=$(set +o)
set -euo pipefail

GD_REPO=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
# Outside the repo: a workspace inside it would make src/gear_dynamics a symlink loop for the
# tools that follow links (rosrun's find -L). GD_WS_SUFFIX names a sibling workspace (the
# sanitizer builds of scripts/sanitize.sh).
GD_WS=${GD_WS:-${XDG_CACHE_HOME:-$HOME/.cache}/gear_dynamics/ws-$(echo -n "$GD_REPO" | md5sum | cut -c1-12)${GD_WS_SUFFIX:-}}

# catkin's helpers need Debian's python3 (with catkin_pkg, rospkg, genmsg); a pyenv or venv
# python3 first on PATH breaks them ("No module named ..."), so Debian's goes first.
export PATH=/usr/bin:/bin:/usr/sbin:/sbin:$PATH
unset PYTHONPATH PYTHONHOME VIRTUAL_ENV PYENV_VERSION

GD_PACKAGES=(
  build-essential cmake catkin python3-catkin-pkg ros-core-dev ros-message-generation
  libdynamic-reconfigure-config-init-mutex-dev python3-dynamic-reconfigure
  librosbag-dev libroslz4-dev python3-rosbag librostest-dev python3-rostest python3-rostopic python3-rosservice python3-tf2-ros
  python3-rosnode python3-rosparam rosbash rosout
  libdiagnostic-updater-dev libdiagnostic-msgs-dev python3-diagnostic-msgs libstd-srvs-dev ros-std-srvs python3-std-srvs
  libros-rosgraph-msgs-dev libsensor-msgs-dev python3-sensor-msgs ros-robot-state-publisher liburdfdom-dev libtf2-ros-dev libmessage-filters-dev
  libeigen3-dev librandom123-dev libtbb-dev libyaml-cpp-dev libgtest-dev libbenchmark-dev libboost-dev libcli11-dev
  python3-matplotlib python3-numpy python3-scipy
  pybind11-dev python3-pybind11 python3-yaml python3-setuptools
  ccache
)

gd_install() {
  # One dpkg-query for all and no process per package (each is slow); an unknown package is not listed.
  local -A installed=()
  local p missing=()
  while read -r p; do installed[$p]=1; done < <(dpkg-query -W -f='${Package} ${Status}\n' "${GD_PACKAGES[@]}" \
    2>/dev/null | sed -n 's/ install ok installed$//p' || true)
  for p in "${GD_PACKAGES[@]}"; do
    [ -n "${installed[$p]:-}" ] || missing+=("$p")
  done
  if [ ${#missing[@]} -gt 0 ]; then
    echo "setup: installing ${missing[*]}"
    local sudo=""
    [ "$(id -u)" -eq 0 ] || sudo=sudo
    $sudo apt-get update -q
    DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -q --no-install-recommends "${missing[@]}"
  fi
}

# Whether the last build with these arguments is still current, so that catkin_make (seconds to
# find nothing to do) can be skipped: no file of the repository (but .git, batches/ and report/,
# the main command's outputs) is newer than that build's start, no Debian package was installed or
# upgraded since (dpkg's status file), and the workspace's CMake cache and binary folders were not
# changed after it (a cmake re-run, a clean, other targets). Otherwise catkin_make decides.
gd_build_current() {
  local start=$GD_WS/.gd_build_start done=$GD_WS/.gd_build_done f
  [ -f "$start" ] && [ -f "$done" ] && [ "$(cat "$done")" = "$*" ] && [ ! "$start" -nt "$done" ] || return 1
  [ -f "$GD_WS/devel/setup.bash" ] && [ ! /var/lib/dpkg/status -nt "$start" ] || return 1
  for f in "$GD_WS/build/CMakeCache.txt" "$GD_WS/devel/lib" "$GD_WS/devel/lib/gear_dynamics"; do
    [ -e "$f" ] && [ ! "$f" -nt "$done" ] || return 1
  done
  [ -z "$(find "$GD_REPO" \( -path "$GD_REPO/.git" -o -path "$GD_REPO/batches" -o -path "$GD_REPO/report" \) \
            -prune -o -newer "$start" -print -quit)" ]
}

gd_build() {
  mkdir -p "$GD_WS/src"
  ln -sfn "$GD_REPO" "$GD_WS/src/gear_dynamics"
  if gd_build_current "$@"; then
    echo "setup: nothing changed since the last build ($GD_WS/.gd_build_done)"
  else
    # The start is stamped before catkin_make reads anything: a file edited during the build is
    # newer and so rebuilds next time. The stamp of a success comes after it, with the arguments.
    touch "$GD_WS/.gd_build_start"
    (cd "$GD_WS" && catkin_make -DCMAKE_BUILD_TYPE=Release -DPYTHON_EXECUTABLE=/usr/bin/python3 \
       "${gd_launcher[@]}" -j"$(nproc)" "$@")
    echo "$*" > "$GD_WS/.gd_build_done"
  fi
  # shellcheck disable=SC1091
  set +u; source "$GD_WS/devel/setup.bash"; set -u
  echo "setup: workspace $GD_WS"
}

gd_install
# Compiles through ccache: a rebuild, or the build of another clone of the same sources (paths are
# hashed relative to the workspace), compiles only what changed. The sloppiness lets it cache the
# compiles that read the test programs' precompiled header. GD_CCACHE=0 compiles directly.
gd_launcher=(-DCMAKE_C_COMPILER_LAUNCHER= -DCMAKE_CXX_COMPILER_LAUNCHER=)  # CMake's cache keeps the last
if [ "${GD_CCACHE:-1}" != 0 ] && command -v ccache >/dev/null; then
  export CCACHE_BASEDIR=$GD_WS CCACHE_NOHASHDIR=1
  export CCACHE_SLOPPINESS=pch_defines,time_macros,include_file_mtime,include_file_ctime
  gd_launcher=(-DCMAKE_C_COMPILER_LAUNCHER=ccache -DCMAKE_CXX_COMPILER_LAUNCHER=ccache)
fi
# GD_BUILD_ARGS: extra catkin_make arguments (CMake options, targets), e.g. from scripts/sanitize.sh.
read -ra gd_build_args <<< "${GD_BUILD_ARGS:-}"
gd_build "${gd_build_args[@]}"
eval "$gd_shell_options"
unset gd_shell_options
