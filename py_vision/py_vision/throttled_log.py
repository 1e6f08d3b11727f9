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
At most one log line per kind of event and period: a flood of events is not a flood of lines.

What arrives over ROS or HTTP (malformed requests, oversized images, refused clients) is
logged through it.
"""

import math
import threading
import time
from typing import Callable, Dict, Hashable, Optional, Tuple


class ThrottledLog:
    """
    Log the first event of each key at once, then at most one line per period.

    A line after a quiet spell says how many like it were held back meanwhile. Each severity
    has its own method, and so its own call site: rclpy's loggers refuse a call site whose
    severity changes between calls (ValueError).
    """

    def __init__(self, logger, period: float = 5.0, clock: Callable[[], float] = time.monotonic):
        self._logger = logger
        self._period = period
        self._clock = clock
        self._seen: Dict[Hashable, Tuple[float, int]] = {}  # key: (last logged, held back)
        self._lock = threading.Lock()

    def _line(self, key: Hashable, message: str) -> Optional[str]:
        """Return the line to log for this event now, or None when it is held back."""
        now = self._clock()
        with self._lock:
            last, held = self._seen.get(key, (-math.inf, 0))
            if now - last < self._period:
                self._seen[key] = (last, held + 1)
                return None
            self._seen[key] = (now, 0)
        if held:
            message += ' (%d more like it in the last %.0f s)' % (held, now - last)
        return message

    def warning(self, key: Hashable, message: str) -> None:
        """Log message as a warning, unless one of key was logged less than a period ago."""
        line = self._line(key, message)
        if line is not None:
            self._logger.warning(line)

    def error(self, key: Hashable, message: str) -> None:
        """Log message as an error, unless one of key was logged less than a period ago."""
        line = self._line(key, message)
        if line is not None:
            self._logger.error(line)
