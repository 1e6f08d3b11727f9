#!/usr/bin/env bash
# Set up everything py_vision needs on a PC with only Python 3, then build the package:
#   .venv/    pinned ROS 2 Jazzy wheels, OpenCV, numpy, colcon (requirements*.txt)
#   install/  the colcon-installed package, exactly what `ros2 run` would execute
# With --board, instead: .venv-board/ on Python 3.10 with the boards' numpy 1.23.3 and OpenCV
# 4.6.0 (requirements-board.txt) and its own build in .venv-board/install/, whose executables
# run on that environment (scripts/test.sh's board-version run). Python 3.10 is $PYTHON310 if
# set, else python3.10 on PATH, else pyenv's newest 3.10; without one it exits with status 3.
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
  $venv/bin/python -c 'import rclpy, cv2, numpy, colcon_core' \
    || { echo '[setup] the Python environment is incomplete, see the pip output above' >&2; exit 1; }
  touch "$stamp"
fi

echo "[setup] colcon build ($venv)"
# --base-paths keeps colcon from crawling .venv; --symlink-install is not used so that the
# installed tree is exactly what a board build produces.
$venv/bin/colcon --log-base $out/log build --base-paths py_vision --build-base $out/build \
  --install-base $out/install >$out/log-colcon.txt 2>&1 \
  || { cat $out/log-colcon.txt >&2; echo '[setup] colcon build failed' >&2; exit 1; }
echo "[setup] built: $(cd $out && pwd)/install/py_vision/lib/py_vision/"
