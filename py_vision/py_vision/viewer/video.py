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
A camera's H.264 for browsers that decode it themselves (WebCodecs), and how it is framed.

`VideoStore` keeps the access units since the newest keyframe that a decoder can start at, so
a browser that connects gets a picture at once (the keyframe and what follows it) instead of
waiting up to a keyframe interval, and a browser that falls behind resumes at a keyframe:
nothing it is sent lacks its references. `GET /video` sends each unit as `frame()` frames it:
a 5-byte header (the unit's length, big-endian uint32, then 1 where a decoder can start,
0 otherwise) and the unit's Annex B bytes.
"""

import struct
import threading
from typing import List, Optional, Tuple

__all__ = ['frame', 'HEADER', 'VideoStore']

HEADER = struct.Struct('>IB')
# A group of pictures longer than this (a camera that sends a keyframe every minute) is not
# kept whole: browsers that connect meanwhile wait for the next keyframe.
MAX_UNITS = 900
MAX_BYTES = 64 * 1024 * 1024


def frame(unit: bytes, start: bool) -> bytes:
    """Return a unit as GET /video sends it: its header, then its bytes."""
    return HEADER.pack(len(unit), 1 if start else 0) + unit


class VideoStore:
    """The access units since the newest keyframe, numbered; browsers read them from there."""

    def __init__(self):
        self._lock = threading.Condition()
        self._units: List[Tuple[bytes, bool]] = []   # (unit, a decoder can start at it)
        self._first = 1              # the number of _units[0]
        self._keyframe = False       # _units[0] is a keyframe a decoder can start at
        self._number = 0             # the newest unit's number
        self._bytes = 0
        self._closing = False
        self.codec = ''              # the codec string of the newest keyframe ('avc1.42c01e')

    @property
    def number(self) -> int:
        """Return how many units were submitted so far."""
        return self._number

    def submit(self, unit: bytes, start: bool, codec: str = '') -> None:
        """Add the newest unit; start: a decoder can start at it (keyframe, parameter sets)."""
        with self._lock:
            self._number += 1
            if start:
                self._units, self._first, self._keyframe, self._bytes = [], self._number, True, 0
                self.codec = codec or self.codec
            if self._keyframe and (len(self._units) >= MAX_UNITS
                                   or self._bytes + len(unit) > MAX_BYTES):
                self._units, self._keyframe, self._bytes = [], False, 0
            if self._keyframe:
                self._units.append((unit, start))
                self._bytes += len(unit)
            self._lock.notify_all()

    def since(self, number: int,
              timeout: float) -> Optional[Tuple[int, List[Tuple[bytes, bool]]]]:
        """
        Wait up to timeout for units after `number`; return (newest number, [(unit, start)]).

        The units follow `number` when it is still in the group kept; otherwise they start at
        the keyframe. Empty when there is nothing new, or nothing a decoder could start at
        yet; None when the viewer is closing.
        """
        with self._lock:
            self._lock.wait_for(lambda: self._closing or self._number > number, timeout)
            if self._closing:
                return None
            if self._number <= number:
                return number, []
            if not self._keyframe:
                # Nothing to start at: the reader waits for the next keyframe from here.
                return self._number, []
            if self._first <= number:
                return self._number, self._units[number + 1 - self._first:]
            return self._number, list(self._units)

    def close(self) -> None:
        """Wake every waiting client for good: the viewer is closing."""
        with self._lock:
            self._closing = True
            self._lock.notify_all()
