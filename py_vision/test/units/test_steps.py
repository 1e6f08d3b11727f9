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
The step loader, and the built-in model steps without a ROS graph.

hand_signs with a stand-in tracker (landmarks written by hand, hand_poses): each sign's Twist,
the hold before a sign moves the robot, min_drive_score, the speed caps, the zero commands of
the watchdog (a fake clock), of a failure, of a stale frame, of the enable input and of the
stop, TwistStamped stamped when sent; with its real models on photographs,
min_score below 0.5 letting through a palm (or a hand) scoring between it and 0.5. faces with a
model double whose scores are lowered: min_score below 0.5 letting through a face scoring less.
"""

import json
import threading

from builtin_interfaces.msg import Time
from fake_clock import FakeClock
from geometry_msgs.msg import Twist, TwistStamped
from hand_poses import FOLDED, place, pose, THUMB_ACROSS, thumb_up
import numpy as np
from photos import hand_photo, photo
from py_vision.models.hands import Hand
from py_vision.params import ConfigError, Spec
from py_vision.steps import loader
from py_vision.steps.api import StepContext
from py_vision.steps.circle import Circle
from py_vision.steps.faces import Faces
from py_vision.steps.hand_signs import DRIVE_SCORE_FLOOR, HandSigns, motion, twist_of
from py_vision.vision_step import StepPublishers, VisionStep
import pytest
from std_msgs.msg import Bool, Header, String


def test_built_in_steps_are_found_by_their_short_names():
    assert loader.find('circle') == ('py_vision.steps.circle:Circle', Circle)
    for name in ('hand_signs', 'faces'):
        target, step_class = loader.find(name)
        assert target == loader.BUILT_IN[name] and callable(step_class.process)
    # The same class by its full name.
    assert loader.find('py_vision.steps.circle:Circle')[1] is Circle


@pytest.mark.parametrize('name, words', [
    ('', "step '': not a built-in step"),
    ('circle:', 'nor module.path:Class'),
    ('py_vision.steps.circle:Square', 'module py_vision.steps.circle has no Square'),
    ('py_vision.steps.circle:CIRCLE_BGR', 'is not a step'),
    ('py_vision.no_such_thing:Step', 'no module py_vision.no_such_thing on PYTHONPATH'),
])
def test_a_name_that_is_no_step_is_one_line_naming_it(name, words):
    with pytest.raises(loader.StepError) as raised:
        loader.find(name)
    assert words in str(raised.value) and '\n' not in str(raised.value)


def test_a_step_parameter_may_not_take_the_name_of_the_nodes_own():
    mine = (Spec('display', 'x', 'a step that wants a display of its own'),)
    with pytest.raises(loader.StepError, match="parameter\\(s\\) display clash with the node's"):
        loader.check_parameters('mine', mine, VisionStep.NODE_PARAMETERS)
    loader.check_parameters('circle', Circle.PARAMETERS, VisionStep.NODE_PARAMETERS)


@pytest.mark.parametrize('sign, expected', [
    ('thumb_up', (1.5, 0.0)), ('fist', (-1.5, 0.0)), ('point_left', (0.0, 0.5)),
    ('point_right', (0.0, -0.5)), ('open_hand', (0.0, 0.0)), ('unknown', (0.0, 0.0)),
    ('no_hand', (0.0, 0.0)),
])
def test_each_sign_has_its_motion_and_the_rest_stand_still(sign, expected):
    twist = twist_of(motion(sign, 1.5, 0.5))
    assert (twist.linear.x, twist.angular.z) == expected
    assert (twist.linear.y, twist.linear.z, twist.angular.x, twist.angular.y) == (0, 0, 0, 0)


def test_min_drive_score_is_never_below_the_floor():
    spec = next(spec for spec in HandSigns.PARAMETERS if spec.name == 'min_drive_score')
    assert spec.coerce(DRIVE_SCORE_FLOOR) == DRIVE_SCORE_FLOOR
    with pytest.raises(ConfigError, match='min_drive_score: 0.1 is not accepted; expected '
                       '0.2..1'):
        spec.coerce(0.1)


class FakePublisher:
    """A publisher that keeps what is published."""

    def __init__(self, msg_type, topic):
        self.msg_type, self.topic_name, self.sent = msg_type, topic, []

    def publish(self, msg):
        assert isinstance(msg, self.msg_type)
        self.sent.append(msg)


class FakeNode:
    """The node a step creates its publishers and timers through; its clock says NOW."""

    NOW = Time(sec=1700000000, nanosec=5)

    def __init__(self):
        self.publishers = {}
        self.subscriptions = {}
        self.timers = []

    def create_publisher(self, msg_type, topic, depth):
        self.publishers[topic] = FakePublisher(msg_type, topic)
        return self.publishers[topic]

    def create_subscription(self, msg_type, topic, callback, qos):
        self.subscriptions[topic] = callback

        class Subscription:
            topic_name = topic
        return Subscription()

    def create_timer(self, period, callback, clock=None):
        self.timers.append((period, callback))

    def get_clock(self):
        node = self

        class Clock:
            def now(self):
                class Now:
                    def to_msg(self):
                        return node.NOW
                return Now()
        return Clock()


class FakeTracker:
    """HandTracker's find(), answering the hands it is given."""

    hands = []

    def find(self, image):
        return list(self.hands)


