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
hand_signs' commands fail safe, in the installed vision_step, seen by a subscriber of the test.

The step is hand_signs itself with its tracker replaced (a step double, SCRIPTED_STEP, written
to a temporary folder on PYTHONPATH): what a frame shows is written in its first pixel, blue the
hand (landmark sets from hand_poses: a thumbs-up, a fist), green what the tracker does with it
(raise, block until the step is closed, take a second). The frames come from the test's own
publisher, the commands go to the test's own subscriber on /turtle1/cmd_vel. Timing is never
asserted: the order and content of the commands are.
"""

import os
from pathlib import Path
import signal
import time

from diagnostic_msgs.msg import DiagnosticArray
from geometry_msgs.msg import Twist, TwistStamped
import numpy as np
import pytest
from rclpy.qos import QoSProfile, ReliabilityPolicy
from ros_harness import status_values, wait_until
from sensor_msgs.msg import Image

RELIABLE = QoSProfile(depth=1000, reliability=ReliabilityPolicy.RELIABLE)
CMD_VEL = '/turtle1/cmd_vel'
PROCESSING = 'vision_step: processing'  # the node's status in /diagnostics
STEP = 'scripted_signs:ScriptedSigns'
TESTS = Path(__file__).resolve().parents[1]

# The hands a frame can show (its first pixel's blue) and what the tracker does (green).
NONE, THUMB_UP, FIST = 0, 1, 2
PLAIN, RAISE, BLOCK, SLOW, UNTIL_STOP = 0, 1, 2, 3, 4

SCRIPTED_STEP = '''
import threading
import time

from hand_poses import FOLDED, place, pose, THUMB_ACROSS, thumb_up
from py_vision.models.hands import Hand
from py_vision.steps.hand_signs import HandSigns

HANDS = {1: thumb_up(), 2: place(pose((FOLDED,) * 4, THUMB_ACROSS))}


class Scripted:
    """A tracker reading the frame's first pixel: blue the hand, green what to do."""

    def __init__(self, closing, cancelled):
        self.closing = closing
        self.cancelled = cancelled

    def find(self, image):
        hand, action = int(image[0, 0, 0]), int(image[0, 0, 1])
        if action == 1:
            raise RuntimeError('the model failed on this frame')
        if action == 2:
            print('blocking in process()', flush=True)
            self.closing.wait(20)
        if action == 3:
            time.sleep(1.0)
        if action == 4:
            print('processing until the stop begins', flush=True)
            began = time.monotonic()
            while not self.cancelled() and time.monotonic() - began < 20:
                time.sleep(0.01)
            time.sleep(max(0.0, 0.5 - (time.monotonic() - began)))
        return [Hand(HANDS[hand], 'right', 0.9)] if hand in HANDS else []


class ScriptedSigns(HandSigns):
    def start(self, context):
        note = super().start(context)
        self.closing = threading.Event()
        self.tracker = Scripted(self.closing, context.cancelled)
        return note

    def close(self):
        super().close()
        # The frame being processed ends just after the step's last word: the worst moment.
        self.closing.set()
