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
The `hand_signs` step: a hand sign drives turtlesim's turtle.

Read as four steps: detect a hand and its 21 landmarks (MediaPipe's palm detector and hand
landmark model, py_vision.models.hands), classify the landmarks into one of a handful of signs
(py_vision.models.signs: not a sign language, a few gestures), act (the sign's motion as a
geometry_msgs/Twist, the sign as std_msgs/String on `hand_sign`), and draw the landmarks and
the sign on the image. A Twist goes out for every processed frame, all zero when no hand is
seen or the best one scores below `min_score`, so the turtle stops when the hand goes away.
"""

from typing import Any, Dict, List, Optional, Tuple

import cv2
from geometry_msgs.msg import Twist
import numpy as np
from py_vision.models.hands import Hand, HandTracker, LANDMARK_FILE
from py_vision.models.palm import MODEL_FILE as PALM_FILE
from py_vision.models.signs import classify
from py_vision.params import Spec
from py_vision.steps.api import Step, StepContext
from std_msgs.msg import String

NO_HAND = 'no_hand'
MAX_LINEAR, MAX_ANGULAR = 2.0, 3.0  # turtlesim units: m/s and rad/s

# Each sign's motion: (forward, turn left) as fractions of linear_speed and angular_speed.
# Every other sign, `unknown` and no hand: stand still.
MOTIONS: Dict[str, Tuple[float, float]] = {
    'thumb_up': (1.0, 0.0),       # forward
    'fist': (-1.0, 0.0),          # backward
    'point_left': (0.0, 1.0),     # turn left (anticlockwise)
    'point_right': (0.0, -1.0),   # turn right (clockwise)
    'open_hand': (0.0, 0.0),      # stop
}

# The landmarks' bones as MediaPipe numbers them: wrist 0, thumb 1-4, index 5-8, middle 9-12,
# ring 13-16, little finger 17-20.
BONES = ((0, 1), (1, 2), (2, 3), (3, 4), (0, 5), (5, 6), (6, 7), (7, 8), (5, 9), (9, 10),
         (10, 11), (11, 12), (9, 13), (13, 14), (14, 15), (15, 16), (13, 17), (0, 17),
         (17, 18), (18, 19), (19, 20))
BONE_BGR, JOINT_BGR, TEXT_BGR = (0, 255, 0), (0, 0, 255), (255, 255, 255)


def motion(sign: str, linear_speed: float, angular_speed: float) -> Twist:
    """Return the Twist of a sign (all zero for a sign without a motion)."""
    forward, turn = MOTIONS.get(sign, (0.0, 0.0))
    twist = Twist()
    twist.linear.x = float(np.clip(forward * linear_speed, -MAX_LINEAR, MAX_LINEAR))
    twist.angular.z = float(np.clip(turn * angular_speed, -MAX_ANGULAR, MAX_ANGULAR))
    return twist


def draw(image: np.ndarray, hand: Optional[Hand], sign: str) -> None:
    """Draw the hand's bones and joints and the sign on image, in place."""
    if hand is not None:
        points = [tuple(int(round(v)) for v in point[:2]) for point in hand.landmarks]
        for a, b in BONES:
            cv2.line(image, points[a], points[b], BONE_BGR, 2, cv2.LINE_AA)
        for point in points:
            cv2.circle(image, point, 3, JOINT_BGR, -1, cv2.LINE_AA)
        sign = '%s (%s hand, %.2f)' % (sign, hand.handedness, hand.score)
    cv2.putText(image, sign, (10, 30), cv2.FONT_HERSHEY_SIMPLEX, 0.8, (0, 0, 0), 4,
                cv2.LINE_AA)
    cv2.putText(image, sign, (10, 30), cv2.FONT_HERSHEY_SIMPLEX, 0.8, TEXT_BGR, 2,
                cv2.LINE_AA)


class HandSigns(Step):
    """Hand, landmarks, sign, Twist: the tutorial's next step."""

    PARAMETERS = (
        Spec('min_score', 0.5, 'a hand scoring less than this counts as no hand (zero Twist)',
             (0.0, 1.0), live=True),
        Spec('linear_speed', 1.0, 'forward / backward speed of thumb_up / fist (turtlesim '
             'units a second)', (0.0, MAX_LINEAR), live=True),
        Spec('angular_speed', 1.0, 'turning speed of point_left / point_right (rad/s)',
             (0.0, MAX_ANGULAR), live=True),
        Spec('cmd_vel_topic', '/turtle1/cmd_vel', 'where the Twist goes (turtlesim listens '
             'on /turtle1/cmd_vel)', check=bool, accepted='a topic name'),
    )

    def __init__(self):
        self.tracker: Optional[HandTracker] = None
        self.settings: Dict[str, Any] = {}
        self.signs = self.twists = None

    def start(self, context: StepContext) -> Optional[str]:
        """Load the two models; create the hand_sign and Twist publishers."""
        self.settings = dict(context.parameters)
        # One hand drives the turtle: once it is tracked, the palm detector rests (a tracked
        # hand costs the landmark model alone, bench/bench_models.py).
        self.tracker = HandTracker.from_files(context.model_path(PALM_FILE),
                                              context.model_path(LANDMARK_FILE), context.threads,
                                              max_hands=1)
        self.signs = context.create_publisher(String, 'hand_sign')
        self.twists = context.create_publisher(Twist, self.settings['cmd_vel_topic'])
        return '%s; %s and %s; signs on %s, Twist on %s' % (
            self.tracker.landmark_model.runtime, PALM_FILE, LANDMARK_FILE,
            self.signs.topic_name, self.twists.topic_name)

    def parameters_changed(self, changes: Dict[str, Any]) -> Optional[str]:
        """Take a new min_score or speed (the next frame uses it)."""
        self.settings = dict(self.settings, **changes)
        return None

    def process(self, image: np.ndarray, header: Any) -> Optional[np.ndarray]:
        """Find the best hand, classify its sign, publish sign and Twist, draw them."""
        hands: List[Hand] = self.tracker.find(image)
        best = max(hands, key=lambda hand: hand.score, default=None)
        if best is not None and best.score < self.settings['min_score']:
            best = None
        sign = NO_HAND if best is None else classify(best.landmarks, best.handedness)
        self.signs.publish(String(data=sign))
        self.twists.publish(motion(sign, self.settings['linear_speed'],
                                   self.settings['angular_speed']))
        draw(image, best, sign)
        return image

    def close(self) -> None:
        """Stop the turtle: the last Twist is a zero one."""
        if self.twists is not None:
            self.twists.publish(Twist())