THUMB_UP = Hand(thumb_up(), 'right', 0.9)
FIST = Hand(place(pose((FOLDED,) * 4, THUMB_ACROSS)), 'right', 0.9)


def defaults(step_class, **changes):
    return dict({spec.name: spec.default for spec in step_class.PARAMETERS}, **changes)


class SignsUnderTest:
    """
    A HandSigns started on a FakeNode with a stand-in tracker, and what it published.

    Its gate runs on a fake clock from the start (its watchdog thread, waiting on real time,
    finds nothing due unless the test moves the clock); one copy of each stop and no hold_time
    unless asked.
    """

    def __init__(self, frame_age=lambda: 0.01, **parameters):
        self.node = FakeNode()
        self.step = HandSigns()
        self.age = frame_age
        self.watched = True  # whether the step's output image is published or shown
        parameters = dict({'stop_repeats': 1, 'hold_time': 0.0}, **parameters)
        self.clock = self.step.clock = FakeClock()
        self.step.sleep = self.clock.sleep
        self.note = self.step.start(StepContext(
            node=self.node, logger=None, parameters=defaults(HandSigns, **parameters),
            frame_age=lambda: self.age(), output_wanted=lambda: self.watched))
        self.step.tracker = FakeTracker()
        self.signs = self.node.publishers['hand_sign']
        self.twists = self.node.publishers[self.step.settings['cmd_vel_topic']]
        self.image = np.zeros((480, 640, 3), np.uint8)

    def frame(self, hands, frame_id='camera'):
        """Process one frame showing hands; return (sign, (forward, turn) sent, image)."""
        self.step.tracker.hands = hands
        sent = len(self.twists.sent)
        out = self.step.process(self.image.copy(), Header(frame_id=frame_id))
        assert len(self.twists.sent) == sent + 1, 'one command a frame'
        return self.signs.sent[-1].data, speeds(self.twists.sent[-1]), out

    def commands(self):
        return [speeds(msg) for msg in self.twists.sent]


def speeds(msg):
    twist = msg.twist if isinstance(msg, TwistStamped) else msg
    return twist.linear.x, twist.angular.z