'''


@pytest.fixture
def scripted_env(ros_env, tmp_path):
    """Return the node environment with the step double (and hand_poses) on PYTHONPATH."""
    (tmp_path / 'scripted_signs.py').write_text(SCRIPTED_STEP)
    path = os.pathsep.join(p for p in (str(tmp_path), str(TESTS), ros_env.get('PYTHONPATH', ''))
                           if p)
    return dict(ros_env, PYTHONPATH=path)


def moving(msg):
    twist = msg.twist if isinstance(msg, TwistStamped) else msg
    return (twist.linear.x, twist.angular.z) != (0.0, 0.0)


def after_last_moving(commands):
    """Return the commands after the last moving one (all of them if none moved)."""
    found = list(commands)
    last = max((i for i, msg in enumerate(found) if moving(msg)), default=-1)
    return found[last + 1:]


def nothing_for(seconds, predicate):
    """
    Return True when predicate stays false for `seconds`.

    An observation window (that something does not happen), not a synchronisation.
    """
    deadline = time.monotonic() + seconds
    while time.monotonic() < deadline:
        if predicate():
            return False
        time.sleep(0.05)
    return not predicate()


class Camera:
    """The test's camera: frames on usb_camera/image, a hand and an action in the first pixel."""

    def __init__(self, peer, frame_id='camera'):
        self.publisher = peer.node.create_publisher(Image, 'usb_camera/image', RELIABLE)
        self.frame_id = frame_id
        self.sent = 0

    def send(self, hand, action=PLAIN):
        image = np.zeros((48, 64, 3), np.uint8)
        image[0, 0] = (hand, action, 0)
        self.sent += 1
        msg = Image(height=48, width=64, encoding='bgr8', step=64 * 3, data=image.tobytes())
        msg.header.stamp.sec = self.sent  # 1970: the node goes by when frames arrive
        msg.header.frame_id = self.frame_id
        self.publisher.publish(msg)

    def send_until(self, condition, hand, action=PLAIN, timeout=60.0, what='the commands'):
        """Send frames 20 a second until condition() holds."""
        def sent():
            if condition():
                return True
            self.send(hand, action)
            return False
        wait_until(sent, timeout, interval=0.05, what=what)


def start(launch, env, **params):
    node = launch('vision_step', params=dict({'step': STEP}, **params), env=env)
    node.wait_for_output(r'running step %s' % STEP, timeout=90.0)
    return node


def test_the_camera_stopping_while_the_robot_moves_sends_one_zero_then_nothing(
        launch, peer, scripted_env):
    twists = peer.collect(Twist, CMD_VEL, RELIABLE)
    node = start(launch, scripted_env, command_timeout=0.5)
    camera = Camera(peer)
    camera.send_until(lambda: any(moving(m) for m in list(twists)), THUMB_UP,
                      what='a moving command')
    # The camera stops: one zero (within command_timeout and a check of the watchdog).
    wait_until(lambda: after_last_moving(twists), 20.0, what='a zero command')
    assert nothing_for(1.5, lambda: len(after_last_moving(twists)) > 1)
    stopped = after_last_moving(twists)
    assert len(stopped) == 1 and not moving(stopped[0]), stopped
    # The frames return, the same sign shown: it holds again (two zeros) before it moves.
    count = len(twists)
    camera.send_until(lambda: any(moving(m) for m in list(twists)[count:]), THUMB_UP,
                      what='moving again')
    resumed = list(twists)[count:]
    first_moving = next(i for i, msg in enumerate(resumed) if moving(msg))
    assert first_moving >= 2, resumed
    assert 'no frame processed for command_timeout: one zero command' in node.output()
    assert node.stop(signal.SIGINT) == 0
    assert 'Traceback' not in node.output()


def test_the_step_failing_after_a_moving_command_sends_one_zero(launch, peer, scripted_env):
    twists = peer.collect(Twist, CMD_VEL, RELIABLE)
    arrays = peer.collect(DiagnosticArray, '/diagnostics', RELIABLE)
    # A watchdog too slow to be what stops it here.
    node = start(launch, scripted_env, command_timeout=60.0, max_frame_age=60.0)
    camera = Camera(peer)
    camera.send_until(lambda: any(moving(m) for m in list(twists)), THUMB_UP,
                      what='a moving command')
    # The step fails on every frame from now on: one zero, then nothing while it fails.
    camera.send_until(lambda: after_last_moving(twists), THUMB_UP, RAISE, what='a zero')
    camera.send_until(
        lambda: int(status_values(arrays, PROCESSING).get('step failed', 0)) >= 10, THUMB_UP,
        RAISE, what='ten failed frames')
    stopped = after_last_moving(twists)
    assert len(stopped) == 1 and not moving(stopped[0]), stopped
    node.wait_for_output(r'step %s failed on a frame' % STEP)
    # Good frames again: the sign holds again before the robot moves.
    count = len(twists)
    camera.send_until(lambda: any(moving(m) for m in list(twists)[count:]), THUMB_UP,
                      what='moving again')
    resumed = list(twists)[count:]
    assert next(i for i, msg in enumerate(resumed) if moving(msg)) >= 2, resumed
    assert node.stop(signal.SIGINT) == 0
    assert 'Traceback' not in node.output()


def stop_during_a_frame(launch, peer, env, action, marker, max_frame_age):
    """
    Move the robot, send a frame doing `action`, SIGINT once it logs `marker`.

    The node ends cleanly and its last command is one zero, with nothing after it. Return the
    node's output.
    """
    twists = peer.collect(Twist, CMD_VEL, RELIABLE)
    node = start(launch, env, command_timeout=60.0, max_frame_age=max_frame_age)
    camera = Camera(peer)
    camera.send_until(lambda: any(moving(m) for m in list(twists)), THUMB_UP,
                      what='a moving command')
    camera.send(THUMB_UP, action)
    node.wait_for_output(marker)
    assert node.stop(signal.SIGINT, timeout=20.0) == 0
    wait_until(lambda: after_last_moving(twists), 10.0, what='the last zero command')
    assert nothing_for(1.0, lambda: len(after_last_moving(twists)) != 1)
    last = after_last_moving(twists)
    assert len(last) == 1 and not moving(last[0]), last
    assert 'Traceback' not in node.output()
    return node.output()


def test_sigint_during_a_long_process_ends_on_a_zero_with_nothing_after_it(
        launch, peer, scripted_env):
    # A frame whose processing lasts until the step is closed, then ends on a thumbs-up: the
    # abandoned frame's thumbs-up does not follow the last zero.
    output = stop_during_a_frame(launch, peer, scripted_env, BLOCK, 'blocking in process', 60.0)
    assert 'abandoned' in output


def test_a_stale_frame_ending_during_the_stop_still_leaves_a_last_zero(
        launch, peer, scripted_env):
    # The frame under way ends once the stop has begun (its publishers silenced), too old to
    # steer: its zero is dropped with it, so the stop itself must send the last zero.
    output = stop_during_a_frame(launch, peer, scripted_env, UNTIL_STOP,
                                 'processing until the stop begins', 0.3)
    assert 'abandoned' not in output  # it ended within the grace


def test_a_flickering_sign_stops_the_robot_and_never_reverses_it(launch, peer, scripted_env):
    # Stamped: each command names its frame (the frame's stamp), whatever else is in flight.
    twists = peer.collect(TwistStamped, CMD_VEL, RELIABLE)
    node = start(launch, scripted_env, cmd_vel_stamped=True, command_timeout=60.0,
                 max_frame_age=60.0)
    camera = Camera(peer)
    camera.send_until(lambda: twists, NONE, what='a first command')  # connected

    def command_of(frame):
        return next((m for m in list(twists) if m.header.stamp.sec == frame), None)
    commands = []
    # One frame at a time, each one's command awaited: thumbs-up, one frame of fist, thumbs-up.
    for hand in [THUMB_UP] * 4 + [FIST] + [THUMB_UP] * 4:
        camera.send(hand)
        frame = camera.sent
        commands.append(wait_until(lambda: command_of(frame), 20.0,
                                   what='the command of frame %d' % frame).twist.linear.x)
    assert commands == [0.0, 0.0, 1.0, 1.0, 0.0, 0.0, 0.0, 1.0, 1.0]
    assert node.stop(signal.SIGINT) == 0


def test_stamped_commands_carry_the_frames_header_and_the_safety_zeros_now(
        launch, peer, scripted_env):
    twists = peer.collect(TwistStamped, CMD_VEL, RELIABLE)
    # The watchdog slower than the slow frame below, so that the stale frame stops the robot.
    node = start(launch, scripted_env, cmd_vel_stamped=True, command_timeout=5.0,
                 max_frame_age=0.5)
    assert 'TwistStamped on /turtle1/cmd_vel' in node.output()
    camera = Camera(peer, frame_id='front_camera')
    camera.send_until(lambda: any(moving(m) for m in list(twists)), THUMB_UP,
                      what='a moving command')
    first = next(m for m in list(twists) if moving(m))
    assert first.header.frame_id == 'front_camera' and 1 <= first.header.stamp.sec < 1000
    # The camera stops: the watchdog's zero, stamped now, with the last frame's frame_id.
    wait_until(lambda: after_last_moving(twists), 20.0, what='a zero command')
    zero = after_last_moving(twists)[0]
    assert zero.header.frame_id == 'front_camera'
    assert abs(zero.header.stamp.sec - time.time()) < 60
    # Moving again, then a frame that takes a second in the step: too old by the time its
    # command is decided (max_frame_age 0.5, from its arrival): a zero, not its thumbs-up.
    count = len(twists)
    camera.send_until(lambda: any(moving(m) for m in list(twists)[count:]), THUMB_UP,
                      what='moving again')
    camera.send(THUMB_UP, SLOW)
    wait_until(lambda: after_last_moving(list(twists)[count:]), 20.0,
               what="the slow frame's zero")
    stale = after_last_moving(list(twists)[count:])[0]
    assert stale.header.frame_id == 'front_camera'
    assert abs(stale.header.stamp.sec - time.time()) < 60, stale
    node.wait_for_output('a frame older than max_frame_age')
    assert node.stop(signal.SIGINT) == 0
    assert 'Traceback' not in node.output()
