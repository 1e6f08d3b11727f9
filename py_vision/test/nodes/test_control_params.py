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
ControlParameters: a camera's controls declared as parameters of a node, in process.

The camera is the capture loop over a real `Camera`: the synthetic one, or a device with a
control of every V4L2 type laid out as the kernel's vivid driver has them (`TableSource`).
"""

from collections import Counter
from dataclasses import replace

from py_vision.capture import Camera, CaptureLoop, StreamFormat
from py_vision.capture.controls import (
    ARRAY, BITMASK, BOOL, BUTTON, CID, COMPOUND, ControlInfo, holder, INT, INT64, INT_MENU, MENU,
    SETTABLE, STRING)
from py_vision.control_params import ControlParameters
from py_vision.node_main import ConfigError
from py_vision.params import Parameters
import pytest
import rclpy
from rclpy.parameter import Parameter

VIVID = 0x0098f900   # vivid's own controls: V4L2_CID_USER_BASE | 0xf000
EVERY_TYPE = (
    ControlInfo(CID.BRIGHTNESS, 'Brightness', INT, 0, 255, 1, 128),
    ControlInfo(CID.AUTOGAIN, 'Gain, Automatic', BOOL, 0, 1, 1, 1),
    ControlInfo(CID.GAIN, 'Gain', INT, 0, 255, 1, 100),
    ControlInfo(VIVID + 0, 'Button', BUTTON, 0, 0, 0, 0),
    ControlInfo(VIVID + 3, 'Integer 64 Bits', INT64, -2 ** 63, 2 ** 63 - 1, 1, 0),
    ControlInfo(VIVID + 4, 'Menu', MENU, 1, 4, 1, 3,
                menu=((1, 'Menu Item 1'), (3, 'Menu Item 3'), (4, 'Menu Item 4'))),
    ControlInfo(VIVID + 5, 'String', STRING, 2, 4, 1, 0),
    ControlInfo(VIVID + 6, 'Bitmask', BITMASK, 0, 0x80402010, 1, 0x80002000),
    ControlInfo(VIVID + 7, 'Integer Menu', INT_MENU, 1, 8, 1, 4,
                menu=((2, '2'), (3, '3'), (4, '5'), (5, '8'), (6, '13'), (7, '21'), (8, '42'))),
    ControlInfo(VIVID + 8, 'U32 1 Element Array', ARRAY, 16, 0x20000, 1, 24),
    ControlInfo(VIVID + 11, 'Area', COMPOUND, 0, 0, 0, 0),
    ControlInfo(VIVID + 12, 'Read-Only Integer 32 Bits', INT, 0, 255, 1, 0, read_only=True),
)


class Log:
    """A logger that keeps its lines."""

    def __init__(self):
        self.lines = []

    def info(self, line):
        self.lines.append(line)

    warning = info


class TableSource:
    """A device with these controls and no frames: it keeps values, counts button presses."""

    def __init__(self, controls):
        self.table = {control.cid: control for control in controls}
        self.values = {cid: control.default for cid, control in self.table.items()}
        self.presses = Counter()

    def controls(self):
        return [control.with_value(
            self.values[cid] if control.kind in SETTABLE and control.kind != BUTTON else None,
            holder(cid, self.values) is not None) for cid, control in self.table.items()]

    def set_control(self, cid, value):
        if self.table[cid].kind == BUTTON:
            self.presses[cid] += 1
        else:
            self.values[cid] = value
        return None

    def release(self):
        pass

    interrupt = release


def open_loop(source):
    stream = StreamFormat('YUYV', 320, 240, 30.0)
    loop = CaptureLoop(lambda: Camera(source, 'table', stream, []), lambda camera, frame: None,
                       Log(), name='table')
    loop.open()
    return loop


@pytest.fixture
def node(peer, request):
    made = rclpy.create_node(request.node.name[:40].strip('_'), context=peer.context)
    yield made
    made.destroy_node()


def declared(node, source=None, log=None):
    """Declare the controls of source (the every-type table by default) on node."""
    source = source or TableSource(EVERY_TYPE)
    loop = open_loop(source)
    controls = ControlParameters(Parameters(node), loop, log or Log(), 'table')
    controls.declare(set())
    return source, loop, controls


def test_every_control_type_one_number_sets_is_a_parameter_with_its_range(node):
    log = Log()
    source, loop, controls = declared(node, log=log)
    assert controls.names == ['brightness', 'gain_automatic', 'gain', 'button',
                              'integer_64_bits', 'menu', 'bitmask', 'integer_menu',
                              'read_only_integer_32_bits']
    wide = node.describe_parameter('integer_64_bits')
    assert wide.type == Parameter.Type.INTEGER.value
    assert (wide.integer_range[0].from_value, wide.integer_range[0].to_value) == (
        -2 ** 63, 2 ** 63 - 1)
    assert wide.additional_constraints.startswith(
        'camera control 0x0098f903 (integer64, step 1, default 0)')
    menu = node.describe_parameter('integer_menu')
    assert menu.description == 'Integer Menu; menu: 2=2; 3=3; 4=5; 5=8; 6=13; 7=21; 8=42'
    assert (menu.integer_range[0].from_value, menu.integer_range[0].to_value) == (1, 8)
    bitmask = node.describe_parameter('bitmask')
    assert bitmask.description == 'Bitmask; bitmask 0x80402010'
    assert node.get_parameter('bitmask').value == 0x80002000
    button = node.describe_parameter('button')
    assert button.type == Parameter.Type.BOOL.value and not button.read_only
    assert 'set it true to press it' in button.description
    assert node.get_parameter('button').value is False
    assert node.describe_parameter('read_only_integer_32_bits').read_only
    # Not parameters, and said once.
    for name in ('string', 'u32_1_element_array', 'area'):
        assert not node.has_parameter(name), name
    assert [line for line in log.lines if 'not parameters' in line] == [
        'table: not parameters (no single value to set): string (string), '
        'u32_1_element_array (array), area (compound)']


def test_each_type_reaches_the_camera_or_is_refused_with_the_reason(node):
    source, loop, controls = declared(node)

    def set_one(name, value):
        result = node.set_parameters_atomically([Parameter(name, value=value)])
        return None if result.successful else result.reason
    assert set_one('integer_64_bits', 2 ** 40 + 7) is None
    assert source.values[VIVID + 3] == 2 ** 40 + 7
    assert set_one('integer_menu', 1) == \
        'integer_menu: 1 is not one of its menu entries (2=2; 3=3; 4=5; 5=8; 6=13; 7=21; 8=42)'
    assert set_one('integer_menu', 8) is None and source.values[VIVID + 7] == 8
    assert set_one('menu', 2) == \
        'menu: 2 is not one of its menu entries (1=Menu Item 1; 3=Menu Item 3; 4=Menu Item 4)'
    assert set_one('bitmask', 0x1) == 'bitmask: 0x1 has bits outside its mask 0x80402010'
    assert set_one('bitmask', 0x80400010) is None and source.values[VIVID + 6] == 0x80400010
    assert source.values[VIVID + 7] == 8 and source.values[VIVID + 3] == 2 ** 40 + 7


def test_a_button_presses_when_set_true_and_reads_back_false(node):
    source, loop, controls = declared(node)
    assert node.set_parameters_atomically([Parameter('button', value=True)]).successful
    assert source.presses[VIVID] == 1
    controls.sync()
    assert node.get_parameter('button').value is False
    assert node.set_parameters_atomically([Parameter('button', value=False)]).successful
    assert source.presses[VIVID] == 1, 'false presses nothing'
    assert VIVID not in loop.wanted_controls(), 'a press is not repeated after a reconnect'


def test_a_refused_inactive_control_names_the_automatic_mode_holding_it(node):
    source, loop, controls = declared(node)
    result = node.set_parameters_atomically([Parameter('gain', value=5)])
    assert result.reason == 'gain is inactive while gain_automatic is 1'
    assert 'inactive while gain_automatic is 1' in \
        node.describe_parameter('gain').additional_constraints
    # Switched off in the same set, the automatic mode goes first and frees the gain.
    assert node.set_parameters_atomically([
        Parameter('gain', value=5), Parameter('gain_automatic', value=False)]).successful
    assert (source.values[CID.AUTOGAIN], source.values[CID.GAIN]) == (0, 5)


def test_values_given_at_start_reach_the_camera_in_one_batch_and_a_refusal_is_a_warning(
        peer):
    overrides = [Parameter('integer_64_bits', value=-2 ** 50), Parameter('gain', value=7),
                 Parameter('gain_automatic', value=False), Parameter('button', value=True),
                 Parameter('brightness', value=999)]
    node = rclpy.create_node('given_at_start', context=peer.context,
                             parameter_overrides=overrides,
                             automatically_declare_parameters_from_overrides=False)
    try:
        log = Log()
        source, loop, controls = declared(node, log=log)
        assert source.values[VIVID + 3] == -2 ** 50
        assert (source.values[CID.AUTOGAIN], source.values[CID.GAIN]) == (0, 7)
        assert source.presses[VIVID] == 1
        assert source.values[CID.BRIGHTNESS] == 128
        assert ("brightness: 999 is out of the camera's range 0..255; left at the camera's "
                'own value') in log.lines
        assert node.get_parameter('integer_64_bits').value == -2 ** 50
        assert node.get_parameter('button').value is False
    finally:
        node.destroy_node()


def test_a_value_of_the_wrong_type_given_at_start_is_an_error(peer):
    node = rclpy.create_node('wrong_type', context=peer.context,
                             parameter_overrides=[Parameter('integer_64_bits', value='many')])
    try:
        with pytest.raises(ConfigError, match='integer_64_bits'):
            declared(node)
    finally:
        node.destroy_node()


class Lost:
    """A camera read twice while declared, unplugged before the second read."""

    def __init__(self, found):
        self.reads = iter([found, []])

    def controls(self):
        return next(self.reads, [])

    def set_controls(self, values, keep=True):
        return {}


def test_a_camera_lost_while_its_controls_are_declared_still_gets_them(node):
    # The controls are read twice while they are declared (before and after the values the
    # user gave are applied); a camera unplugged in between answers nothing the second time.
    camera = Camera.open('synthetic', 160, 120, 10.0)
    try:
        found = camera.controls()
        controls = ControlParameters(Parameters(node), Lost(found), Log(), 'synthetic')
        controls.declare(set())
        assert 'brightness' in controls.names
        brightness = next(c for c in found if c.cid == CID.BRIGHTNESS)
        assert node.get_parameter('brightness').value == brightness.value
    finally:
        camera.release()


def _brightness(**changes):
    control = ControlInfo(CID.BRIGHTNESS, 'Brightness', INT, 0, 255, 1, 128, 128)
    return replace(control, **changes)


class Reports:
    """A camera that reports `first` twice (while declared), then `later`."""

    def __init__(self, first, later):
        self.reads = iter([[first], [first]])
        self.later = later

    def controls(self):
        return next(self.reads, [self.later])

    def set_controls(self, values, keep=True):
        return {}


def test_sync_survives_a_read_only_control_that_becomes_writable(node):
    controls = ControlParameters(Parameters(node), Reports(
        _brightness(read_only=True), _brightness(value=140)), Log(), 'fake')
    controls.declare(set())
    controls.sync()
    # rclpy cannot change a read-only parameter: it keeps what it was declared with.
    assert node.describe_parameter('brightness').read_only
    assert node.get_parameter('brightness').value == 128


def test_sync_moves_a_value_outside_the_new_range_with_the_range(node):
    controls = ControlParameters(Parameters(node), Reports(
        _brightness(value=200), _brightness(maximum=100, value=90, inactive=True)), Log(),
        'fake')
    controls.declare(set())
    controls.sync()
    described = node.describe_parameter('brightness')
    assert described.integer_range[0].to_value == 100
    assert 'inactive' in described.additional_constraints
    assert node.get_parameter('brightness').value == 90


class Recorder:
    """The capture loop of a synthetic camera, recording each batch it is given."""

    def __init__(self, loop):
        self.loop = loop
        self.batches = []

    def controls(self):
        return self.loop.controls()

    def set_controls(self, values, keep=True):
        self.batches.append(dict(values))
        return self.loop.set_controls(values, keep)


def _synthetic(node):
    loop = CaptureLoop(lambda: Camera.open('synthetic', 160, 120, 10.0),
                       lambda camera, frame: None, Log())
    loop.open()
    recorder = Recorder(loop)
    ControlParameters(Parameters(node), recorder, Log(), 'synthetic').declare(set())
    return loop, recorder


def test_a_set_the_camera_refuses_in_part_changes_nothing(node):
    loop, recorder = _synthetic(node)
    try:
        # exposure_time_absolute is inactive while auto_exposure is on: the camera refuses it.
        results = node.set_parameters_atomically([
            Parameter('brightness', value=10), Parameter('exposure_time_absolute', value=300)])
        assert not results.successful
        assert results.reason == 'exposure_time_absolute is inactive while auto_exposure is 3'
        assert recorder.batches == []
        assert next(c.value for c in loop.controls() if c.cid == CID.BRIGHTNESS) == 0
        assert node.get_parameter('brightness').value == 0
    finally:
        loop.close()


def test_a_set_that_frees_a_control_goes_to_the_camera_as_one_batch(node):
    loop, recorder = _synthetic(node)
    try:
        results = node.set_parameters_atomically([
            Parameter('exposure_time_absolute', value=300), Parameter('auto_exposure', value=1)])
        assert results.successful, results.reason
        assert recorder.batches == [{CID.EXPOSURE_ABSOLUTE: 300, CID.EXPOSURE_AUTO: 1}]
        assert next(c.value for c in loop.controls() if c.cid == CID.EXPOSURE_ABSOLUTE) == 300
        # usb_cam's names go the same way.
        results = node.set_parameters_atomically([
            Parameter('exposure', value=200), Parameter('autoexposure', value=True)])
        assert results.reason == 'exposure is inactive while auto_exposure is 3'
    finally:
        loop.close()
