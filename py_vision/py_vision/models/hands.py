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
matrix. A region whose presence score is below `min_hand_score` is no hand.

Tracking (`track=True`, the default, as MediaPipe does): the hands found in one frame give the
regions to look at in the next (`landmark_region`: the square around the palm's landmarks,
turned from the wrist to the knuckles, twice their size, a tenth towards the fingers), and the
palm detector runs only while fewer than `max_hands` hands are tracked. With one hand tracked
and max_hands=1, a frame costs one landmark pass instead of a palm detection and a landmark
pass. A tracked hand whose presence score drops below `min_hand_score` is dropped, and the
palm detector looks for hands again in the next frame. For unrelated pictures, track=False.

Which hand: the model was trained on mirrored pictures (a selfie view) and answers 'Left' for
what looks like a left hand in the picture. A camera that does not mirror (a USB camera as it
comes, py_vision's default) shows the person's right hand where a mirror would show their left,
so `Hand.handedness` swaps the model's answer unless `mirrored=True` says the frames are
mirrored. Either way `handedness` is the hand of the person in front of the camera.
"""

from dataclasses import dataclass
import math
from typing import List, Optional

import numpy as np
from py_vision.models.crops import InputBuffers, rotated_crop
from py_vision.models.files import shipped_model
from py_vision.models.palm import enlarge, hand_region, HandRegion, MODEL_FILE as PALM_FILE
from py_vision.models.palm import PalmDetector, upright_rotation
from py_vision.models.runtime import find_outputs, load, Model

__all__ = ['Hand', 'HAND_LANDMARKS', 'HandTracker', 'LANDMARK_FILE', 'landmark_region']

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
# The outputs read, by their names in hand_landmark_lite.tflite (another export of the model
# may list them in another order; where these names are not all there, the first three are
# read): the 21 landmarks (x, y in the 224-pixel input, z), the hand presence score and the
# left-hand score. Presence and handedness have the same shape: only the names tell them apart.
_OUTPUTS = ((('Identity',), (1, 63)), (('Identity_1',), (1, 1)), (('Identity_2',), (1, 1)))
# The landmarks that outline the palm (wrist, thumb base, each finger's first two joints), and
# the knuckles whose mean with the middle one gives the hand's direction.
_PALM = [0, 1, 2, 3, 5, 6, 9, 10, 13, 14, 17, 18]
_INDEX_MCP, _MIDDLE_MCP, _RING_MCP = 5, 9, 13
_Z_SPREAD = 0.4
# Two regions this alike (IoU of their upright bounding squares) are one hand.
_SAME_HAND = 0.5


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


def landmark_region(landmarks: np.ndarray, scale: float = 2.0,
                    shift: float = -0.1) -> HandRegion:
    """
    Return the region to look for a hand in the next frame, from its landmarks in this one.

    Turned so that the wrist -> knuckles direction (the middle knuckle averaged with the mean
    of the index and ring ones) points up; the box around the palm's landmarks in that turned
    frame, `scale` times its longer side, moved `shift` times its height towards the fingers.
    """
    # A dozen points: Python's float arithmetic (the same IEEE doubles, in the same order, as
    # numpy's) costs less than as many numpy calls.
    points = np.asarray(landmarks, np.float64)[:, :2].tolist()
    (ix, iy), (mx, my), (rx, ry) = (points[_INDEX_MCP], points[_MIDDLE_MCP],
                                    points[_RING_MCP])
    knuckles = (((ix + rx) / 2 + mx) / 2, ((iy + ry) / 2 + my) / 2)
    rotation = upright_rotation(points[0], knuckles)
    xs, ys = [points[index][0] for index in _PALM], [points[index][1] for index in _PALM]
    middle_x, middle_y = (min(xs) + max(xs)) / 2, (min(ys) + max(ys)) / 2
    cos, sin = math.cos(rotation), math.sin(rotation)
    # The palm's points in the region's own axes (turned back by the rotation).
    relative = [(x - middle_x, y - middle_y) for x, y in zip(xs, ys)]
    turned_x = [x * cos + y * sin for x, y in relative]
    turned_y = [-x * sin + y * cos for x, y in relative]
    low_x, low_y, high_x, high_y = min(turned_x), min(turned_y), max(turned_x), max(turned_y)
    cx, cy = (low_x + high_x) / 2, (low_y + high_y) / 2
    return enlarge(middle_x + (cx * cos - cy * sin), middle_y + (cx * sin + cy * cos),
                   high_x - low_x, high_y - low_y, rotation, scale, shift)


def _overlap(a: HandRegion, b: HandRegion) -> float:
    """Return the IoU of two regions' upright bounding squares."""
    half_a = a.side * (abs(math.cos(a.rotation)) + abs(math.sin(a.rotation))) / 2
    half_b = b.side * (abs(math.cos(b.rotation)) + abs(math.sin(b.rotation))) / 2
    w = max(0.0, min(a.x + half_a, b.x + half_b) - max(a.x - half_a, b.x - half_b))
    h = max(0.0, min(a.y + half_a, b.y + half_b) - max(a.y - half_a, b.y - half_b))
    union = 4 * half_a * half_a + 4 * half_b * half_b - w * h
    return w * h / union if union > 0 else 0.0


class HandTracker:
    """Finds hands and their landmarks in bgr8 frames (one thread at a time: it tracks)."""

    def __init__(self, palm_model: Model, landmark_model: Model, min_palm_score: float = 0.5,
                 min_hand_score: float = 0.5, max_hands: int = 2, mirrored: bool = False,
                 track: bool = True):
        """Use a loaded palm_detection_lite and hand_landmark_lite model."""
        self._outputs = find_outputs(landmark_model, [(1, _SIZE, _SIZE, 3)], _OUTPUTS)
        self.palms = PalmDetector(palm_model, min_palm_score, max_palms=max_hands)
        self.landmark_model = landmark_model
        self.min_hand_score = min_hand_score
        self.max_hands = max_hands
        self.mirrored = mirrored
        self.track = track
        self._tracked: List[HandRegion] = []
        self._buffers = InputBuffers()  # the landmark model's input, made in the same arrays

    @property
    def min_palm_score(self) -> float:
        """Return the palm detector's threshold: a palm scoring less is not looked at."""
        return self.palms.min_score

    @min_palm_score.setter
    def min_palm_score(self, value: float) -> None:
        self.palms.min_score = value

    @classmethod
    def from_files(cls, palm_path: str = '', landmark_path: str = '', threads: int = 1,
                   **options) -> 'HandTracker':
        """Load the two model files (by default the shipped ones) and make a tracker of them."""
        return cls(load(palm_path or shipped_model(PALM_FILE), threads),
                   load(landmark_path or shipped_model(LANDMARK_FILE), threads), **options)

    def forget(self) -> None:
        """Forget the hands tracked: the next frame is searched with the palm detector."""
        self._tracked = []

    def find(self, image_bgr: np.ndarray) -> List[Hand]:
        """Return the hands in the frame, most certain first."""
        regions = list(self._tracked) if self.track else []
        if len(regions) < self.max_hands:
            for palm in self.palms.detect(image_bgr):
                region = hand_region(palm)
                if all(_overlap(region, known) <= _SAME_HAND for known in regions):
                    regions.append(region)
                if len(regions) >= self.max_hands:
                    break
        found = []
        for region in regions:
            hand = self._landmarks(image_bgr, region)
            if hand is not None:
                found.append((hand, landmark_region(hand.landmarks)))
        found.sort(key=lambda item: -item[0].score)
        hands, self._tracked = [], []
        for hand, region in found:
            # Two regions that ended on the same hand: the more certain one is kept.
            if all(_overlap(region, kept) <= _SAME_HAND for kept in self._tracked):
                hands.append(hand)
                self._tracked.append(region)
        return hands

    def _landmarks(self, image_bgr: np.ndarray, region: HandRegion) -> Optional[Hand]:
        """Return the hand in the region, or None when the model sees none there."""
        crop = rotated_crop(image_bgr, (region.x, region.y), region.side, region.rotation,
                            _SIZE, (0.0, 1.0), self._buffers)
        results = self.landmark_model.run(crop.tensor)
        points, presence, left = (results[index] for index in self._outputs)
        score = float(presence.reshape(-1)[0])
        if score < self.min_hand_score:
            return None
        points = points.reshape(21, 3).astype(np.float64)
        landmarks = np.empty((21, 3), np.float32)
        landmarks[:, :2] = crop.points_to_image(points[:, :2])
        # z as MediaPipe scales it: like x, then divided by 0.4 (its training data's z spread).
        landmarks[:, 2] = points[:, 2] * (region.side / _SIZE / _Z_SPREAD)
        # The model's 'Left' is a left hand as a mirror shows it (module docstring).
        looks_left = float(left.reshape(-1)[0]) > 0.5
        return Hand(landmarks, 'left' if looks_left == self.mirrored else 'right', score)
