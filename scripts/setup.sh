#!/usr/bin/env bash
# Set up everything py_vision needs on a PC with only Python 3, then build the package:
#   .venv/    pinned ROS 2 Jazzy wheels, OpenCV, numpy, colcon (requirements*.txt)
#   install/  the colcon-installed package, exactly what `ros2 run` would execute
# With --board, instead: the boards' software in .venv-board/: Python 3.10 with their numpy
# 1.23.3 and OpenCV 4.6.0 (requirements-board.txt), their ROS 2 Humble unpacked from its tarball
# into .venv-board/humble/, and the package built against it into .venv-board/install/
# (scripts/test.sh's board-version run; scripts/board_env.sh is that environment). Python 3.10
# is $PYTHON310 if set, else python3.10 on PATH, else pyenv's newest 3.10; without one it exits
# with status 3. The Humble tarball (ros-humble-*.tar.zst, see find_humble) is
# $PY_VISION_HUMBLE if set, else looked for in ../shared/humble; without one it exits with
# status 4. Its shared libraries come from Debian (scripts/test.sh installs them).
# Safe to run again: it only does what is missing or out of date.
# Usage: scripts/setup.sh [--test | --board]
#   (--test also installs the test and benchmark tools)
set -euo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
cd "$root"

# Print the first working Python 3.10 (PYTHON310, python3.10 on PATH, pyenv's versions/3.10.*).
# A pyenv shim named python3.10 exists even when that version is not selected, and then fails:
# every candidate is run, not just looked up. A PYTHON310 that is not Python 3.10 is an error.
find_python310() {
  local candidate version
  if [ -n "${PYTHON310:-}" ]; then
    version=$("$PYTHON310" -c 'import sys; print("%d.%d" % sys.version_info[:2])' 2>/dev/null) \
      || version=none
    if [ "$version" != 3.10 ]; then
      echo "[setup] PYTHON310=$PYTHON310 is not a working Python 3.10 (it reports: $version)" >&2
      exit 1
    fi
    echo "$PYTHON310"
    return
  fi
  local pyenv_root
  pyenv_root=$(pyenv root 2>/dev/null) || pyenv_root=${PYENV_ROOT:-$HOME/.pyenv}
  # Newest patch release first: sort -V orders 3.10.9 before 3.10.13.
  for candidate in python3.10 $(ls -d "$pyenv_root"/versions/3.10.*/bin/python3.10 2>/dev/null \
      | sort -rV); do
    version=$("$candidate" -c 'import sys; print("%d.%d" % sys.version_info[:2])' 2>/dev/null) \
      || continue
    if [ "$version" = 3.10 ]; then
      command -v "$candidate"
      return
    fi
  done
  return 3
}

# Print the Humble tarball in $1: $1 itself, or the newest ros-humble-*.tar.zst in that folder.
humble_tarball_in() {
  local found
  if [ -f "$1" ]; then
    echo "$1"
    return
  fi
  found=$(ls -t "$1"/ros-humble-*.tar.zst 2>/dev/null | head -1)
  [ -n "$found" ] && echo "$found"
}

