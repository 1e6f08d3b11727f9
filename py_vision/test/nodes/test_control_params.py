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

"""ControlParameters: a camera's controls declared as parameters of a node, in process."""

from dataclasses import replace

from py_vision.capture import Camera
from py_vision.capture.controls import CID, ControlInfo, INT
from py_vision.control_params import ControlParameters
from py_vision.params import Parameters
import rclpy
from rclpy.parameter import Parameter


class Log:
    """A logger that keeps its lines."""

    def __init__(self):
        self.lines = []

    def info(self, line):
        self.lines.append(line)

    warning = info


def test_a_camera_lost_while_its_controls_are_declared_still_gets_them(peer):
    # The controls are read twice while they are declared (before and after the values the
    # user gave are applied); a camera unplugged in between answers nothing the second time.
    camera = Camera.open('synthetic', 160, 120, 10.0)
    node = rclpy.create_node('camera_controls', context=peer.context)
    try:
        found = camera.controls()
        reads = iter([found, []])
        controls = ControlParameters(Parameters(node), lambda name, value: None,
                                     lambda: next(reads, []), Log(), 'synthetic')
        controls.declare(set())
        assert 'brightness' in controls.names
        brightness = next(c for c in found if c.name == 'brightness')
        assert node.get_parameter('brightness').value == brightness.value
    finally:
        node.destroy_node()
        camera.release()


def _brightness(**changes):
    control = ControlInfo(CID.BRIGHTNESS, 'Brightness', INT, 0, 255, 1, 128, 128)
    return replace(control, **changes)


def _sync_with(node, first, later):
    """Declare the controls as first reported, then sync to what the device reports later."""
    reads = iter([[first], [first]])
    controls = ControlParameters(Parameters(node), lambda name, value: None,
                                 lambda: next(reads, [later]), Log(), 'fake')
    controls.declare(set())
    controls.sync()
    return controls


def test_sync_survives_a_read_only_control_that_becomes_writable(peer):
    node = rclpy.create_node('sync_read_only', context=peer.context)
    try:
        _sync_with(node, _brightness(read_only=True), _brightness(value=140))
        # rclpy cannot change a read-only parameter: it keeps what it was declared with.
        assert node.describe_parameter('brightness').read_only
        assert node.get_parameter('brightness').value == 128
    finally:
        node.destroy_node()


def test_sync_moves_a_value_outside_the_new_range_with_the_range(peer):
    node = rclpy.create_node('sync_range', context=peer.context)
    try:
        _sync_with(node, _brightness(value=200),
                   _brightness(maximum=100, value=90, inactive=True))
        described = node.describe_parameter('brightness')
        assert described.integer_range[0].to_value == 100
        assert 'inactive' in described.additional_constraints
        assert node.get_parameter('brightness').value == 90
    finally:
        node.destroy_node()


def _declared(node):
    camera = Camera.open('synthetic', 160, 120, 10.0)
    applied = []

    def set_control(name, value):
        applied.append((name, value))
        return camera.set_control(name, value)

    controls = ControlParameters(Parameters(node), set_control, camera.controls, Log(),
                                 'synthetic')
    controls.declare(set())
    return camera, applied


def test_a_set_the_camera_refuses_in_part_changes_nothing(peer):
    node = rclpy.create_node('set_all_or_nothing', context=peer.context)
    camera, applied = _declared(node)
    try:
        # exposure_time_absolute is inactive while auto_exposure is on: the camera refuses it.
        results = node.set_parameters_atomically([
            Parameter('brightness', value=10), Parameter('exposure_time_absolute', value=300)])
        assert not results.successful
        assert 'exposure_time_absolute is inactive' in results.reason
        assert applied == []
        assert camera.control('brightness').value == 0
        assert node.get_parameter('brightness').value == 0
    finally:
        node.destroy_node()
        camera.release()


def test_a_set_that_frees_a_control_applies_the_automatic_mode_first(peer):
    node = rclpy.create_node('set_mode_first', context=peer.context)
    camera, applied = _declared(node)
    try:
        results = node.set_parameters_atomically([
            Parameter('exposure_time_absolute', value=300), Parameter('auto_exposure', value=1)])
        assert results.successful, results.reason
        assert [name for name, _ in applied] == ['auto_exposure', 'exposure_time_absolute']
        assert camera.control('exposure_time_absolute').value == 300
    finally:
        node.destroy_node()
        camera.release()
