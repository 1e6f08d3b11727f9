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
Newest-frame processing: a step slower than its input works on the newest item, not a backlog.

A subscription callback calls `LatestFrameWorker.offer(msg)`, which only puts the message in
a one-item slot (an item still waiting there is replaced and counted as skipped) and wakes the
worker thread. That thread runs the processing step on whatever is in the slot whenever it is
ready for the next one. With a step faster than its input every item is processed, in order;
with a slower one each result describes the newest input, and the delay does not grow.

Each item's arrival (the clock when it was offered) goes with it: `frame_age()`, called by
the step, says how long ago the item it works on arrived, measured on this host whatever the
item's own stamps say.

The worker also adds up the CPU time its thread spent in the steps (`cpu_ms`, since start).
With a `part_clock` (the wall and CPU seconds the worker's thread has spent so far in one part
of the work: vision_step gives it the time inside models, py_vision.models.model_time), each
item's time is split into that part and the rest, both with their percentiles, and the part's
CPU time is added up too.

No ROS here: the node supplies the step and reports how old each of its outputs is.
"""

import collections
import sys
import threading
import time
import traceback
from typing import Callable, Deque, Dict, Generic, Optional, Tuple, TypeVar

from py_vision.stats import percentile

T = TypeVar('T')

_EMPTY = object()  # the slot's "nothing waiting" (None is a valid item)


def print_error(error: Exception) -> None:
    """Report an exception the processing step raised on stderr, with its traceback."""
    traceback.print_exception(type(error), error, error.__traceback__, file=sys.stderr)


class _RecentValues:
    """Values of the last window_s seconds, for percentiles that follow what happens now."""

    def __init__(self, window_s: float, clock: Callable[[], float]):
        self.window_s = window_s
        self._clock = clock
        self._values: Deque[Tuple[float, float]] = collections.deque()

    def add(self, value: float, at: Optional[float] = None) -> None:
        """Add a value at `at` (one reading of the clock for the values of one step)."""
        self._values.append((self._clock() if at is None else at, value))

    def _recent(self, now: Optional[float] = None) -> Deque[Tuple[float, float]]:
        horizon = (self._clock() if now is None else now) - self.window_s
        while self._values and self._values[0][0] < horizon:
            self._values.popleft()
        return self._values

    def count(self, condition: Callable[[float], bool], now: Optional[float] = None) -> int:
        """Return how many of the window's values (the window ending now) meet condition."""
        return sum(1 for _, value in self._recent(now) if condition(value))

    def percentiles_ms(self, now: Optional[float] = None
                       ) -> Tuple[Optional[float], Optional[float]]:
        """Return (p50, p99) in milliseconds, or (None, None) when the window is empty."""
        values = sorted(value for _, value in self._recent(now))
        if not values:
            return None, None
        return (round(percentile(values, 0.5) * 1e3, 2),
                round(percentile(values, 0.99) * 1e3, 2))


