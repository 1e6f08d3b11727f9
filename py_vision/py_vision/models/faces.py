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
MediaPipe's short-range face detector (face_detection_short_range.tflite) on camera frames.

The frame is letterboxed into the model's 128x128 input (values -1 to 1); the model scores 896
anchors (strides 8, 16, 16, 16) and regresses a box and six keypoints for each; the anchors
scoring at least `min_score` are merged by weighted non-maximum suppression (IoU 0.3), as in
MediaPipe's face_detection graph. The model is for faces near the camera (up to about 2 m,
selfie distance): a face narrower than about a seventh of the frame's longer side is found
poorly or not at all (the astronaut's face: found at 94 pixels wide in a 640-wide frame, score
0.9; at 73 pixels, score 0.6; missed at 64).
"""

from dataclasses import dataclass
from typing import List

import numpy as np
from py_vision.models.anchors import SsdDetector, SsdModel
from py_vision.models.files import shipped_model
from py_vision.models.runtime import load, Model

__all__ = ['Face', 'FaceDetector', 'FACE_KEYPOINTS']

# The keypoints in their order, as the person sees them (their right eye is the one on the
# left of an unmirrored picture).
FACE_KEYPOINTS = ('right_eye', 'left_eye', 'nose_tip', 'mouth_centre', 'right_ear_tragion',
                  'left_ear_tragion')

MODEL_FILE = 'face_detection_short_range.tflite'
# 128x128 input, values -1 to 1, six keypoints; the outputs read, by their names in
# face_detection_short_range.tflite (else the first two): the regressors (box and keypoints
# per anchor) and the scores.
_MODEL = SsdModel(128, 6, (-1.0, 1.0), (
    (('regressors',), (1, 896, 16)), (('classificators',), (1, 896, 1))))


@dataclass
class Face:
    """A face: box (x, y, w, h) and keypoints (6, 2) in frame pixels, and its score (0 to 1)."""

    box: np.ndarray
    score: float
    keypoints: np.ndarray


class FaceDetector(SsdDetector):
    """Finds faces in bgr8 frames with the short-range face detection model."""

    def __init__(self, model: Model, min_score: float = 0.5, nms_threshold: float = 0.3,
                 max_faces: int = 0):
        """Use a loaded face_detection_short_range model; max_faces 0 means no limit."""
        super().__init__(model, _MODEL, min_score, nms_threshold, max_faces)

    @classmethod
    def from_file(cls, path: str = '', threads: int = 1, **options) -> 'FaceDetector':
        """Load the model file (by default the shipped one) and make a detector of it."""
        return cls(load(path or shipped_model(MODEL_FILE), threads), **options)

    def detect(self, image_bgr: np.ndarray) -> List[Face]:
        """Return the faces in the frame, best score first."""
        return [Face(*found) for found in self.detections(image_bgr)]
