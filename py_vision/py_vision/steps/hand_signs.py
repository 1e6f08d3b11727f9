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
The `hand_signs` step: a hand sign drives turtlesim's turtle (or a robot base).

Read as four steps: detect a hand and its 21 landmarks (MediaPipe's palm detector and hand
landmark model, py_vision.models.hands), classify the landmarks into one of a handful of signs
(py_vision.models.signs: not a sign language, a few gestures), act (the sign's motion as a
geometry_msgs/Twist, or TwistStamped stamped when sent, and the sign as std_msgs/String on
`hand_sign`), and draw the landmarks and the sign on the image (while it is published or shown:
StepContext.output_wanted). The commands go through a CommandGate (steps/commands.py), which
makes them fail safe: a sign moves the robot once held `hold_frames` frames over `hold_time`
seconds, a change of sign stops it first; no hand, a hand scoring below `min_drive_score` and
`open_hand` stop it at once; a frame older than `max_frame_age` stops it; speeds are capped and
ramped for the base; with `enable_topic` the robot moves only while an enable input says so;
and a zero command goes out (a few copies, then quiet) when no frame was processed for
`command_timeout` seconds (the gate's own watchdog thread), when the step fails on a frame,
when the enable lapses and when the node stops.
"""

import time
from typing import Any, Callable, Dict, List, Optional, Tuple

import cv2
from geometry_msgs.msg import Twist, TwistStamped
import numpy as np
from py_vision.models.hands import Hand, HandTracker, LANDMARK_FILE
from py_vision.models.palm import MODEL_FILE as PALM_FILE
from py_vision.models.signs import classify
from py_vision.params import Spec
from py_vision.steps.api import Step, StepContext
from py_vision.steps.commands import CommandGate, DISABLED, FAILED, GateSettings, Limits
from py_vision.steps.commands import STALE, TIMEOUT, Velocity, Watchdog
from py_vision.throttled_log import ThrottledLog
from rclpy.qos import QoSProfile, ReliabilityPolicy
from std_msgs.msg import Bool, Header, String

NO_HAND = 'no_hand'
# turtlesim's units, m/s and rad/s: the ranges of the speeds and their caps.
MAX_LINEAR, MAX_ANGULAR = 2.0, 3.0
# MediaPipe's own palm detection threshold: min_score below it lowers the palm detector's too
# (a hand the user lets through must not be hidden by a stricter palm stage), never above it.
PALM_SCORE = 0.5
# The lowest score a hand may drive the robot at, whatever min_drive_score says: below it the
# palm detector finds "hands" in the background (docs/processing.md).
DRIVE_SCORE_FLOOR = 0.2
# What the log says when the gate stops the robot of its own accord, at most once per period.
STOP_LOG_PERIOD_S = 5.0
STOP_REASONS = {
    STALE: 'a frame older than max_frame_age (measured from its arrival here)',
    TIMEOUT: 'no frame processed for command_timeout',
    FAILED: 'the step failed on a frame',
    DISABLED: 'the enable input said false or lapsed (enable_timeout)',
}
# The enable input: heard from reliable and best-effort publishers, the newest message only.
ENABLE_QOS = QoSProfile(depth=1, reliability=ReliabilityPolicy.BEST_EFFORT)

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


def motion(sign: str, linear_speed: float, angular_speed: float) -> Velocity:
    """Return the velocity a sign asks for (zero for a sign without a motion)."""
    forward, turn = MOTIONS.get(sign, (0.0, 0.0))
    return Velocity(float(forward * linear_speed), float(turn * angular_speed))


def twist_of(velocity: Velocity) -> Twist:
    """Return velocity as a geometry_msgs/Twist (linear.x, angular.z)."""
    twist = Twist()
    twist.linear.x, twist.angular.z = float(velocity.linear), float(velocity.angular)
    return twist


def draw(image: np.ndarray, hand: Optional[Hand], sign: str, drives: bool = True) -> None:
    """Draw the hand, its sign and whether it drives (`drives`) on image, in place."""
    if hand is not None:
        # Rounded half to even, as round() does.
        pixels = np.rint(np.asarray(hand.landmarks)[:, :2]).astype(int)
        points = [tuple(point) for point in pixels.tolist()]
        for a, b in BONES:
            cv2.line(image, points[a], points[b], BONE_BGR, 2, cv2.LINE_AA)
        for point in points:
            cv2.circle(image, point, 3, JOINT_BGR, -1, cv2.LINE_AA)
        sign = '%s (%s hand, %.2f%s)' % (sign, hand.handedness, hand.score,
                                         '' if drives else ', not driving')
    cv2.putText(image, sign, (10, 30), cv2.FONT_HERSHEY_SIMPLEX, 0.8, (0, 0, 0), 4,
                cv2.LINE_AA)
    cv2.putText(image, sign, (10, 30), cv2.FONT_HERSHEY_SIMPLEX, 0.8, TEXT_BGR, 2,
                cv2.LINE_AA)


def tracker_thresholds(min_score: float) -> Dict[str, float]:
    """Return the HandTracker thresholds that make min_score mean what it says."""
    return {'min_hand_score': min_score, 'min_palm_score': min(min_score, PALM_SCORE)}


def gate_settings(settings: Dict[str, Any]) -> GateSettings:
    """Return the CommandGate settings hand_signs' parameters ask for."""
    return GateSettings(
        hold_frames=settings['hold_frames'], hold_time=settings['hold_time'],
        command_timeout=settings['command_timeout'], max_frame_age=settings['max_frame_age'],
        stop_repeats=settings['stop_repeats'], stop_repeat_period=settings['stop_repeat_period'],
        command_rate=settings['command_rate'],
        enable_timeout=settings['enable_timeout'] if settings['enable_topic'] else None,
        limits=Limits(settings['max_linear_speed'], settings['max_angular_speed'],
                      settings['linear_accel'], settings['angular_accel']))


# The parameters the gate takes while it runs.
LIVE_GATE = ('hold_frames', 'hold_time', 'max_frame_age')


class HandSigns(Step):
    """Hand, landmarks, sign, Twist: the tutorial's next step, made safe to drive a robot."""

    PARAMETERS = (
        Spec('min_score', 0.5, 'a hand scoring less than this counts as no hand; below 0.5 the '
             'palm detector looks with it too (a hand below min_drive_score is drawn and its '
             'sign published, but does not drive)', (0.0, 1.0), live=True),
        Spec('min_drive_score', 0.5, 'a hand moves the robot only when it scores at least this '
             "(MediaPipe's 0.5); never below %g: lower scores find hands in the background"
             % DRIVE_SCORE_FLOOR, (DRIVE_SCORE_FLOOR, 1.0), live=True),
        Spec('linear_speed', 1.0, 'forward / backward speed of thumb_up / fist (m/s; turtlesim '
             'units a second), capped by max_linear_speed', (0.0, MAX_LINEAR), live=True),
        Spec('angular_speed', 1.0, 'turning speed of point_left / point_right (rad/s), capped '
             'by max_angular_speed', (0.0, MAX_ANGULAR), live=True),
        Spec('max_linear_speed', MAX_LINEAR, "the base's speed cap (m/s): no command goes "
             'faster, whatever linear_speed is set to', (0.0, MAX_LINEAR)),
        Spec('max_angular_speed', MAX_ANGULAR, "the base's turning cap (rad/s)",
             (0.0, MAX_ANGULAR)),
        Spec('linear_accel', 0.0, 'acceleration limit (m/s^2; 0: none): a moving command grows '
             'by at most this times the time since the last command; stops are immediate',
             (0.0, 100.0)),
        Spec('angular_accel', 0.0, 'angular acceleration limit (rad/s^2; 0: none)',
             (0.0, 100.0)),
        Spec('cmd_vel_topic', '/turtle1/cmd_vel', 'where the Twist goes (turtlesim listens '
             'on /turtle1/cmd_vel)', check=bool, accepted='a topic name'),
        Spec('cmd_vel_stamped', False, 'publish geometry_msgs/TwistStamped, stamped with the '
             "node's clock when sent, instead of Twist"),
        Spec('frame_id', 'base_link', "TwistStamped's header.frame_id", check=bool,
             accepted='a frame name'),
        Spec('hold_frames', 3, 'processed frames a sign must hold before it moves the robot '
             '(a change of sign stops it first)', (1, 100), live=True),
        Spec('hold_time', 0.2, 'seconds those frames must span (their arrivals) before the sign '
             'moves the robot', (0.0, 10.0), live=True),
        Spec('command_timeout', 0.5, 'seconds without a processed frame after which a zero '
             'command goes out', (0.05, 60.0)),
        Spec('max_frame_age', 0.5, 'seconds since a frame arrived on this host after which it '
             'stops the robot instead of steering it', (0.01, 60.0), live=True),
        Spec('command_rate', 0.0, "times a second the last frame's command goes out again until "
             'the next (0: once a processed frame): for a base whose own timeout is shorter '
             'than the time between two processed frames', (0.0, 50.0)),
        Spec('stop_repeats', 3, 'copies of each stop command sent, for readers that may lose '
             'one (best effort)', (1, 10)),
        Spec('stop_repeat_period', 0.05, 'seconds between the copies of a stop command',
             (0.01, 0.1)),
        Spec('enable_topic', '', 'a std_msgs/Bool topic that must say true, more recently than '
             'enable_timeout, for the robot to move; empty: no enable input'),
        Spec('enable_timeout', 0.5, 'seconds a true on enable_topic lets the robot move',
             (0.05, 60.0)),
    )

    def __init__(self):
        self.tracker: Optional[HandTracker] = None
        self.settings: Dict[str, Any] = {}
        self.signs = self.twists = None
        self.gate: Optional[CommandGate] = None
        self.watchdog: Optional[Watchdog] = None
        self._frame_age: Callable[[], Optional[float]] = lambda: None
        self._output_wanted: Callable[[], bool] = lambda: True
        self._now: Callable[[], Any] = lambda: None
        self._stops: Optional[ThrottledLog] = None  # the gate's own zeros, logged
        # The gate's clock and sleep (monotonic; a test's fake clock, set before start()).
        self.clock: Callable[[], float] = time.monotonic
        self.sleep: Callable[[float], None] = time.sleep

    def start(self, context: StepContext) -> Optional[str]:
        """Load the two models; create the publishers, the enable input and the watchdog."""
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
        self.gate = CommandGate(self._send, gate_settings(self.settings), self.clock, self.sleep)
        enable = ''
        if self.settings['enable_topic']:
            subscription = context.create_subscription(
                Bool, self.settings['enable_topic'], self._enable, ENABLE_QOS)
            enable = '; moving only while %s says true (within %g s)' % (
                subscription.topic_name, self.settings['enable_timeout'])
        self.watchdog = Watchdog(self.gate, self._watchdog_failed)
        return '%s; %s and %s; signs on %s, %s on %s%s' % (
            self.tracker.landmark_model.runtime, PALM_FILE, LANDMARK_FILE,
            self.signs.topic_name, 'TwistStamped' if stamped else 'Twist',
            self.twists.topic_name, enable)

    def parameters_changed(self, changes: Dict[str, Any]) -> Optional[str]:
        """Take a new score, speed, hold or max_frame_age (the next frame uses it)."""
        self.settings = dict(self.settings, **changes)
        if 'min_score' in changes and self.tracker is not None:
            for name, value in tracker_thresholds(changes['min_score']).items():
                setattr(self.tracker, name, value)
        gate_changes = {name: value for name, value in changes.items() if name in LIVE_GATE}
        if self.gate is not None and gate_changes:
            self.gate.configure(**gate_changes)
        return None

    def process(self, image: np.ndarray, header: Any) -> Optional[np.ndarray]:
        """Find the best hand, classify its sign, publish sign and command, draw them."""
        hands: List[Hand] = self.tracker.find(image)
        best = max(hands, key=lambda hand: hand.score, default=None)
        if best is not None and best.score < self.settings['min_score']:
            best = None
        sign = NO_HAND if best is None else classify(best.landmarks, best.handedness)
        self.signs.publish(String(data=sign))
        drives = best is None or best.score >= self.settings['min_drive_score']
        self.gate.frame(sign if drives else NO_HAND,
                        motion(sign if drives else NO_HAND, self.settings['linear_speed'],
                               self.settings['angular_speed']),
                        self._frame_age())
        if self._output_wanted():  # nobody watching: no drawing
            draw(image, best, sign, drives)
        return image

    def frame_failed(self, header: Any, error: Exception) -> None:
        """Stop the robot: the step failed on a frame (one stop)."""
        if self.gate is not None:
            self.gate.frame_failed()

    def stopping(self) -> None:
        """Stop the robot at once: the last command is a zero one, and nothing follows it."""
        if self.gate is not None:
            self.gate.stop()
        if self.watchdog is not None:
            self.watchdog.join()

    def close(self) -> None:
        """Stop the robot, if stopping() did not already: the node is stopping."""
        self.stopping()

    def _enable(self, msg: Bool) -> None:
        self.gate.enable(bool(msg.data))

    def _watchdog_failed(self, error: Exception) -> None:
        if self._stops is not None:
            self._stops.error('watchdog', 'the command watchdog could not send: %s: %s; trying '
                              'again' % (type(error).__name__, error))

    def _send(self, velocity: Velocity, why: str) -> Optional[bool]:
        """Publish one command (the gate's send, under its lock); False: it was dropped."""
        if why in STOP_REASONS and self._stops is not None:
            self._stops.warning(why, '%s: a zero command on %s; the next frames must hold a '
                                'sign again' % (STOP_REASONS[why], self.twists.topic_name))
        twist = twist_of(velocity)
        if self.settings['cmd_vel_stamped']:
            header = Header(stamp=self._now().to_msg(), frame_id=self.settings['frame_id'])
            return self.twists.publish(TwistStamped(header=header, twist=twist))
        return self.twists.publish(twist)