class LatestFrameWorker(Generic[T]):
    """
    Runs process(item) on its own thread, always on the newest item offered.

    Counts since start: items offered (`frames_in`), steps run (`processed`) and items
    replaced before a step took them (`skipped`); frames_in = processed + skipped + the one
    waiting or in progress. Over the last window_s seconds: how long a step took and how old
    the outputs were (`record_age()`), p50 and p99; with a part_clock, how much of each step's
    time was in that part and how much was the rest, p50 and p99, and how many of those steps
    spent any time in the part. The CPU time of the steps (`cpu_ms`) and of their part
    (`part_cpu_ms`): since start, whole milliseconds.

    A step that raises is reported through on_error (default: a traceback on stderr) and
    the worker goes on with the next item.
    """

    def __init__(self, process: Callable[[T], None], *,
                 on_error: Callable[[Exception], None] = print_error,
                 window_s: float = 5.0, name: str = 'latest_frame',
                 clock: Callable[[], float] = time.monotonic,
                 part_clock: Optional[Callable[[], Tuple[float, float]]] = None,
                 cpu_clock: Callable[[], float] = time.thread_time):
        self._process = process
        self._part_clock = part_clock
        self._cpu_clock = cpu_clock
        self._cpu_s = self._part_cpu_s = 0.0  # since start
        self._on_error = on_error
        self._clock = clock
        self._cond = threading.Condition()
        self._waiting = _EMPTY
        self._waiting_since = 0.0   # when the waiting item was offered
        self._arrived: Optional[float] = None  # when the item in progress was (worker thread)
        self._closed = threading.Event()
        self.frames_in = 0
        self.processed = 0
        self.skipped = 0
        self._processing_s = _RecentValues(window_s, clock)
        self._age_s = _RecentValues(window_s, clock)
        self._part_s = _RecentValues(window_s, clock)
        self._rest_s = _RecentValues(window_s, clock)
        self._thread = threading.Thread(target=self._run, name=name, daemon=True)
        self._thread.start()

    @property
    def closed(self) -> bool:
        """Return True once close() was called: a long step may poll this to give up early."""
        return self._closed.is_set()

    def offer(self, item: T) -> None:
        """Make item the next one to process (O(1), never waits for the step)."""
        with self._cond:
            if self._closed.is_set():
                return
            self.frames_in += 1
            if self._waiting is not _EMPTY:
                self.skipped += 1
            self._waiting = item
            self._waiting_since = self._clock()
            self._cond.notify()

    def frame_age(self) -> Optional[float]:
        """
        Return the seconds since the item being processed was offered (None between items).

        For the step, on the worker thread: how old what it works on is, from its arrival.
        """
        arrived = self._arrived
        return None if arrived is None else self._clock() - arrived

    def record_age(self, age_s: float) -> None:
        """Record how old an output was when it went out: now minus its input's capture time."""
        with self._cond:
            self._age_s.add(age_s)

    def snapshot(self) -> Dict[str, Optional[float]]:
        """Return the counts since start and the recent percentiles, JSON-able."""
        with self._cond:
            # One window for all: the processing, its part and the rest cover the same steps.
            now = self._clock()
            processing = self._processing_s.percentiles_ms(now)
            age = self._age_s.percentiles_ms(now)
            part, rest = self._part_s.percentiles_ms(now), self._rest_s.percentiles_ms(now)
            return {
                'frames_in': self.frames_in,
                'processed': self.processed,
                'skipped': self.skipped,
                'processing_ms_p50': processing[0],
                'processing_ms_p99': processing[1],
                'age_ms_p50': age[0],
                'age_ms_p99': age[1],
                'part_ms_p50': part[0],
                'part_ms_p99': part[1],
                'rest_ms_p50': rest[0],
                'rest_ms_p99': rest[1],
                'part_items': self._part_s.count(lambda seconds: seconds > 0, now),
                'cpu_ms': int(round(self._cpu_s * 1e3)),
                'part_cpu_ms': int(round(self._part_cpu_s * 1e3)),
            }

    def close(self, timeout: float = 1.0) -> bool:
        """
        Stop taking items and end the thread; return True if it ended within timeout seconds.

        An item still waiting is dropped (counted as skipped). The step in progress is
        abandoned: an error it raises from now on is not reported, and a step that polls
        `closed` ends early. One that does not poll it finishes on the (daemon) thread, which
        ends with the process if it outlasts timeout.
        """
        with self._cond:
            self._closed.set()
            if self._waiting is not _EMPTY:
                self.skipped += 1
                self._waiting = _EMPTY
            self._cond.notify()
        if self._thread is not threading.current_thread():
            self._thread.join(timeout)
        return not self._thread.is_alive()

    def _run(self) -> None:
        while True:
            with self._cond:
                while self._waiting is _EMPTY and not self._closed.is_set():
                    self._cond.wait()
                if self._closed.is_set():
                    return
                item, self._waiting = self._waiting, _EMPTY
                self._arrived = self._waiting_since
            part = self._part_clock() if self._part_clock is not None else (0.0, 0.0)
            start, cpu = self._clock(), self._cpu_clock()
            try:
                self._process(item)
            except Exception as error:
                # After close() the node tears down what the step uses: its failure is expected.
                if not self._closed.is_set():
                    self._on_error(error)
            finally:
                self._arrived = None
            took, cpu = self._clock() - start, self._cpu_clock() - cpu
            if self._part_clock is not None:
                wall, part_cpu = self._part_clock()
                part = (min(took, wall - part[0]), part_cpu - part[1])
            del item  # a frame is large: do not hold it while waiting for the next one
            with self._cond:
                self.processed += 1
                done = self._clock()
                self._processing_s.add(took, done)
                self._cpu_s += cpu
                if self._part_clock is not None:
                    self._part_s.add(part[0], done)
                    self._rest_s.add(took - part[0], done)
                    self._part_cpu_s += part[1]
