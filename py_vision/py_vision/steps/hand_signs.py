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
The `hand_signs` step: a hand sign drives turtlesim's turtle (or a robot).

Read as four steps: detect a hand and its 21 landmarks (MediaPipe's palm detector and hand
landmark model, py_vision.models.hands), classify the landmarks into one of a handful of signs
(py_vision.models.signs: not a sign language, a few gestures), act (the sign's motion as a
geometry_msgs/Twist, or TwistStamped with the frame's header, and the sign as std_msgs/String
on `hand_sign`), and draw the landmarks and the sign on the image (while it is published or
shown: StepContext.output_wanted). The commands go through a CommandGate (steps/commands.py),
which makes them fail safe: a sign moves the robot once held
`hold_frames` frames, a change of sign stops it first; no hand (or one scoring below
`min_score`) and `open_hand` stop it at once; a frame older than `max_frame_age` stops it;
and one zero command goes out when no frame was processed for `command_timeout` seconds (a
timer), when the step fails on a frame (`frame_failed`) and when the node stops (`close`).
"""

from typing import Any, Callable, Dict, List, Optional, Tuple

import cv2
from geometry_msgs.msg import Twist, TwistStamped
import numpy as np
from py_vision.models.hands import Hand, HandTracker, LANDMARK_FILE
from py_vision.models.palm import MODEL_FILE as PALM_FILE
from py_vision.models.signs import classify
from py_vision.params import Spec
from py_vision.steps.api import Step, StepContext
from py_vision.steps.commands import CommandGate, FAILED, FRAME, HELD_BACK, STALE, STOPPED
from py_vision.steps.commands import TIMEOUT
from py_vision.throttled_log import ThrottledLog
from std_msgs.msg import Header, String

NO_HAND = 'no_hand'
MAX_LINEAR, MAX_ANGULAR = 2.0, 3.0  # turtlesim units: m/s and rad/s
# MediaPipe's own palm detection threshold: min_score below it lowers the palm detector's too
# (a hand the user lets through must not be hidden by a stricter palm stage), never above it.
PALM_SCORE = 0.5
# The watchdog's timer looks this many times per command_timeout.
CHECKS_PER_TIMEOUT = 5
# What the log says when the gate stops the robot of its own accord, at most once per period.
STOP_LOG_PERIOD_S = 5.0
STOP_REASONS = {
    STALE: 'a frame older than max_frame_age (measured from its arrival here)',
    TIMEOUT: 'no frame processed for command_timeout',
    FAILED: 'the step failed on a frame',
}

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
        # Rounded half to even, as round() does.
        pixels = np.rint(np.asarray(hand.landmarks)[:, :2]).astype(int)
        points = [tuple(point) for point in pixels.tolist()]
        for a, b in BONES:
            cv2.line(image, points[a], points[b], BONE_BGR, 2, cv2.LINE_AA)
        for point in points:
            cv2.circle(image, point, 3, JOINT_BGR, -1, cv2.LINE_AA)
        sign = '%s (%s hand, %.2f)' % (sign, hand.handedness, hand.score)
    cv2.putText(image, sign, (10, 30), cv2.FONT_HERSHEY_SIMPLEX, 0.8, (0, 0, 0), 4,
                cv2.LINE_AA)
    cv2.putText(image, sign, (10, 30), cv2.FONT_HERSHEY_SIMPLEX, 0.8, TEXT_BGR, 2,
                cv2.LINE_AA)


def tracker_thresholds(min_score: float) -> Dict[str, float]:
    """Return the HandTracker thresholds that make min_score mean what it says."""
    return {'min_hand_score': min_score, 'min_palm_score': min(min_score, PALM_SCORE)}


class HandSigns(Step):
    """Hand, landmarks, sign, Twist: the tutorial's next step, made safe to drive a robot."""

    PARAMETERS = (
        Spec('min_score', 0.5, 'a hand scoring less than this counts as no hand (zero Twist); '
             'below 0.5 the palm detector looks with it too', (0.0, 1.0), live=True),
        Spec('linear_speed', 1.0, 'forward / backward speed of thumb_up / fist (turtlesim '
             'units a second)', (0.0, MAX_LINEAR), live=True),
        Spec('angular_speed', 1.0, 'turning speed of point_left / point_right (rad/s)',
             (0.0, MAX_ANGULAR), live=True),
        Spec('cmd_vel_topic', '/turtle1/cmd_vel', 'where the Twist goes (turtlesim listens '
             'on /turtle1/cmd_vel)', check=bool, accepted='a topic name'),
        Spec('cmd_vel_stamped', False, 'publish geometry_msgs/TwistStamped (with the '
             "frame's header) instead of Twist"),
        Spec('hold_frames', 3, 'processed frames a sign must hold before it moves the robot '
             '(a change of sign stops it first)', (1, 100), live=True),
        Spec('command_timeout', 0.5, 'seconds without a processed frame after which one zero '
             'command goes out', (0.05, 60.0)),
        Spec('max_frame_age', 0.5, 'seconds since a frame arrived on this host after which it '
             'stops the robot instead of steering it', (0.01, 60.0), live=True),
    )

    def __init__(self):
        self.tracker: Optional[HandTracker] = None
        self.settings: Dict[str, Any] = {}
        self.signs = self.twists = None
        self.gate: Optional[CommandGate] = None
        self._frame_age: Callable[[], Optional[float]] = lambda: None
        self._output_wanted: Callable[[], bool] = lambda: True
        self._now: Callable[[], Any] = lambda: None
        self._stops: Optional[ThrottledLog] = None  # the gate's own zeros, logged

    def start(self, context: StepContext) -> Optional[str]:
        """Load the two models; create the hand_sign and Twist publishers and the watchdog."""
        self.settings = dict(context.parameters)
        # One hand drives the turtle: once it is tracked, the palm detector rests (a tracked
        # hand costs the landmark model alone, bench/bench_models.py).
        self.tracker = HandTracker.from_files(context.model_path(PALM_FILE),
                                              context.model_path(LANDMARK_FILE), context.threads,
                                              max_hands=1,
                                              **tracker_thresholds(self.settings['min_score']))
        self.signs = context.create_publisher(String, 'hand_sign')
        stamped = self.settings['cmd_vel_stamped']
        self.twists = context.create_publisher(TwistStamped if stamped else Twist,
                                               self.settings['cmd_vel_topic'])
        self._frame_age = context.frame_age
        self._output_wanted = context.output_wanted
        self._now = context.node.get_clock().now
        self._stops = ThrottledLog(context.logger, STOP_LOG_PERIOD_S) if context.logger else None
        timeout = self.settings['command_timeout']
        self.gate = CommandGate(self._send, Twist(), self.settings['hold_frames'], timeout,
                                self.settings['max_frame_age'])
        context.create_timer(timeout / CHECKS_PER_TIMEOUT, self.gate.check)
        return '%s; %s and %s; signs on %s, %s on %s' % (
            self.tracker.landmark_model.runtime, PALM_FILE, LANDMARK_FILE,
            self.signs.topic_name, 'TwistStamped' if stamped else 'Twist',
            self.twists.topic_name)

    def parameters_changed(self, changes: Dict[str, Any]) -> Optional[str]:
        """Take a new min_score, speed, hold_frames or max_frame_age (the next frame uses it)."""
        self.settings = dict(self.settings, **changes)
        if 'min_score' in changes and self.tracker is not None:
            for name, value in tracker_thresholds(changes['min_score']).items():
                setattr(self.tracker, name, value)
        if self.gate is not None:
            self.gate.hold_frames = self.settings['hold_frames']
            self.gate.max_frame_age = self.settings['max_frame_age']
        return None

    def process(self, image: np.ndarray, header: Any) -> Optional[np.ndarray]:
        """Find the best hand, classify its sign, publish sign and command, draw them."""
        hands: List[Hand] = self.tracker.find(image)
        best = max(hands, key=lambda hand: hand.score, default=None)
        if best is not None and best.score < self.settings['min_score']:
            best = None
        sign = NO_HAND if best is None else classify(best.landmarks, best.handedness)
        self.signs.publish(String(data=sign))
        self.gate.frame(sign, motion(sign, self.settings['linear_speed'],
                                     self.settings['angular_speed']),
                        header, self._frame_age())
        if self._output_wanted():  # nobody watching: no drawing
            draw(image, best, sign)
        return image

    def frame_failed(self, header: Any, error: Exception) -> None:
        """Stop the robot: the step failed on a frame (one zero command)."""
        if self.gate is not None:
            self.gate.frame_failed()

    def close(self) -> None:
        """Stop the robot: the last command is a zero one, and nothing follows it."""
        if self.gate is not None:
            self.gate.stop()

    def _send(self, twist: Twist, header: Any, why: str) -> Optional[bool]:
        """Publish one command (the gate's send, under its lock); False: it was dropped."""
        if why not in (FRAME, HELD_BACK, STOPPED) and self._stops is not None:
            self._stops.warning(why, '%s: one zero command on %s; the next frames must hold a '
                                'sign again' % (STOP_REASONS[why], self.twists.topic_name))
        if self.settings['cmd_vel_stamped']:
            if why not in (FRAME, HELD_BACK):
                # The gate's own zero: stamped now, with the last frame's frame_id.
                header = Header(stamp=self._now().to_msg(),
                                frame_id=header.frame_id if header is not None else '')
            return self.twists.publish(TwistStamped(header=header, twist=twist))
        return self.twists.publish(twist)