def test_hand_signs_publishes_the_sign_and_its_twist_and_zero_below_min_score():
    test = SignsUnderTest(linear_speed=1.5, hold_frames=1)
    assert 'palm_detection_lite.tflite and hand_landmark_lite.tflite' in test.note, test.note
    assert 'Twist on /turtle1/cmd_vel' in test.note
    # A thumbs-up: forward at linear_speed, the landmarks and the sign drawn.
    sign, moving, out = test.frame([THUMB_UP])
    assert (sign, moving) == ('thumb_up', (1.5, 0.0))
    assert (out != 0).any(axis=2).sum() > 500
    # The same hand scoring below min_score, or no hand: no_hand and a zero Twist.
    assert test.frame([Hand(thumb_up(), 'right', 0.3)])[:2] == ('no_hand', (0.0, 0.0))
    assert test.frame([])[:2] == ('no_hand', (0.0, 0.0))
    # A lower min_score, set live, lets it through (and reaches the tracker's thresholds): its
    # sign is published and drawn, but below min_drive_score it does not drive.
    tracker = test.step.tracker
    tracker.min_hand_score = tracker.min_palm_score = 0.5
    assert test.step.parameters_changed({'min_score': 0.2}) is None
    assert (tracker.min_hand_score, tracker.min_palm_score) == (0.2, 0.2)
    sign, moving, out = test.frame([Hand(thumb_up(), 'right', 0.3)])
    assert (sign, moving) == ('thumb_up', (0.0, 0.0))
    assert (out != 0).any(axis=2).sum() > 500
    assert test.step.parameters_changed({'min_drive_score': 0.25}) is None
    assert test.frame([Hand(thumb_up(), 'right', 0.3)])[:2] == ('thumb_up', (1.5, 0.0))
    # Above 0.5 the palm detector keeps MediaPipe's 0.5; the hand's score must reach it.
    test.step.parameters_changed({'min_score': 0.8})
    assert (tracker.min_hand_score, tracker.min_palm_score) == (0.8, 0.5)
    assert isinstance(test.twists.sent[0], Twist)


def test_hand_signs_draws_only_while_its_image_is_published_or_shown():
    test = SignsUnderTest(hold_frames=1)
    test.watched = False
    sign, moving, out = test.frame([THUMB_UP])
    # Nobody watching: the same sign and command, the image left as it came.
    assert (sign, moving) == ('thumb_up', (1.0, 0.0))
    assert not out.any()
    test.watched = True
    assert (test.frame([THUMB_UP])[2] != 0).any(axis=2).sum() > 500
    assert (test.frame([])[2] != 0).any(axis=2).sum() > 100  # the sign: no_hand


def test_hand_signs_moves_only_on_a_held_sign_and_a_flicker_stops_it():
    test = SignsUnderTest()  # hold_frames 3
    seen = [test.frame(hands)[:2] for hands in [[THUMB_UP]] * 4 + [[FIST]] + [[THUMB_UP]] * 3]
    assert [sign for sign, _ in seen] == ['thumb_up'] * 4 + ['fist'] + ['thumb_up'] * 3
    assert [moving for _, moving in seen] == [(0.0, 0.0)] * 2 + [(1.0, 0.0)] * 2 + [
        (0.0, 0.0)] * 3 + [(1.0, 0.0)]
    # No hand stops it at once; hold_frames is live.
    assert test.frame([])[1] == (0.0, 0.0)
    test.step.parameters_changed({'hold_frames': 1})
    assert test.frame([FIST])[1] == (-1.0, 0.0)


