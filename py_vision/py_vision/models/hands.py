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
Hands and their 21 landmarks: MediaPipe's palm detector, then its hand landmark model.

`HandTracker.find(frame)` runs the palm detector on the whole frame; for each palm (at most
`max_hands`) it cuts the hand's region (palm.hand_region), turned upright, into the landmark
model's 224x224 input (values 0 to 1); the model gives 21 landmarks (HAND_LANDMARKS), a hand
presence score and which hand it is; the landmarks go back into the frame through the crop's
matrix. A region whose presence score is below `min_hand_score` is no hand. Each frame is
searched afresh (MediaPipe also tracks a hand from the previous frame's landmarks to skip the
palm detector; this does not).

Which hand: the model was trained on mirrored pictures (a selfie view) and answers 'Left' for
what looks like a left hand in the picture. A camera that does not mirror (a USB camera as it
comes, py_vision's default) shows the person's right hand where a mirror would show their left,
so `Hand.handedness` swaps the model's answer unless `mirrored=True` says the frames are
mirrored. Either way `handedness` is the hand of the person in front of the camera.
"""

from dataclasses import dataclass
from typing import List

import numpy as np
from py_vision.models.crops import rotated_crop
from py_vision.models.files import shipped_model
from py_vision.models.palm import hand_region, MODEL_FILE as PALM_FILE, PalmDetector
from py_vision.models.runtime import check_shapes, load, Model

__all__ = ['Hand', 'HAND_LANDMARKS', 'HandTracker', 'LANDMARK_FILE']

LANDMARK_FILE = 'hand_landmark_lite.tflite'

# The 21 landmarks in the model's order: the wrist, then each finger from its root to its tip.
HAND_LANDMARKS = (
    'wrist',
    'thumb_cmc', 'thumb_mcp', 'thumb_ip', 'thumb_tip',
    'index_mcp', 'index_pip', 'index_dip', 'index_tip',
    'middle_mcp', 'middle_pip', 'middle_dip', 'middle_tip',
    'ring_mcp', 'ring_pip', 'ring_dip', 'ring_tip',
    'pinky_mcp', 'pinky_pip', 'pinky_dip', 'pinky_tip',
)

_SIZE = 224


@dataclass
class Hand:
    """
    A hand in a frame.

    landmarks: (21, 3) float32, HAND_LANDMARKS' order: x, y in frame pixels, z the depth
    relative to the wrist in about the same scale (smaller: nearer the camera);
    handedness: 'left' or 'right', the person's hand (see the module's docstring);
    score: the landmark model's hand presence score, 0 to 1.
    """

    landmarks: np.ndarray
    handedness: str
    score: float


class HandTracker:
    """Finds hands and their landmarks in bgr8 frames."""

    def __init__(self, palm_model: Model, landmark_model: Model, min_palm_score: float = 0.5,
                 min_hand_score: float = 0.5, max_hands: int = 2, mirrored: bool = False):
        """Use a loaded palm_detection_lite and hand_landmark_lite model."""
        check_shapes(landmark_model, [(1, _SIZE, _SIZE, 3)], ((1, 63), (1, 1), (1, 1)))
        self.palms = PalmDetector(palm_model, min_palm_score, max_palms=max_hands)
        self.landmark_model = landmark_model
        self.min_hand_score = min_hand_score
        self.mirrored = mirrored

    @classmethod
    def from_files(cls, palm_path: str = '', landmark_path: str = '', threads: int = 1,
                   **options) -> 'HandTracker':
        """Load the two model files (by default the shipped ones) and make a tracker of them."""
        return cls(load(palm_path or shipped_model(PALM_FILE), threads),
                   load(landmark_path or shipped_model(LANDMARK_FILE), threads), **options)

    def find(self, image_bgr: np.ndarray) -> List[Hand]:
        """Return the hands in the frame, most certain first."""
        hands = []
        for palm in self.palms.detect(image_bgr):
            region = hand_region(palm)
            crop = rotated_crop(image_bgr, (region.x, region.y), region.side, region.rotation,
                                _SIZE, (0.0, 1.0))
            points, presence, left = self.landmark_model.run(crop.tensor)[:3]
            score = float(presence.reshape(-1)[0])
            if score < self.min_hand_score:
                continue
            points = points.reshape(21, 3).astype(np.float64)
            landmarks = np.empty((21, 3), np.float32)
            landmarks[:, :2] = crop.points_to_image(points[:, :2])
            landmarks[:, 2] = points[:, 2] * (region.side / _SIZE)
            # The model's 'Left' is a left hand as a mirror shows it (module docstring).
            looks_left = float(left.reshape(-1)[0]) > 0.5
            handedness = 'left' if looks_left == self.mirrored else 'right'
            hands.append(Hand(landmarks, handedness, score))
        hands.sort(key=lambda hand: -hand.score)
        return hands
