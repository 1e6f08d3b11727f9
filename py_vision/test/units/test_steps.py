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

"""The step loader's names and errors, and hand_signs' table of motions, without ROS graphs."""

from py_vision.params import Spec
from py_vision.steps import loader
from py_vision.steps.circle import Circle
from py_vision.steps.hand_signs import MAX_ANGULAR, MAX_LINEAR, motion
from py_vision.vision_step import VisionStep
import pytest


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