def test_hand_signs_watchdog_failure_stale_frame_and_stop_each_send_one_zero():
    age = [0.01]
    test = SignsUnderTest(frame_age=lambda: age[0], hold_frames=1, command_timeout=0.5,
                          max_frame_age=0.3)
    clock = test.clock
    assert test.node.timers == []  # the watchdog is a thread of the gate's, not a timer
    assert test.frame([THUMB_UP])[1] == (1.0, 0.0)
    clock.t += 0.3
    test.step.gate.check()
    assert test.commands() == [(1.0, 0.0)]
    clock.t += 0.3  # no frame for 0.6 s: one zero, then nothing
    test.step.gate.check()
    test.step.gate.check()
    assert test.commands() == [(1.0, 0.0), (0.0, 0.0)]
    # The step failing on a frame (the node calls frame_failed): one zero.
    test.frame([THUMB_UP])
    test.step.frame_failed(Header(), RuntimeError('the model failed'))
    test.step.frame_failed(Header(), RuntimeError('the model failed'))
    assert test.commands()[2:] == [(1.0, 0.0), (0.0, 0.0)]
    # A frame that waited 0.4 s before its command: a zero, not its fist; the sign still out.
    test.frame([THUMB_UP])
    age[0] = 0.4
    test.step.tracker.hands = [FIST]
    test.step.process(test.image.copy(), Header(frame_id='camera'))
    assert test.signs.sent[-1].data == 'fist'
    assert test.commands()[4:] == [(1.0, 0.0), (0.0, 0.0)]
    # The stop (at once, the frame under way not awaited): a last zero, and a frame still being
    # processed sends nothing after it; the watchdog's thread has ended.
    age[0] = 0.01
    test.frame([THUMB_UP])
    test.step.stopping()
    assert not test.step.watchdog._thread.is_alive()
    test.step.tracker.hands = [THUMB_UP]
    test.step.process(test.image.copy(), Header(frame_id='camera'))
    test.step.close()
    assert test.commands()[6:] == [(1.0, 0.0), (0.0, 0.0)]


def test_hand_signs_caps_the_speeds_for_the_base():
    test = SignsUnderTest(hold_frames=1, linear_speed=2.0, angular_speed=3.0,
                          max_linear_speed=0.3, max_angular_speed=0.8)
    assert test.frame([THUMB_UP])[1] == (0.3, 0.0)
    test.step.parameters_changed({'linear_speed': 1.5})  # live, still capped
    assert test.frame([THUMB_UP])[1] == (0.3, 0.0)


def test_hand_signs_with_an_enable_topic_moves_only_while_it_says_true():
    test = SignsUnderTest(hold_frames=1, enable_topic='/hand_signs/enable',
                          enable_timeout=0.5)
    assert 'moving only while /hand_signs/enable says true (within 0.5 s)' in test.note
    enable = test.node.subscriptions['/hand_signs/enable']
    sent = len(test.twists.sent)
    test.step.tracker.hands = [THUMB_UP]
    test.step.process(test.image.copy(), Header())
    assert len(test.twists.sent) == sent  # not enabled: nothing sent
    enable(Bool(data=True))
    assert test.frame([THUMB_UP])[1] == (1.0, 0.0)
    enable(Bool(data=False))
    assert test.commands()[-1] == (0.0, 0.0)


def test_hand_signs_stamped_commands_are_stamped_when_sent_with_frame_id():
    test = SignsUnderTest(cmd_vel_stamped=True, hold_frames=1)
    assert 'TwistStamped on /turtle1/cmd_vel' in test.note, test.note
    header = Header(frame_id='front_camera', stamp=Time(sec=12, nanosec=34))
    test.step.tracker.hands = [THUMB_UP]
    test.step.process(test.image.copy(), header)
    test.step.close()
    moving, zero = test.twists.sent
    assert isinstance(moving, TwistStamped) and speeds(moving) == (1.0, 0.0)
    assert moving.header == Header(frame_id='base_link', stamp=FakeNode.NOW)
    assert speeds(zero) == (0.0, 0.0)
    assert zero.header == Header(frame_id='base_link', stamp=FakeNode.NOW)
    test = SignsUnderTest(cmd_vel_stamped=True, hold_frames=1, frame_id='odom')
    test.frame([THUMB_UP])
    assert test.twists.sent[-1].header.frame_id == 'odom'


# min_score below 0.5 with the real models, on photographs whose scores are known (LiteRT and
# tflite_runtime agree on them to far better than the margins): the hand photograph at a
# quarter of its brightness has its best palm at 0.41 (its hand, once found, at 0.98); the
# horse's leg the palm detector takes for a palm (0.63) is a hand at 0.004 (test_hands).
DARK_HAND_BRIGHTNESS = 0.25


