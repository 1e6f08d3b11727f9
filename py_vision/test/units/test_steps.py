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

"""The step loader's names and errors, and hand_signs' signs and Twists, without ROS graphs."""

from hand_poses import thumb_up
import numpy as np
from py_vision.models.hands import Hand
from py_vision.params import Spec
from py_vision.steps import loader
from py_vision.steps.api import StepContext
from py_vision.steps.circle import Circle
from py_vision.steps.hand_signs import HandSigns, MAX_ANGULAR, MAX_LINEAR, motion
from py_vision.vision_step import VisionStep
import pytest
from std_msgs.msg import Header


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
    twist = motion(sign, 1.5, 0.5)
    assert (twist.linear.x, twist.angular.z) == expected
    assert (twist.linear.y, twist.linear.z, twist.angular.x, twist.angular.y) == (0, 0, 0, 0)


def test_speeds_are_clamped():
    assert motion('thumb_up', 100.0, 100.0).linear.x == MAX_LINEAR
    assert motion('point_right', 100.0, 100.0).angular.z == -MAX_ANGULAR


class FakePublisher:
    """A publisher that keeps what is published."""

    def __init__(self, msg_type, topic):
        self.msg_type, self.topic_name, self.sent = msg_type, topic, []

    def publish(self, msg):
        assert isinstance(msg, self.msg_type)
        self.sent.append(msg)


class FakeNode:
    """The node a step creates its publishers through."""

    def __init__(self):
        self.publishers = {}

    def create_publisher(self, msg_type, topic, depth):
        self.publishers[topic] = FakePublisher(msg_type, topic)
        return self.publishers[topic]


class FakeTracker:
    """HandTracker's find(), answering the hands it is given."""

    hands = []

    def find(self, image):
        return list(self.hands)


def test_hand_signs_publishes_the_sign_and_its_twist_and_zero_below_min_score():
    node = FakeNode()
    step = HandSigns()
    values = {spec.name: spec.default for spec in HandSigns.PARAMETERS}
    note = step.start(StepContext(node=node, logger=None, parameters=dict(
        values, linear_speed=1.5)))
    assert 'palm_detection_lite.tflite and hand_landmark_lite.tflite' in note, note
    assert 'Twist on /turtle1/cmd_vel' in note
    signs, twists = node.publishers['hand_sign'], node.publishers['/turtle1/cmd_vel']
    step.tracker = FakeTracker()
    image = np.zeros((480, 640, 3), np.uint8)
    header = Header(frame_id='camera')

    def run(hands):
        step.tracker.hands = hands
        out = step.process(image.copy(), header)
        twist = twists.sent[-1]
        return signs.sent[-1].data, (twist.linear.x, twist.angular.z), out
    # A thumbs-up: forward at linear_speed, the landmarks and the sign drawn.
    sign, speeds, out = run([Hand(thumb_up(), 'right', 0.9)])
    assert (sign, speeds) == ('thumb_up', (1.5, 0.0))
    assert (out != 0).any(axis=2).sum() > 500
    # The same hand scoring below min_score, or no hand: no_hand and a zero Twist.
    assert run([Hand(thumb_up(), 'right', 0.3)])[:2] == ('no_hand', (0.0, 0.0))
    assert run([])[:2] == ('no_hand', (0.0, 0.0))
    # A lower min_score, set live, lets it through; stopping sends a last zero Twist.
    assert step.parameters_changed({'min_score': 0.2}) is None
    assert run([Hand(thumb_up(), 'right', 0.3)])[:2] == ('thumb_up', (1.5, 0.0))
    step.close()
    assert (twists.sent[-1].linear.x, twists.sent[-1].angular.z) == (0.0, 0.0)
    assert len(signs.sent) == 4 and len(twists.sent) == 5
