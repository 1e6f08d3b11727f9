#!/usr/bin/env bash
# Set up everything py_vision needs on a PC with only Python 3, then build the package:
#   .venv/    pinned ROS 2 Jazzy wheels, OpenCV, numpy, colcon (requirements*.txt)
#   install/  the colcon-installed package, exactly what `ros2 run` would execute
# With --compat, instead: .venv-compat/ with numpy 1.x and OpenCV 4.x as on the boards
# (requirements-compat.txt) and its own build in .venv-compat/install/, whose executables run
# on that environment (scripts/test.sh's compatibility run).
# Safe to run again: it only does what is missing or out of date.
# Usage: scripts/setup.sh [--test | --compat]
#   (--test also installs the test and benchmark tools)
set -euo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
cd "$root"

venv=.venv
out=.   # where build/, install/, log/ and log-colcon.txt go
base=requirements.txt
reqs=$base
case "${1:-}" in
  --test) reqs=requirements-test.txt ;;
  --compat) venv=.venv-compat; out=.venv-compat; base=requirements-compat.txt; reqs=$base ;;
esac

python=${PYTHON:-python3}
if [ ! -x $venv/bin/python ]; then
  echo "[setup] creating $venv with $($python --version 2>&1)"
  "$python" -m venv $venv
fi
stamp=$venv/.installed-$(cat $base "$reqs" | sha1sum | cut -c1-12)
if [ ! -f "$stamp" ]; then
  echo "[setup] installing $reqs into $venv"
  # pip's notes about unused local index locations are noise; real errors still show.
  $venv/bin/python -m pip install --quiet -r "$reqs" 2>&1 | grep -v 'is ignored: it is neither' \
    || true
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