def real_hand_signs(min_score):
    node = FakeNode()
    step = HandSigns()
    step.start(StepContext(node=node, logger=None, parameters=defaults(
        HandSigns, min_score=min_score)))
    return step, node.publishers['hand_sign']


def sign_of(step, signs, image):
    step.tracker.forget()
    step.process(image.copy(), Header())
    return signs.sent[-1].data


def test_hand_signs_min_score_below_half_finds_a_palm_and_a_hand_scoring_less_than_half():
    dark = (hand_photo().astype(np.float32) * DARK_HAND_BRIGHTNESS).astype(np.uint8)
    horse = photo('horse.png')
    step, signs = real_hand_signs(0.5)
    assert sign_of(step, signs, dark) == 'no_hand'
    assert sign_of(step, signs, horse) == 'no_hand'
    step.parameters_changed({'min_score': 0.3})
    assert sign_of(step, signs, dark) == 'open_hand'
    assert sign_of(step, signs, horse) == 'no_hand'
    step.parameters_changed({'min_score': 0.001})
    assert sign_of(step, signs, horse) != 'no_hand'
    # Started with it, too.
    step, signs = real_hand_signs(0.3)
    assert sign_of(step, signs, dark) == 'open_hand'


class LoweredScores:
    """A face model whose raw scores (the (1, N, 1) output) are `by` logits lower."""

    def __init__(self, model, by):
        self.model, self.by = model, by

    def __getattr__(self, name):
        return getattr(self.model, name)

    def run(self, *arrays):
        return [out - self.by if out.shape[-1] == 1 else out for out in self.model.run(*arrays)]


def face_scores(msg):
    if isinstance(msg, String):
        return [item['score'] for item in json.loads(msg.data)['detections']]
    return [detection.results[0].hypothesis.score for detection in msg.detections]


def test_faces_min_score_below_half_finds_a_face_scoring_less_than_half():
    node = FakeNode()
    step = Faces()
    step.start(StepContext(node=node, logger=None, parameters=defaults(Faces, min_score=0.1)))
    [publisher] = node.publishers.values()
    # The astronaut's face scores 0.92 (logit 2.4); 3.5 logits lower it scores about 0.25.
    step.detector.model = LoweredScores(step.detector.model, 3.5)
    astronaut = photo('astronaut.png')
    step.process(astronaut.copy(), Header())
    [score] = face_scores(publisher.sent[-1])
    assert 0.1 <= score < 0.5
    step.parameters_changed({'min_score': 0.5})
    step.process(astronaut.copy(), Header())
    assert face_scores(publisher.sent[-1]) == []


class AckedPublisher(FakePublisher):
    """A FakePublisher that says how long it was given to be acknowledged."""

    def __init__(self, msg_type, topic):
        super().__init__(msg_type, topic)
        self.waited = []

    def wait_for_all_acked(self, timeout):
        self.waited.append(timeout.nanoseconds / 1e9)
        return True


def test_after_the_stop_only_the_stopping_thread_publishes_through_the_steps_publishers():
    node = FakeNode()
    node.create_publisher = lambda msg_type, topic, depth: AckedPublisher(msg_type, topic)
    owner = StepPublishers()
    publisher = owner.create(node, String, 'said', 10)
    assert publisher.topic_name == 'said'  # the rest is the real publisher's

    def from_the_worker(text):
        worker = threading.Thread(target=publisher.publish, args=(String(data=text),))
        worker.start()
        worker.join(10)
    from_the_worker('before the stop')
    owner.stop()
    from_the_worker('from an abandoned process()')  # dropped
    publisher.publish(String(data="the step's last word"))  # the stopping thread: sent
    assert [m.data for m in owner.publishers[0].sent] == [
        'before the stop', "the step's last word"]
    assert owner.dropped == 1
    assert owner.deliver(1.0) and 0 < owner.publishers[0].waited[0] <= 1.0
