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

from py_vision.capture import Camera
from py_vision.control_params import ControlParameters
from py_vision.params import Parameters
import rclpy


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
