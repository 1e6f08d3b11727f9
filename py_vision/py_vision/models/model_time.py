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
How long a thread has spent inside models: each runtime's invoke, timed where it runs.

Every runtime of `runtime.py` runs its model (the interpreter's invoke, the session's run, the
network's forward pass: not the copies in and out around it) inside `timing()`, which adds
the time it took (the steady clock's, wall time), the CPU time the thread used meanwhile and
one run to the calling thread's total.
`thread_model_time()` returns that total, a `ModelTime`; read before and after a piece of work
(vision_step: one frame), `after.since(before)` is that work's time inside models. A model run
through another runtime can be counted the same way: `with timing(): session.run(...)`.

Per thread, since models run on whichever thread calls them (vision_step's worker): what
another thread runs meanwhile is not counted in this one's. No ROS, no runtime here.
"""

from contextlib import contextmanager
from dataclasses import dataclass
import threading
import time
from typing import Callable, Iterator

__all__ = ['ModelTime', 'thread_model_time', 'timing']


@dataclass(frozen=True)
class ModelTime:
    """Time inside models: seconds (wall), how many runs, and the thread's CPU seconds."""

    seconds: float = 0.0
    runs: int = 0
    cpu_seconds: float = 0.0

    def since(self, earlier: 'ModelTime') -> 'ModelTime':
        """Return what was added to this total after `earlier`, an older total of the thread."""
        return ModelTime(self.seconds - earlier.seconds, self.runs - earlier.runs,
                         self.cpu_seconds - earlier.cpu_seconds)


class _ThreadTotal(threading.local):
    seconds = 0.0
    runs = 0
    cpu_seconds = 0.0


_TOTAL = _ThreadTotal()


def thread_model_time() -> ModelTime:
    """Return the calling thread's time inside models so far."""
    total = _TOTAL
    return ModelTime(total.seconds, total.runs, total.cpu_seconds)


@contextmanager
def timing(clock: Callable[[], float] = time.monotonic,
           cpu_clock: Callable[[], float] = time.thread_time) -> Iterator[None]:
    """Count the with-block as one model run of the calling thread (also when it raises)."""
    start, cpu = clock(), cpu_clock()
    try:
        yield
    finally:
        total = _TOTAL
        total.seconds += clock() - start
        total.cpu_seconds += cpu_clock() - cpu
        total.runs += 1
