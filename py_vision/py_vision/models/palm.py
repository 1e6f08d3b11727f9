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
MediaPipe's palm detector (palm_detection_lite.tflite) and the hand region it gives.

The frame is letterboxed into the model's 192x192 input (values 0 to 1); the model scores 2016
anchors (strides 8, 16, 16, 16) and regresses a palm box and seven keypoints for each (0: the
wrist, 2: the middle finger's knuckle, ...); scores of at least `min_score` are merged by
weighted non-maximum suppression (IoU 0.3), as in MediaPipe's palm_detection graph. A palm is
easier to find than a whole hand (rigid, square, no fingers to spread), and from it
`hand_region` derives the square the landmark model looks at: turned so that the wrist is below
the middle finger's knuckle, scaled 2.6 times the palm and moved half a palm towards the
fingers (MediaPipe's palm_detection_detection_to_roi graph).
"""

from dataclasses import dataclass
import math
from typing import List

import numpy as np
from py_vision.models.anchors import SsdDetector, SsdModel
from py_vision.models.runtime import Model

__all__ = ['enlarge', 'hand_region', 'HandRegion', 'Palm', 'PalmDetector', 'upright_rotation']

MODEL_FILE = 'palm_detection_lite.tflite'
_WRIST, _MIDDLE_KNUCKLE = 0, 2
# 192x192 input, values 0 to 1, seven keypoints; the outputs read, by their names in
# palm_detection_lite.tflite (else the first two): the regressors (box and keypoints per
# anchor) and the scores.
_MODEL = SsdModel(192, 7, (0.0, 1.0), (
    (('Identity',), (1, 2016, 18)), (('Identity_1',), (1, 2016, 1))))


@dataclass
class Palm:
    """A palm: box (x, y, w, h) and keypoints (7, 2) in frame pixels, and its score (0 to 1)."""

    box: np.ndarray
    score: float
    keypoints: np.ndarray


@dataclass(frozen=True)
class HandRegion:
    """A square of `side` pixels around a hand, centred on (x, y), turned by `rotation` rad."""

    x: float
    y: float
    side: float
    rotation: float


class PalmDetector(SsdDetector):
    """Finds palms in bgr8 frames with the palm detection model."""

    def __init__(self, model: Model, min_score: float = 0.5, nms_threshold: float = 0.3,
                 max_palms: int = 0):
        """Use a loaded palm_detection_lite model; max_palms 0 means no limit."""
        super().__init__(model, _MODEL, min_score, nms_threshold, max_palms)

    def detect(self, image_bgr: np.ndarray) -> List[Palm]:
        """Return the palms in the frame, best score first."""
        return [Palm(*found) for found in self.detections(image_bgr)]


def upright_rotation(start: np.ndarray, end: np.ndarray) -> float:
    """Return the rotation (radians, -pi to pi) that turns start -> end to point up."""
    angle = math.pi / 2 - math.atan2(-(end[1] - start[1]), end[0] - start[0])
    return angle - 2 * math.pi * math.floor((angle + math.pi) / (2 * math.pi))


def enlarge(x: float, y: float, width: float, height: float, rotation: float, scale: float,
            shift: float) -> HandRegion:
    """
    Return the square around a turned box (centre x, y): MediaPipe's rect transformation.

    The centre moves by `shift` times the box's height along the box's turned vertical
    (negative: towards its top, where the fingers are); the side is `scale` times the box's
    longer side.
    """
    return HandRegion(x - height * shift * math.sin(rotation),
                      y + height * shift * math.cos(rotation),
                      max(width, height) * scale, rotation)


def hand_region(palm: Palm, scale: float = 2.6, shift: float = -0.5) -> HandRegion:
    """
    Return the square around the whole hand of a palm.

    Turned so that the wrist -> middle knuckle direction points up, centred half the palm's
    height towards the fingers, 2.6 times the palm box's longer side.
    """
    x, y, width, height = (float(value) for value in palm.box)
    rotation = upright_rotation(palm.keypoints[_WRIST], palm.keypoints[_MIDDLE_KNUCKLE])
    return enlarge(x + width / 2, y + height / 2, width, height, rotation, scale, shift)
