#!/usr/bin/env bash
# Set everything up (scripts/setup.sh --test) and run the whole test suite against the
# colcon-installed package; if it passes, run the tests of the numpy and OpenCV code again on
# numpy 1.x and OpenCV 4.x, as on the boards (.venv-compat, scripts/setup.sh --compat).
# Extra arguments go to pytest, in both runs (e.g. -k bridge, -x).
set -euo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
bash "$root/scripts/setup.sh" --test
cd "$root"

# The browser-viewer test drives Debian's Chromium; install it where we may (root + apt).
if ! command -v chromium >/dev/null 2>&1 && [ "$(id -u)" = 0 ] && command -v apt-get >/dev/null; then
  echo '[test] installing chromium for the browser-viewer test'
  { apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq chromium; } \
    >/tmp/py_vision-apt.log 2>&1 || echo '[test] could not install chromium (see /tmp/py_vision-apt.log)'
fi

status=0
.venv/bin/python -m pytest py_vision/test petalinux/test -p no:cacheprovider "$@" || status=$?
if [ "$status" = 5 ]; then
  echo '[test] pytest collected no tests: that is a failure' >&2
  exit 1
fi
[ "$status" = 0 ] || exit "$status"

# The boards run numpy 1.x and OpenCV 4.x: run the tests of the code that uses them again in
# .venv-compat, against its own build there, so that the nodes these tests start run on it too.
echo '[test] numpy 1.x / OpenCV 4.x compatibility run'
bash scripts/setup.sh --compat
.venv-compat/bin/python -c 'import cv2, numpy; print("[test] numpy", numpy.__version__, "OpenCV", cv2.__version__)'
compat_tests=(test_cv_bridge.py test_cv_bridge_properties.py test_synthetic_camera.py
  test_frame_source.py test_web_viewer.py test_dds.py test_passthrough.py test_cv_bridge_test.py)
PY_VISION_INSTALL=.venv-compat/install .venv-compat/bin/python -m pytest \
  "${compat_tests[@]/#/py_vision/test/}" -p no:cacheprovider "$@" || status=$?
if [ "$status" = 5 ]; then
  # Only a -k or -m that matches none of its tests may leave this run empty.
  case " $* " in
    *' -k'* | *' -m'*) echo '[test] the compatibility run has none of the selected tests'; exit 0 ;;
  esac
  echo '[test] the compatibility run collected no tests: that is a failure' >&2
  exit 1
fi
exit "$status"
