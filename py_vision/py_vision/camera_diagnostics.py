# Copyright 2026 py_vision contributors
#
# Licensed under the Apache License, Version 2.0 (the "License");
# you may not use this file except in compliance with the License.
# You may obtain a copy of the License at
#
#     http://www.apache.org/licenses/LICENSE-2.0
#
# Unless required by applicable law or agreed to in writing, software
# distributed under the License is distributed on an "AS IS" BASIS,
# WITHOUT WARRANTIES OR CONDITIONS OF ANY KIND, either express or implied.
# See the License for the specific language governing permissions and
# limitations under the License.

"""
The camera's status on /diagnostics, made from what the capture loop counts.

`CameraMonitor.status()` turns the loop's `CaptureStats` into the status "<node>: camera":
ERROR while the device is lost (or not open while it should stream, or its stream has no room
on the USB bus: `waiting` says so), WARN when the measured
rate is outside RATE_TOLERANCE of the requested one, no frame came for a while, or frames
were corrupt, flagged as errors by the driver or dropped (the device's frame numbers skip)
lately, OK otherwise. Its keys are read by other tools (the browser panel):
keep them.
"""

from typing import Dict, Optional

from py_vision.capture import CaptureStats
from py_vision.diagnostics import ERROR, OK, Recent, Status, WARN

# The measured rate counts as the requested one within this fraction (a real camera gives
# 29.97 for 30, and a loaded machine reads a frame late now and then).
RATE_TOLERANCE = 0.1
# Reports in a row without a new frame (while streaming) before it is a warning; the first
# report after (re)opening may come before the first frame.
QUIET_REPORTS_WARN = 2


class CameraMonitor:
    """Makes the camera's status from the loop's counters, one report after another."""

    def __init__(self):
        self._recent = Recent()
        self._frames_before: Optional[int] = None
        self._quiet = 0  # reports in a row without a new frame

    def status(self, stats: CaptureStats, device: str, requested_rate: float,
               subscribers: Dict[str, int], state: Optional[str] = None) -> Status:
        """
        Return the status "<node>: camera" now.

        subscribers maps each topic to its subscriber count; state is the lifecycle state of
        a managed node (None for the plain node, which always streams).
        """
        new_frames = stats.frames != self._frames_before
        self._frames_before = stats.frames
        self._quiet = 0 if new_frames else self._quiet + 1
        rate = stats.measured_fps if new_frames else 0.0
        values = {
            'device': device,
            'pixel format': 'video file' if stats.pixel_format == 'file' else stats.pixel_format,
            'size': '%dx%d' % (stats.width, stats.height) if stats.width else '',
            'frame rate': float(rate),
            'requested rate': float(requested_rate),
            'camera rate': float(stats.fps),
            'frames': stats.frames,
            'lost': stats.lost,
            'stalls': stats.stalls,
            'stale': stats.stale,
            'corrupt': stats.corrupt,
            'error frames': stats.errors,
            'dropped': stats.dropped,
            'reconnects': stats.reconnects,
            'device present': stats.present,
            'streaming': stats.streaming,
            'waiting': stats.waiting,
            'io method': stats.io_method,
        }
        values.update(('subscribers %s' % topic.lstrip('/'), count)
                      for topic, count in subscribers.items())
        if state is not None:
            values['lifecycle state'] = state
        recent = self._recent.update(corrupt=stats.corrupt, errors=stats.errors,
                                     dropped=stats.dropped)
        if state is not None and state != 'active':
            what = 'camera open, not streaming' if stats.present else 'camera closed'
            return Status(OK, '%s: %s' % (state, what), values)
        if not stats.present:
            if stats.lost:
                return Status(ERROR, 'device lost (%d time(s)): reconnecting' % stats.lost,
                              values)
            return Status(ERROR, 'device not open', values)
        if stats.waiting:
            return Status(ERROR, stats.waiting, values)
        what = '%s %s' % (values['size'], values['pixel format'])
        if not new_frames and self._quiet >= QUIET_REPORTS_WARN:
            return Status(WARN, 'no frame for %d s' % self._quiet, values)
        if rate <= 0:  # no frame yet, or one: the rate is not measured yet
            return Status(OK, 'starting: %s' % what, values)
        problems = []
        if abs(rate - requested_rate) > RATE_TOLERANCE * requested_rate:
            problems.append('%.1f fps, requested %.1f' % (rate, requested_rate))
        if recent['corrupt']:
            problems.append('%d corrupt frame(s) lately' % recent['corrupt'])
        if recent['errors']:
            problems.append('%d frame(s) flagged as errors lately' % recent['errors'])
        if recent['dropped']:
            problems.append('%d frame(s) dropped lately' % recent['dropped'])
        if problems:
            return Status(WARN, '; '.join(problems), values)
        return Status(OK, 'streaming %s at %.1f fps' % (what, rate), values)
