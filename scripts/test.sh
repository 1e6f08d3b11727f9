#!/usr/bin/env bash
# Set everything up (scripts/setup.sh --test) and run the whole test suite against the
# colcon-installed package. Extra arguments go to pytest (e.g. -k bridge, -x).
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
exit "$status"
