# The boards' environment, to be sourced: Python 3.10 with the boards' numpy and OpenCV
# (.venv-board) and the boards' ROS 2 Humble unpacked in .venv-board/humble, both made by
# scripts/setup.sh --board. scripts/test.sh's board-version run uses it; by hand:
#   . scripts/board_env.sh && python -m pytest py_vision/test/nodes/test_params_file.py
# (PY_VISION_INSTALL then points the tests at the board build in .venv-board/install).
# shellcheck shell=bash
_board_root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
if [ ! -f "$_board_root/.venv-board/humble/install/setup.bash" ]; then
  echo "[board_env] $_board_root/.venv-board/humble is missing: run scripts/setup.sh --board" >&2
  unset _board_root
  return 1
fi
# Humble's own scripts start with `#!/usr/bin/env python3`: the venv's Python comes first.
export VIRTUAL_ENV="$_board_root/.venv-board"
export PATH="$VIRTUAL_ENV/bin:$PATH"
# Its setup scripts read unset variables.
case $- in *u*) _board_nounset=1; set +u ;; *) _board_nounset= ;; esac
# shellcheck disable=SC1091
. "$_board_root/.venv-board/humble/install/setup.bash"
[ -n "$_board_nounset" ] && set -u
# Humble's setup script does not set it (a ROS installation's does).
export ROS_DISTRO=humble
export PY_VISION_INSTALL="$_board_root/.venv-board/install"
unset _board_root _board_nounset
