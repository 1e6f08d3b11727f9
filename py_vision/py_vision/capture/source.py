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
The source interface: what every frame source (V4L2, video file, synthetic) gives the camera.

A source has OpenCV's VideoCapture interface for streaming (isOpened, read, set, get, release;
formats and sizes are negotiated through set/get as with OpenCV), plus what OpenCV cannot say:
the capture time and index of the last frame, the formats the device offers (`FrameFormat`),
its controls (`ControlInfo`, read from the device at each call) and a way to set them by V4L2
id, and interrupt() to end a read that waits for its frame.
"""

from dataclasses import dataclass, field
import time
from typing import List, Optional, Protocol, Tuple

import cv2
import numpy as np
from py_vision.capture.controls import ControlInfo

__all__ = ['Clock', 'FrameFormat', 'FrameSize', 'FrameSource', 'Frame', 'MONOTONIC',
           'SourceError']


class SourceError(Exception):
    """A video_device that cannot be opened; the message is one line naming it."""


class Clock(Protocol):
    """The time a source paces itself by: time.monotonic() and time.sleep() in real life."""

    def now(self) -> float: ...  # noqa: D102

    def sleep(self, seconds: float) -> None: ...  # noqa: D102


class _Monotonic:
    """The real clock."""

    now = staticmethod(time.monotonic)
    sleep = staticmethod(time.sleep)


MONOTONIC: Clock = _Monotonic()


@dataclass(frozen=True)
class FrameSize:
    """One frame size a pixel format offers, and its frame rates (highest first)."""

    width: int
    height: int
    rates: Tuple[float, ...]


@dataclass(frozen=True)
class FrameFormat:
    """One pixel format a device offers: 'YUYV' or 'MJPG', its description and sizes."""

    fourcc: str
    description: str
    sizes: Tuple[FrameSize, ...]


@dataclass
class Frame:
    """One captured frame: BGR pixels, or the camera's JPEG bytes decoded only on demand."""

    index: Optional[int]
    capture_time: Optional[float]           # time.monotonic() of the capture, if known
    width: int = 0
    height: int = 0
    jpeg: Optional[np.ndarray] = None      # 1-D uint8, the camera's own bytes (MJPEG)
    _bgr: Optional[np.ndarray] = field(default=None, repr=False)
    decoded: bool = False                   # bgr() had to decode the JPEG
    corrupt: bool = False                   # not a whole image: never to be published

    def bgr(self) -> Optional[np.ndarray]:
        """Return the frame as a BGR image (decoding the camera's JPEG once); None if corrupt."""
        if self._bgr is None and self.jpeg is not None and not self.decoded:
            self.decoded = True
            self._bgr = cv2.imdecode(self.jpeg, cv2.IMREAD_COLOR)
            self.corrupt = self._bgr is None
        return self._bgr


class FrameSource(Protocol):
    """What the camera layer uses from a frame source."""

    last_index: Optional[int]          # source frame number of the last frame read, if known
    last_capture_time: Optional[float]  # its capture time, time.monotonic(), if known

    def isOpened(self) -> bool: ...  # noqa: N802, D102 (OpenCV's interface)

    def read(self) -> Tuple[bool, Optional[np.ndarray]]: ...  # noqa: D102

    def set(self, prop_id: int, value: float) -> bool: ...  # noqa: A003, D102

    def get(self, prop_id: int) -> float: ...  # noqa: D102

    def release(self) -> None: ...  # noqa: D102

    def interrupt(self) -> None: ...  # noqa: D102

    def formats(self) -> List[FrameFormat]: ...  # noqa: D102

    def controls(self) -> List[ControlInfo]: ...  # noqa: D102

    def set_control(self, cid: int, value: int) -> Optional[str]: ...  # noqa: D102
