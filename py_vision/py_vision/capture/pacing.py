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


"""Real-time frame pacing for the sources that make their own frames (synthetic, video file)."""

import math
import threading

from py_vision.capture.source import Clock, MONOTONIC

__all__ = ['FramePacer']


class FramePacer:
    """
    Real-time frame schedule: frame n is due at t0 + n / fps, t0 being the first wait().

    With ``drop=True`` (a camera with a single buffer) a late caller gets the newest due frame
    and the frames in between are skipped. With ``drop=False`` (a file played in real time) a
    late caller gets the next frame at once and the schedule restarts from there. `clock`
    gives the time and the sleep (a fake one in tests).
    """

    def __init__(self, fps, drop=True, clock: Clock = MONOTONIC):
        self.fps = fps
        self.drop = drop
        self.clock = clock
        self.t0 = None
        self.next = 0
        self.cancelled = threading.Event()

    def cancel(self):
        """End the wait() in progress (in another thread), or the next one, at once."""
        self.cancelled.set()

    def restart(self):
        """Start a new schedule at the next wait() (after a size or rate change)."""
        self.t0 = None
        self.next = 0

    @property
    def running(self):
        return self.t0 is not None

    def wait(self):
        """
        Block until the next frame is due; return its number in this schedule and due time.

        Return None when cancel() ended the wait (the cancel is used up: the next wait waits).
        """
        if self._consume_cancel():
            return None
        now = self.clock.now()
        if self.t0 is None:
            self.t0 = now
            self.next = 1
            return 0, now
        number = self.next
        due = self.t0 + number / self.fps
        if now >= due + 1.0 / self.fps:
            if self.drop:
                number = max(number, int(math.floor((now - self.t0) * self.fps)))
                due = self.t0 + number / self.fps
            else:
                self.t0 = now - number / self.fps
                due = now
        else:
            self._sleep_until(due)
            if self._consume_cancel():
                return None
        self.next = number + 1
        return number, due

    def _consume_cancel(self):
        if not self.cancelled.is_set():
            return False
        self.cancelled.clear()
        return True

    def _sleep_until(self, deadline):
        # Sleep most of the wait, then short sleeps: never more than ~0.1 ms late, no busy
        # spin. Long waits (low frame rates) are cut into 50 ms steps so that cancel() is
        # seen quickly.
        while not self.cancelled.is_set():
            remaining = deadline - self.clock.now()
            if remaining <= 0:
                return
            self.clock.sleep(min(0.05, remaining - 0.001 if remaining > 0.002 else remaining))
