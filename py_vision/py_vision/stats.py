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

"""Received-stream statistics: rate, latency percentiles and gaps."""

import collections
import threading
import time


def stamp_age_s(now_ns, stamp):
    """
    Return how old a message's header stamp is at now_ns (a clock's nanoseconds), in seconds.

    None for a zero stamp: its publisher did not stamp the message, and it has no age. Plain
    arithmetic on the stamp's sec and nanosec: a stamp no rclpy Time can hold (sec is
    signed, nanosec unchecked) is an implausible age, never an exception.
    """
    if stamp.sec == 0 and stamp.nanosec == 0:
        return None
    return (now_ns - (stamp.sec * 1000000000 + stamp.nanosec)) / 1e9


def percentile(sorted_values, fraction):
    """Return the nearest-rank percentile of an already sorted, non-empty list."""
    rank = min(len(sorted_values) - 1, max(0, int(round(fraction * len(sorted_values))) - 1))
    return sorted_values[rank]


def gap_worth_saying(snapshot):
    """
    Return the longest gap of a snapshot when it is worth a line, else None.

    A gap counts when it is over a second and over five frame periods. Right after an outage
    the window may hold a single frame, so no rate: the gap then counts from a second on
    (it once went unsaid there, the threshold being five periods of a rate of zero).
    """
    gap, fps = snapshot['longest_gap_s'], snapshot['fps']
    threshold = max(1.0, 5.0 / fps) if fps > 0 else 1.0
    return gap if gap > threshold else None


class StreamStats:
    """
    Counts what a subscriber receives; `snapshot()` summarises the recent window.

    Safe to use from two threads: the one frames arrive on, the one that reports.
    """

    def __init__(self, window_s=5.0, clock=time.monotonic):
        self.window_s = window_s
        self._clock = clock
        self._lock = threading.Lock()
        self._recent = collections.deque()  # (arrival time, latency in s)
        self.frames = 0
        self.errors = 0
        self.longest_gap_s = 0.0
        self.width = self.height = 0
        self.encoding = ''
        self._last_arrival = None

    def add(self, latency_s, width, height, encoding):
        """Record one frame: its latency (stamp to arrival; None: no stamp), size, encoding."""
        with self._lock:
            now = self._clock()
            if self._last_arrival is not None:
                self.longest_gap_s = max(self.longest_gap_s, now - self._last_arrival)
            self._last_arrival = now
            self._recent.append((now, latency_s))
            self.frames += 1
            self.width, self.height, self.encoding = width, height, encoding

    def add_error(self):
        """Record one message that could not be used; return how many so far."""
        with self._lock:
            self.errors += 1
            return self.errors

    def snapshot(self):
        """Return a JSON-able summary: totals, and rate and latency over the recent window."""
        with self._lock:
            now = self._clock()
            while self._recent and self._recent[0][0] < now - self.window_s:
                self._recent.popleft()
            recent = list(self._recent)
            summary = {'frames': self.frames, 'recent_frames': len(recent),
                       'errors': self.errors, 'longest_gap_s': round(self.longest_gap_s, 3),
                       'width': self.width, 'height': self.height, 'encoding': self.encoding}
        latencies = sorted(latency for _, latency in recent if latency is not None)
        fps = 0.0
        if len(recent) > 1:
            span = now - recent[0][0]
            fps = (len(recent) - 1) / span if span > 0 else 0.0
        return dict(
            summary, fps=round(fps, 2),
            latency_ms_p50=round(percentile(latencies, 0.5) * 1e3, 2) if latencies else None,
            latency_ms_p99=round(percentile(latencies, 0.99) * 1e3, 2) if latencies else None)

    def reset_gap(self):
        """Start measuring the longest gap afresh (after it has been reported)."""
        with self._lock:
            self.longest_gap_s = 0.0
