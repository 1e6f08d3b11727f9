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
The newest frame a viewer shows, and its JPEG.

`submit()` only stores a reference to the image and wakes the waiting clients: a frame is
encoded to JPEG once, when the first client wants it, and never when nobody watches.
"""

import threading
from typing import Optional, Tuple, Union

import cv2
import numpy as np


class FrameStore:
    """Holds the newest frame (an image or a JPEG); encodes it at most once."""

    def __init__(self, jpeg_quality: int):
        if not 0 <= int(jpeg_quality) <= 100:
            raise ValueError('jpeg_quality must be within 0..100, got %r' % jpeg_quality)
        self._jpeg_params = [cv2.IMWRITE_JPEG_QUALITY, int(jpeg_quality)]
        self._frame_lock = threading.Condition()
        self._frame: Union[np.ndarray, bytes, None] = None
        self._number = 0
        self._closing = False
        self._encode_lock = threading.Lock()
        self._jpeg: Optional[bytes] = None
        self._jpeg_number = 0
        self.encoded = 0  # frames encoded so far (at most one per submitted frame)

    @property
    def number(self) -> int:
        """Return how many frames were submitted so far."""
        return self._number

    def submit(self, image: np.ndarray) -> None:
        """Make image (uint8 BGR HxWx3 or mono HxW) the newest frame; it must not change later."""
        if not isinstance(image, np.ndarray):
            raise ValueError('the viewer shows numpy images, got %s' % type(image).__name__)
        if image.dtype != np.uint8 or not (
                image.ndim == 2 or (image.ndim == 3 and image.shape[2] in (1, 3))):
            raise ValueError('the viewer shows uint8 BGR (HxWx3) or mono (HxW) images, got %s %s'
                             % (image.dtype, image.shape))
        self._put(image)

    def submit_jpeg(self, jpeg: bytes) -> None:
        """Make an already encoded JPEG (bytes) the newest frame; it is served as it is."""
        if not isinstance(jpeg, bytes) or jpeg[:2] != b'\xff\xd8':
            raise ValueError('submit_jpeg takes the bytes of a JPEG image')
        self._put(jpeg)

    def _put(self, frame):
        with self._frame_lock:
            self._frame = frame
            self._number += 1
            self._frame_lock.notify_all()

    def wait_newer(self, number: int, timeout: float) -> Optional[int]:
        """Wait for a frame newer than number; return the newest number (None when closing)."""
        with self._frame_lock:
            self._frame_lock.wait_for(
                lambda: self._closing or self._number != number, timeout)
            return None if self._closing else self._number

    def latest_jpeg(self) -> Tuple[int, Optional[bytes]]:
        """Return (number, JPEG bytes) of the newest frame, encoding it if nobody did yet."""
        with self._encode_lock:
            with self._frame_lock:
                number, frame = self._number, self._frame
            if frame is None:
                return 0, None
            if number != self._jpeg_number and isinstance(frame, bytes):
                self._jpeg, self._jpeg_number = frame, number
            elif number != self._jpeg_number:
                ok, buffer = cv2.imencode('.jpg', frame, self._jpeg_params)
                if not ok:
                    raise ValueError('JPEG encoding failed for a %s frame' % (frame.shape,))
                self._jpeg, self._jpeg_number = buffer.tobytes(), number
                self.encoded += 1
            return self._jpeg_number, self._jpeg

    def close(self) -> None:
        """Wake every waiting client for good: the viewer is closing."""
        with self._frame_lock:
            self._closing = True
            self._frame_lock.notify_all()
