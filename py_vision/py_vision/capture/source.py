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

A source is configured with a pixel format, size and rate (`configure`, which answers with
what it really gives: `StreamFormat`), streams between `start()` and `stop()` (the device
stays open and keeps its buffers and controls in between), and hands out one `Frame` at a time
(`next_frame`): the bytes as the device sent them, in a pixel format of the table
(pixel_formats), with the capture time, the frame's number and whether the device flagged it.
A frame's bytes may be the device's own buffer: they are valid until the next `next_frame()`
(or `stop()`), which gives the buffer back. Besides, a source says what it offers
(`FrameFormat`), its controls (`ControlInfo`, read from the device at each call) and sets
them by V4L2 id; `interrupt()` ends a `next_frame()` waiting in another thread.
`capture_into(arrays)` offers memory of the caller's own for the device to write frames
into (a V4L2 driver that takes user memory): False where the source cannot; a frame written
there names its array (`Frame.user_buffer`).
"""

from dataclasses import dataclass, field
import time
from typing import Dict, List, Optional, Protocol, Sequence, Tuple

import numpy as np
from py_vision.capture.controls import ControlInfo
from py_vision.capture.pixel_formats import find, PixelFormat, placed

__all__ = ['BusFull', 'Clock', 'FrameFormat', 'FrameSize', 'FrameSource', 'Frame', 'MONOTONIC',
           'SourceError', 'StreamFormat']


class SourceError(Exception):
    """A video_device that cannot be opened; the message is one line naming it."""


class BusFull(SourceError):
    """The camera's stream does not fit on its USB bus now (other streams take it): retry."""


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
    """
    One pixel format a device offers: its FourCC, its description and sizes.

    Most cameras offer discrete sizes and rates (`sizes`). One that scales offers any size
    within `size_range` (min width, min height, max width, max height) and one with a stepwise
    frame interval any rate within `rate_range` (lowest, highest); `sizes` then lists common
    sizes within them.
    """

    fourcc: str
    description: str
    sizes: Tuple[FrameSize, ...]
    size_range: Optional[Tuple[int, int, int, int]] = None
    rate_range: Optional[Tuple[float, float]] = None

    def nearest(self, width: int, height: int, fps: float) -> Tuple[int, int, float]:
        """
        Return the size and rate this format offers nearest to a request.

        The nearest size is the one with the least area outside their overlap (uvcvideo's
        measure); the nearest rate is the closest the size offers (the higher on a tie).
        """
        size_range, sizes = self.size_range, self.sizes
        if size_range and size_range[0] <= width <= size_range[2] \
                and size_range[1] <= height <= size_range[3]:
            chosen = (width, height)
        elif sizes:
            best = min(sizes, key=lambda s: _outside_overlap(s.width, s.height, width, height))
            chosen = (best.width, best.height)
        else:
            chosen = (width, height)
        if self.rate_range and self.rate_range[0] <= fps <= self.rate_range[1]:
            return chosen[0], chosen[1], fps
        near = min(sizes, key=lambda s: _outside_overlap(s.width, s.height, *chosen),
                   default=None)
        rates = list(near.rates) if near is not None else []
        if self.rate_range:
            rates += list(self.rate_range)
        if not rates:
            return chosen[0], chosen[1], fps
        return chosen[0], chosen[1], min(rates, key=lambda rate: (abs(rate - fps), -rate))


def _outside_overlap(width, height, other_width, other_height):
    overlap = min(width, other_width) * min(height, other_height)
    return width * height + other_width * other_height - 2 * overlap


@dataclass(frozen=True)
class StreamFormat:
    """What a source gives once configured: format (FourCC), size, rate, row length in bytes."""

    fourcc: str
    width: int
    height: int
    fps: float
    bytesperline: int = 0     # 0: the format's natural row (or compressed)

    @property
    def pixel_format(self) -> Optional[PixelFormat]:
        """Return the format from the table, or None when py_vision does not know it."""
        return find(self.fourcc)


@dataclass(slots=True)
class Frame:
    """
    One captured frame: the bytes as the device sent them, converted only on demand.

    `data` is 1-D uint8 (only the bytes the device filled); `image(output)` converts them once
    per output (bgr8, rgb8, mono8, mono16, or native: the pixels as sent wherever a sensor_msgs
    encoding has them), a view of `data` where no conversion is needed. A frame whose bytes
    are not a whole image is `corrupt` (found out on receipt, or when a JPEG does not decode);
    one the driver flagged as an error has `error` set and no data.
    """

    index: Optional[int]                    # the device's number for it (V4L2: sequence)
    capture_time: Optional[float]           # time.monotonic() of the capture, if known
    pixel_format: PixelFormat
    width: int = 0
    height: int = 0
    data: Optional[np.ndarray] = None
    bytesperline: int = 0
    error: bool = False                     # flagged by the driver (V4L2_BUF_FLAG_ERROR)
    corrupt: bool = False                   # not a whole image: never to be published
    decoded: bool = False                   # image() had to decode a JPEG
    user_buffer: Optional[int] = None       # which capture_into() array its bytes are in
    _images: Optional[Dict[str, np.ndarray]] = field(default=None, repr=False)

    @property
    def jpeg(self) -> Optional[np.ndarray]:
        """Return the camera's own JPEG bytes (MJPEG), or None for a raw frame."""
        return self.data if self.pixel_format.jpeg else None

    def encoding(self, output: str) -> str:
        """Return the sensor_msgs encoding image(output) is in."""
        return self.pixel_format.native_encoding if output == 'native' else output

    def image(self, output: str = 'bgr8',
              out: Optional[np.ndarray] = None) -> Optional[np.ndarray]:
        """
        Return the frame as `output` (see the class's text); None if it is not a picture.

        With `out` (a message's pixel bytes, shaped as the image) the image is written there,
        converted on the way, and `out` is returned; an image that does not fit it (another
        size or type) comes back in an array of its own, `out` untouched. Either is the
        frame's image from then on (valid while `out` is unchanged).
        """
        images = self._images
        if images is None:
            images = self._images = {}
        image = images.get(output)
        if image is not None or self.corrupt or self.data is None:
            return placed(image, out)
        pixel_format = self.pixel_format
        view = pixel_format.view(self.data, self.width, self.height, self.bytesperline)
        image = pixel_format.convert(view, output, out)
        if pixel_format.compressed:
            self.decoded = True
            self.corrupt = image is None
        images[output] = image
        return image

    def bgr(self) -> Optional[np.ndarray]:
        """Return the frame as a BGR image (decoding the camera's JPEG once); None if corrupt."""
        return self.image('bgr8')


class FrameSource(Protocol):
    """What the camera layer uses from a frame source (see the module's text)."""

    def configure(self, pixel_format: PixelFormat, width: int, height: int,  # noqa: D102
                  fps: float) -> StreamFormat: ...

    def start(self) -> None: ...  # noqa: D102

    def stop(self) -> None: ...  # noqa: D102

    def next_frame(self) -> Optional[Frame]: ...  # noqa: D102

    def capture_into(self, arrays: Optional[Sequence[np.ndarray]]) -> bool: ...  # noqa: D102

    def interrupt(self) -> None: ...  # noqa: D102

    def release(self) -> None: ...  # noqa: D102

    def formats(self) -> List[FrameFormat]: ...  # noqa: D102

    def controls(self) -> List[ControlInfo]: ...  # noqa: D102

    def set_control(self, cid: int, value: int) -> Optional[str]: ...  # noqa: D102
