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
What the capture counts, and the camera's status on /diagnostics made from it.

`CaptureCounters` is written by the capture thread (a frame, a failed read, the device lost
or back) and read by the node's executor once a second; `camera_status()` turns it into the
status "<node>: camera": ERROR while the device is lost, WARN when the measured rate is
outside RATE_TOLERANCE of the requested one or frames are being lost or are corrupt, OK
otherwise. The keys are read by other tools (the browser panel): keep them.
"""

import collections
import threading
import time
from typing import Callable, Dict, Optional

from py_vision.diagnostics import ERROR, OK, Recent, Status, WARN

# The measured rate counts as the requested one within this fraction (a real camera gives
# 29.97 for 30, and a loaded machine reads a frame late now and then).
RATE_TOLERANCE = 0.1
# Seconds of frames the rate is measured over.
RATE_WINDOW_S = 3.0
# A frame read this long after its capture time is stale (usbcam_publisher stamps it with
# the time it was read instead).
STALE_AFTER_S = 1.0
# Losing more than this fraction of the frames lately is a warning, not the odd late read.
LOST_WARN_FRACTION = 0.1
PIXEL_FORMAT_NAMES = {'yuyv': 'YUYV', 'mjpeg': 'MJPEG', 'file': 'video file'}


class CaptureCounters:
    """Counts of the capture since the node started, and the recent frame rate; thread-safe."""

    def __init__(self, clock: Callable[[], float] = time.monotonic):
        self._clock = clock
        self._lock = threading.Lock()
        self._arrivals = collections.deque()
        self._last_index: Optional[int] = None
        self._opened_at: Optional[float] = None
        self.frames = self.lost = self.stale = self.corrupt = 0
        self.read_failures = self.reconnects = 0
        self.present = False
        self.lost_device = False  # False while present, or released on purpose
        self.pixel_format = ''
        self.size = ''
        self.camera_rate = 0.0

    def opened(self, pixel_format: str, width: int, height: int, fps: float) -> None:
        """Record the camera open (at start or after a reconnect): the rate is measured anew."""
        with self._lock:
            self.present = True
            self.lost_device = False
            self.pixel_format = PIXEL_FORMAT_NAMES.get(pixel_format, pixel_format)
            self.size = '%dx%d' % (width, height)
            self.camera_rate = fps
            self._arrivals.clear()
            self._last_index = None
            self._opened_at = self._clock()

    def reconnected(self) -> None:
        """Record a lost device opened again."""
        with self._lock:
            self.reconnects += 1

    def closed(self, lost: bool) -> None:
        """Record the camera released: lost (reads failed), or on purpose (lost False)."""
        with self._lock:
            self.present = False
            self.lost_device = lost
            self._opened_at = None
            self._arrivals.clear()

    def frame(self, index: Optional[int], capture_time: Optional[float]) -> None:
        """Record one frame read: its source index (gaps are lost frames) and capture time."""
        now = self._clock()
        with self._lock:
            self.frames += 1
            if index is not None and self._last_index is not None and \
                    index > self._last_index + 1:
                self.lost += index - self._last_index - 1
            if index is not None:
                self._last_index = index
            if capture_time is not None and now - capture_time >= STALE_AFTER_S:
                self.stale += 1
            self._arrivals.append(now)
            while self._arrivals and self._arrivals[0] < now - RATE_WINDOW_S:
                self._arrivals.popleft()

    def failed_read(self) -> None:
        """Record one read that returned no frame."""
        with self._lock:
            self.read_failures += 1

    def corrupt_frame(self) -> None:
        """Record one frame whose image could not be decoded."""
        with self._lock:
            self.corrupt += 1

    def rate(self) -> Optional[float]:
        """Return frames per second over the last RATE_WINDOW_S, None while still measuring."""
        now = self._clock()
        with self._lock:
            if self._opened_at is None or now - self._opened_at < RATE_WINDOW_S:
                return None
            while self._arrivals and self._arrivals[0] < now - RATE_WINDOW_S:
                self._arrivals.popleft()
            if len(self._arrivals) < 2:
                return 0.0
            span = self._arrivals[-1] - self._arrivals[0]
            return (len(self._arrivals) - 1) / span if span > 0 else 0.0


def camera_status(counters: CaptureCounters, recent: Recent, device: str,
                  requested_rate: float, subscribers: Dict[str, int],
                  state: Optional[str] = None) -> Status:
    """
    Return the status "<node>: camera" from the counters.

    subscribers maps each topic to its subscriber count; state is the lifecycle state of a
    managed node (None for the plain node, which is always streaming).
    """
    rate = counters.rate()
    values = {
        'device': device,
        'pixel format': counters.pixel_format,
        'size': counters.size,
        'frame rate': rate,
        'requested rate': float(requested_rate),
        'camera rate': float(counters.camera_rate) if counters.camera_rate else None,
        'frames': counters.frames,
        'lost': counters.lost,
        'stale': counters.stale,
        'corrupt': counters.corrupt,
        'read failures': counters.read_failures,
        'reconnects': counters.reconnects,
        'device present': counters.present,
    }
    values.update(('subscribers %s' % topic.lstrip('/'), count)
                  for topic, count in subscribers.items())
    if state is not None:
        values['lifecycle state'] = state
    recent_counts = recent.update(frames=counters.frames, lost=counters.lost,
                                  corrupt=counters.corrupt)
    if state is not None and state != 'active':
        recent.clear()
        what = 'camera closed' if state == 'unconfigured' else 'not streaming'
        return Status(OK, '%s: %s' % (state, what), values)
    if not counters.present:
        recent.clear()
        if counters.lost_device:
            return Status(ERROR, 'device lost: reconnecting', values)
        return Status(ERROR, 'device not open', values)
    if rate is None:
        return Status(OK, 'starting: %s %s' % (counters.size, counters.pixel_format), values)
    problems = []
    if abs(rate - requested_rate) > RATE_TOLERANCE * requested_rate:
        problems.append('%.1f fps, requested %.1f' % (rate, requested_rate))
    seen = recent_counts['frames'] + recent_counts['lost']
    if seen and recent_counts['lost'] > LOST_WARN_FRACTION * seen:
        problems.append('%d of the last %d frames lost' % (recent_counts['lost'], seen))
    if recent_counts['corrupt']:
        problems.append('%d corrupt frame(s) lately' % recent_counts['corrupt'])
    if problems:
        return Status(WARN, '; '.join(problems), values)
    return Status(OK, 'streaming %s %s at %.1f fps' % (counters.size, counters.pixel_format,
                                                       rate), values)