# Print the boards' ROS 2 Humble tarball: $PY_VISION_HUMBLE (the tarball or its folder), else
# ../shared/humble beside this checkout, beside the main checkout of this worktree, or beside
# the repository this one was cloned from when that is a folder on this machine (CI and
# `git clone . "$(mktemp -d)"` clone into a temporary directory). Status 4 when there is none.
find_humble() {
  local origin common
  if [ -n "${PY_VISION_HUMBLE:-}" ]; then
    humble_tarball_in "$PY_VISION_HUMBLE" && return
    echo "[setup] PY_VISION_HUMBLE=$PY_VISION_HUMBLE is neither a Humble tarball" \
      '(ros-humble-*.tar.zst) nor a folder with one' >&2
    exit 1
  fi
  humble_tarball_in "$root/../shared/humble" && return
  common=$(git -C "$root" rev-parse --path-format=absolute --git-common-dir 2>/dev/null) \
    && humble_tarball_in "$(dirname "$common")/../shared/humble" && return
  origin=$(git -C "$root" remote get-url origin 2>/dev/null) || return 4
  origin=${origin#file://}
  case $origin in /*) ;; *) origin=$root/$origin ;; esac
  [ -d "$origin" ] && humble_tarball_in "$origin/../shared/humble" && return
  return 4
}

# Unpack the Humble tarball $1 into .venv-board/humble (again only when the tarball changed).
unpack_humble() {
  local stamp
  stamp=.venv-board/humble/.unpacked-$(sha1sum "$1" | cut -c1-12)
  [ -f "$stamp" ] && return
  command -v zstd >/dev/null 2>&1 \
    || { echo '[setup] zstd is missing, to unpack ROS 2 Humble (apt-get install zstd)' >&2; exit 1; }
  echo "[setup] unpacking ROS 2 Humble from $1 into .venv-board/humble"
  rm -rf .venv-board/humble
  mkdir -p .venv-board/humble
  zstd -dc "$1" | tar -x -C .venv-board/humble
  touch "$stamp"
}

# Check that Humble starts in the board environment (sourced); if not, say which shared
# libraries it lacks (from Debian; scripts/test.sh installs them as root).
check_humble() {
  local lib=.venv-board/humble/install/lib missing
  python -c 'import launch_ros, rclpy; rclpy.init(args=[]); rclpy.shutdown()' && return
  # What rclpy and the DDS it loads at init need; the Python library is the interpreter's.
  missing=$(LD_LIBRARY_PATH=$lib:$(python -c 'import sysconfig; print(sysconfig.get_config_var("LIBDIR"))') \
    ldd $lib/python3.10/site-packages/rclpy/*.so $lib/librcl.so $lib/librmw_fastrtps_cpp.so \
    2>/dev/null | grep 'not found' | awk '{print $1}' | sort -u | paste -sd' ') || true
  echo "[setup] ROS 2 Humble does not start in .venv-board (see above)${missing:+; it needs" \
    "these shared libraries: $missing (Debian 12: apt-get install libspdlog1.10 libfmt9" \
    "libtinyxml2-9 libyaml-0-2 libssl3)}" >&2
  exit 1
}

venv=.venv
out=.   # where build/, install/, log/ and log-colcon.txt go
base=requirements.txt
reqs=$base
python=${PYTHON:-python3}
case "${1:-}" in
  --test) reqs=requirements-test.txt ;;
  --board)
    venv=.venv-board; out=.venv-board; base=requirements-board.txt; reqs=$base
    found=0
    python=$(find_python310) || found=$?
    if [ "$found" = 3 ]; then
      echo '[setup] no Python 3.10 found (tried $PYTHON310, python3.10 on PATH, and' \
        "$(pyenv root 2>/dev/null || echo "${PYENV_ROOT:-$HOME/.pyenv}")/versions/3.10.*):" \
        'install one (e.g. pyenv install 3.10) or name it with PYTHON310=/path/to/python3.10' >&2
      exit 3
    fi
    [ "$found" = 0 ] || exit 1
    found=0
    humble=$(find_humble) || found=$?
    if [ "$found" = 4 ]; then
      echo "[setup] the boards' ROS 2 Humble (ros-humble-*.tar.zst) was not found: name it" \
        'with PY_VISION_HUMBLE=/path/to/it, or put it in ../shared/humble beside this' \
        'checkout (how it is built: docs/tests.md#the-board-version-run)' >&2
      exit 4
    fi
    [ "$found" = 0 ] || exit 1
    # A venv left from another interpreter (3.10 removed, or another minor version) is rebuilt.
    if [ -x $venv/bin/python ] \
        && ! $venv/bin/python -c 'import sys; sys.exit(sys.version_info[:2] != (3, 10))'; then
      echo "[setup] $venv is not on Python 3.10: recreating it"
      rm -rf $venv
    fi
    ;;
  '') ;;
  *) echo "usage: scripts/setup.sh [--test | --board]" >&2; exit 2 ;;
esac

if [ ! -x $venv/bin/python ]; then
  echo "[setup] creating $venv with $($python --version 2>&1) ($python)"
  "$python" -m venv $venv
fi
stamp=$venv/.installed-$(cat $base "$reqs" | sha1sum | cut -c1-12)
if [ ! -f "$stamp" ]; then
  echo "[setup] installing $reqs into $venv"
  # pip's notes about unused local index locations, and the older pip of a Python 3.10 venv
  # about legacy setup.py installs, are noise; real errors still show.
  $venv/bin/python -m pip install --quiet -r "$reqs" 2>&1 \
    | grep -v -e 'is ignored: it is neither' -e "DEPRECATION: .* 'setup.py install'" || true
  # rclpy is Humble's on the board environment, checked once it is unpacked.
  $venv/bin/python -c "import cv2, numpy, colcon_core$([ $venv = .venv ] && echo ', rclpy')" \
    || { echo '[setup] the Python environment is incomplete, see the pip output above' >&2; exit 1; }
  touch "$stamp"
fi

if [ "$venv" = .venv-board ]; then
  unpack_humble "$humble"
  # The build sees Humble as the boards' workspace does: install/setup.bash then chains it.
  # shellcheck disable=SC1091
  . scripts/board_env.sh
  check_humble
fi

echo "[setup] colcon build ($venv)"
# --base-paths keeps colcon from crawling .venv; --symlink-install is not used so that the
# installed tree is exactly what a board build produces.
$venv/bin/colcon --log-base $out/log build --base-paths py_vision --build-base $out/build \
  --install-base $out/install >$out/log-colcon.txt 2>&1 \
  || { cat $out/log-colcon.txt >&2; echo '[setup] colcon build failed' >&2; exit 1; }
echo "[setup] built: $(cd $out && pwd)/install/py_vision/lib/py_vision/"
