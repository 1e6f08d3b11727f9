#!/usr/bin/env bash
# Set everything up (scripts/setup.sh), then run the camera passthrough:
#   usbcam_publisher (synthetic camera unless VIDEO_DEVICE is set) -> usb_camera/image
#   -> usbcam_subscriber (an OpenCV window where there is one, else the browser viewer).
# Stop it with Ctrl-C. Environment knobs:
#   VIDEO_DEVICE=/dev/video0   a real camera instead of the synthetic one
#   DISPLAY_MODE=web|window|none|auto (default auto)    DEMO_SECONDS=N  stop after N seconds
set -euo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
bash "$root/scripts/setup.sh"
cd "$root"
set +u
# shellcheck disable=SC1091
source install/setup.bash
set -u
bin=install/py_vision/lib/py_vision

"$bin/usbcam_publisher" --ros-args -p video_device:="${VIDEO_DEVICE:-synthetic}" \
  -p framerate:="${FRAMERATE:-30.0}" &
publisher=$!
"$bin/usbcam_subscriber" --ros-args -p display:="${DISPLAY_MODE:-auto}" -p stats_period:=2.0 &
subscriber=$!
stop() { kill -INT "$subscriber" "$publisher" 2>/dev/null || true; wait "$subscriber" "$publisher" 2>/dev/null || true; }
trap stop EXIT INT TERM
if [ -n "${DEMO_SECONDS:-}" ]; then
  sleep "$DEMO_SECONDS"
else
  wait "$subscriber"
fi
