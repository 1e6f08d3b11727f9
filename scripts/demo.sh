#!/usr/bin/env bash
# Set everything up (scripts/setup.sh), then run the camera passthrough:
#   usbcam_publisher (synthetic camera unless VIDEO_DEVICE is set) -> usb_camera/image
#   -> usbcam_subscriber (an OpenCV window where there is one, else the browser viewer).
# Stop it with Ctrl-C. If a node stops by itself (a camera that cannot be opened, a port in
# use), the demo stops too, repeating that node's error and exiting with its status.
# Environment knobs:
#   VIDEO_DEVICE=/dev/video0   a real camera instead of the synthetic one
#   DISPLAY_MODE=web|window|none|auto (default auto)   WEB_PORT=N browser viewer port (8080)
#   FRAMERATE=N (default 30.0)   DEMO_SECONDS=N  stop after N seconds
set -euo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
bash "$root/scripts/setup.sh"
cd "$root"
set +u
# shellcheck disable=SC1091
source install/setup.bash
set -u
bin=install/py_vision/lib/py_vision

# Job control puts each node in its own process group: Ctrl-C reaches only this script, which
# then stops each node with exactly one SIGINT.
set -m
logs=$(mktemp -d)
"$bin/usbcam_publisher" --ros-args -p video_device:="${VIDEO_DEVICE:-synthetic}" \
  -p framerate:="${FRAMERATE:-30.0}" > >(tee "$logs/usbcam_publisher") 2>&1 &
publisher=$!
"$bin/usbcam_subscriber" --ros-args -p display:="${DISPLAY_MODE:-auto}" -p stats_period:=2.0 \
  -p web_port:="${WEB_PORT:-8080}" > >(tee "$logs/usbcam_subscriber") 2>&1 &
subscriber=$!

stop() {
  trap - EXIT INT TERM
  for pid in "$subscriber" "$publisher"; do
    if kill -0 "$pid" 2>/dev/null; then kill -INT "$pid"; fi
  done
  wait "$subscriber" "$publisher" 2>/dev/null || true
  rm -rf "$logs"
}
trap stop EXIT
trap 'stop; exit 0' INT TERM

deadline=$((SECONDS + ${DEMO_SECONDS:-0}))
while [ -z "${DEMO_SECONDS:-}" ] || [ "$SECONDS" -lt "$deadline" ]; do
  for name in usbcam_publisher usbcam_subscriber; do
    pid=$publisher
    [ "$name" = usbcam_subscriber ] && pid=$subscriber
    if ! kill -0 "$pid" 2>/dev/null; then
      status=0
      wait "$pid" || status=$?
      error=$(grep -E '\[(ERROR|FATAL)\]' "$logs/$name" | tail -n 1 || true)
      echo "[demo] $name stopped (exit status $status)${error:+: $error}" >&2
      stop
      exit "$status"
    fi
  done
  sleep 0.2
done
