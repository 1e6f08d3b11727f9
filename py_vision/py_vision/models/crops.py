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
A model's input cut from a camera frame, and the way back to the frame's pixels.

`letterbox` fits the whole frame into a model's square input, keeping its aspect ratio and
padding the rest with black (MediaPipe's detectors: keep_aspect_ratio, BORDER_ZERO);
`rotated_crop` cuts a rotated square out of the frame (the hand landmark model's input: the
hand turned upright). Both sample the frame bilinearly, as MediaPipe's CPU conversion of an
image to a tensor does (one interpolation from the frame to the model's input, no averaging
of the pixels between samples), convert BGR to RGB, scale the values to the model's range in
one pass into the float32 tensor, and return the affine matrix that maps the input's pixels
back to the frame's. Given `InputBuffers`, they make the input in the same arrays frame after
frame instead of new ones.
"""

from dataclasses import dataclass
import math
from typing import Dict, Optional, Tuple

import cv2
import numpy as np

__all__ = ['Crop', 'InputBuffers', 'letterbox', 'rotated_crop']


@dataclass
class Crop:
    """A model input (1, height, width, 3) float32 RGB and `to_image`, (2, 3) input -> frame."""

    tensor: np.ndarray
    to_image: np.ndarray

    def points_to_image(self, points: np.ndarray) -> np.ndarray:
        """Map (..., 2) points in input pixels to frame pixels."""
        return points @ self.to_image[:, :2].T + self.to_image[:, 2]


class InputBuffers:
    """
    The arrays a model's input is made in, kept from one frame to the next.

    An input is a few hundred kB (a 224x224 float32 tensor: 602 kB); made anew each frame,
    each array was memory the C library mapped, faulted in and gave back again. One set per
    model input, used by one thread: a Crop made in it holds until the next one is made.
    """

    def __init__(self):
        self._arrays: Dict[str, np.ndarray] = {}

    def get(self, name: str, shape: Tuple[int, ...], dtype) -> np.ndarray:
        """Return the array called name, of that shape and type (its contents left over)."""
        array = self._arrays.get(name)
        if array is None or array.shape != shape or array.dtype != dtype:
            array = self._arrays[name] = np.empty(shape, dtype)
        return array


def _tensor(bgr: np.ndarray, value_range: Tuple[float, float],
            buffers: InputBuffers) -> np.ndarray:
    """Return the (1, height, width, 3) float32 RGB tensor of a bgr8 input, in value_range."""
    low, high = value_range
    rgb = cv2.cvtColor(bgr, cv2.COLOR_BGR2RGB, dst=buffers.get('rgb', bgr.shape, np.uint8))
    tensor = buffers.get('tensor', (1,) + bgr.shape, np.float32)
    # x * scale + low in float32, element by element: the same values as converting first.
    np.multiply(rgb, np.float32((high - low) / 255.0), out=tensor[0], dtype=np.float32)
    if low:
        tensor += np.float32(low)
    return tensor


def _check(image: np.ndarray) -> None:
    if not isinstance(image, np.ndarray) or image.ndim != 3 or image.shape[2] != 3 \
            or image.dtype != np.uint8 or min(image.shape[:2]) < 1:
        raise ValueError('expected a bgr8 image (height, width, 3) uint8, got %s'
                         % (getattr(image, 'shape', type(image).__name__),))


def letterbox(image_bgr: np.ndarray, width: int, height: int,
              value_range: Tuple[float, float], buffers: Optional[InputBuffers] = None) -> Crop:
    """Fit the whole image into width x height, centred, black bars where it does not reach."""
    _check(image_bgr)
    buffers = buffers or InputBuffers()
    rows, columns = image_bgr.shape[:2]
    scale = min(width / columns, height / rows)
    fitted_w = max(1, int(round(columns * scale)))
    fitted_h = max(1, int(round(rows * scale)))
    left, top = (width - fitted_w) // 2, (height - fitted_h) // 2
    padded = buffers.get('pixels', (height, width, 3), np.uint8)
    padded.fill(0)
    fitted = padded[top:top + fitted_h, left:left + fitted_w]
    # Straight into the black square: OpenCV writes into the view it is given (where it
    # would not, the copy does).
    resized = cv2.resize(image_bgr, (fitted_w, fitted_h), dst=fitted,
                         interpolation=cv2.INTER_LINEAR)
    if resized is not fitted:
        fitted[...] = resized
    tensor = _tensor(padded, value_range, buffers)
    sx, sy = columns / fitted_w, rows / fitted_h
    to_image = np.array([[sx, 0, -left * sx], [0, sy, -top * sy]], np.float64)
    return Crop(tensor, to_image)


def rotated_crop(image_bgr: np.ndarray, center: Tuple[float, float], side: float,
                 rotation: float, size: int, value_range: Tuple[float, float],
                 buffers: Optional[InputBuffers] = None) -> Crop:
    """
    Cut a square of `side` pixels centred on `center`, turned by `rotation` radians.

    The input's up (its -y) is the frame's direction (sin r, -cos r): a rotation of pi/2 takes
    what points right in the frame to point up in the input. Outside the frame, the edge
    pixels are repeated.
    """
    _check(image_bgr)
    buffers = buffers or InputBuffers()
    cos, sin = math.cos(rotation) * side / size, math.sin(rotation) * side / size
    cx, cy = center
    half = size / 2
    to_image = np.array([[cos, -sin, cx - cos * half + sin * half],
                         [sin, cos, cy - sin * half - cos * half]], np.float64)
    crop = cv2.warpAffine(image_bgr, to_image, (size, size),
                          dst=buffers.get('pixels', (size, size, 3), np.uint8),
                          flags=cv2.INTER_LINEAR | cv2.WARP_INVERSE_MAP,
                          borderMode=cv2.BORDER_REPLICATE)
    return Crop(_tensor(crop, value_range, buffers), to_image)
