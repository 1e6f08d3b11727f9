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
Every control a camera reports is a publisher parameter, described and refused by the device.

On the emulated 1080p webcam (18 controls: integers with steps, booleans, menus, a read-only
privacy switch, controls an automatic mode owns), through ROS's parameter services as `ros2
param` uses them: each control is named as v4l2_camera names it, carries the device's range,
step, default and menu in its descriptor (the format the browser panel reads) and the device's
value; a change reaches the device at once or is refused with the reason; usb_cam's names work
with the device's ranges too. On the emulated camera with a control of every V4L2 type (laid
out as the kernel's vivid driver has them), each type is a parameter, a button presses, string,
array and compound controls are said once not to be parameters, values given on the command
line reach the device, and a refused inactive control names the automatic mode holding it. The
synthetic camera's controls appear the same way.
"""

import re

from param_client import describe_parameters, get_parameters, list_parameters, set_parameter
from rcl_interfaces.msg import ParameterType
from ros_harness import wait_until

NODE = 'usbcam_publisher'
TYPES = {'integer': ParameterType.PARAMETER_INTEGER, 'menu': ParameterType.PARAMETER_INTEGER,
         'boolean': ParameterType.PARAMETER_BOOL}


def value_of(value):
    return value.bool_value if value.type == ParameterType.PARAMETER_BOOL else \
        value.integer_value


def test_every_control_is_a_parameter_with_the_devices_description(
        launch, peer, emulated_camera, ros_env):
    camera = emulated_camera()
    node = launch(NODE, params={'video_device': camera.device}, env=camera.env(ros_env))
    node.wait_for_output('opened', 30)
    controls = camera.model['controls']
    names = [control['name'] for control in controls]
    descriptors = describe_parameters(peer, NODE, names)
    values = get_parameters(peer, NODE, names)
    for control, descriptor, value in zip(controls, descriptors, values):
        name = control['name']
        assert descriptor.name == name and descriptor.type == TYPES[control['type']], name
        assert value_of(value) == camera.control(name), name   # read from the device
        assert descriptor.read_only == bool(control.get('read_only')), name
        assert descriptor.additional_constraints.startswith(
            'camera control 0x%08x (%s, step %d, default %d)' % (
                control['id'], control['type'], control['step'], control['default'])), name
        if control['type'] == 'boolean':
            assert not descriptor.integer_range, name
        else:
            (integer_range,) = descriptor.integer_range
            assert (integer_range.from_value, integer_range.to_value, integer_range.step) == (
                control['min'], control['max'], control['step']), name
        description = control['label']
        if control['type'] == 'menu':
            description += '; menu: ' + '; '.join(
                '%d=%s' % entry for entry in sorted(control['menu'].items()))
        assert descriptor.description == description, name
    exposure = descriptors[names.index('exposure_time_absolute')]
    assert exposure.additional_constraints.endswith('; inactive while auto_exposure is 3')
    # usb_cam's names, with the ranges of the controls they stand for.
    exposure, autoexposure, focus = describe_parameters(
        peer, NODE, ['exposure', 'autoexposure', 'focus'])
    assert exposure.additional_constraints == \
        'camera control: usb_cam name for exposure_time_absolute'
    assert (exposure.integer_range[0].from_value, exposure.integer_range[0].to_value) == (3, 2047)
    assert autoexposure.type == ParameterType.PARAMETER_BOOL
    assert focus.integer_range[0].step == 5


def test_changes_reach_the_device_or_are_refused_with_the_reason(
        launch, peer, emulated_camera, ros_env):
    camera = emulated_camera()
    node = launch(NODE, params={'video_device': camera.device, 'gain': 300},
                  env=camera.env(ros_env))
    node.wait_for_output('opened', 30)
    # Out of the device's range at start: said once, the device keeps its value.
    node.wait_for_output(r"gain: 300 is out of the camera's range 0\.\.255; left at the "
                         r"camera's own value", 10)
    assert camera.control('gain') == 0

    def refused(name, value):
        result = set_parameter(peer, NODE, name, value)
        assert not result.successful, (name, value)
        return result.reason

    assert refused('exposure_time_absolute', 100) == \
        'exposure_time_absolute is inactive while auto_exposure is 3'
    assert refused('exposure', 100) == 'exposure is inactive while auto_exposure is 3'
    assert refused('auto_exposure', 2) == 'auto_exposure: 2 is not one of its menu entries ' \
        '(1=Manual Mode; 3=Aperture Priority Mode)'
    assert 'privacy' in refused('privacy', True)               # read-only
    assert refused('brightness', 300)                           # out of range
    assert refused('pan_absolute', 100)                         # off its step of 3600
    assert camera.control('exposure_time_absolute') == 250      # nothing reached the device
    assert set_parameter(peer, NODE, 'autoexposure', False).successful
    assert camera.control('auto_exposure') == 1
    assert set_parameter(peer, NODE, 'exposure_time_absolute', 100).successful
    assert set_parameter(peer, NODE, 'pan_absolute', -7200).successful
    assert (camera.control('exposure_time_absolute'), camera.control('pan_absolute')) == \
        (100, -7200)

    # Each name shows the device's value: the alias, the control, and what became active.
    def shown():
        values = get_parameters(peer, NODE, ['auto_exposure', 'exposure', 'autoexposure'])
        return [value_of(value) for value in values] == [1, 100, False]
    wait_until(shown, 20, what='the parameters to follow the device')
    (exposure,) = describe_parameters(peer, NODE, ['exposure_time_absolute'])
    assert 'inactive' not in exposure.additional_constraints


def test_the_synthetic_cameras_controls_are_parameters_too(launch, peer):
    node = launch(NODE, params={'video_device': 'synthetic'})
    node.wait_for_output('opened synthetic', 30)
    temperature, auto_exposure = describe_parameters(
        peer, NODE, ['white_balance_temperature', 'auto_exposure'])
    assert (temperature.integer_range[0].from_value, temperature.integer_range[0].to_value) == \
        (2800, 6500)
    assert temperature.additional_constraints == 'camera control 0x0098091a (integer, step 1, ' \
        'default 4600); inactive while white_balance_automatic is 1'
    assert auto_exposure.description == 'Auto Exposure; menu: 1=Manual Mode; ' \
        '3=Aperture Priority Mode'


def wait_declared(peer, name):
    # The controls are declared once the camera is open, after 'opened' is logged.
    wait_until(lambda: name in list_parameters(peer, NODE), 20,
               what='%s to be declared' % name)


def test_every_control_type_is_handled_from_the_command_line_to_the_device(
        launch, peer, emulated_camera, ros_env):
    camera = emulated_camera('every_control')
    wide = -(1 << 50) - 3       # beyond 32 bits
    node = launch(NODE, params={
        'video_device': camera.device, 'image_width': 320, 'image_height': 240,
        'integer_64_bits': wide, 'gain': 7, 'gain_automatic': False, 'bitmask': 0x80400010,
        'integer_menu': 8, 'menu': 4, 'button': True}, env=camera.env(ros_env))
    node.wait_for_output('opened', 30)
    # Given on the command line: on the device, the automatic mode before the gain it holds
    # (they are set once the camera is open, after 'opened' is logged).
    given = ('integer_64_bits', 'gain_automatic', 'gain', 'bitmask', 'integer_menu', 'menu',
             'button')
    wait_until(lambda: [camera.control(name) for name in given] == [
        wide, 0, 7, 0x80400010, 8, 4, 1], 20, what='the values given to reach the device, '
               'the button pressed once')
    wait_declared(peer, 'integer_64_bits')
    assert len(re.findall('not parameters', node.output())) == 1
    assert 'not parameters (no single value to set): string (string), u32_1_element_array ' \
        '(array), area (compound)' in node.output()
    names = ['integer_64_bits', 'bitmask', 'integer_menu', 'button']
    described = dict(zip(names, describe_parameters(peer, NODE, names)))
    (wide_range,) = described['integer_64_bits'].integer_range
    assert (wide_range.from_value, wide_range.to_value) == (-2 ** 63, 2 ** 63 - 1)
    assert described['bitmask'].description == 'Bitmask; bitmask 0x80402010'
    assert described['integer_menu'].description == \
        'Integer Menu; menu: 2=2; 3=3; 4=5; 5=8; 6=13; 7=21; 8=42'
    assert described['button'].type == ParameterType.PARAMETER_BOOL
    assert [value_of(v) for v in get_parameters(peer, NODE, names)] == [
        wide, 0x80400010, 8, False]
    assert not {'string', 'u32_1_element_array', 'area'} & set(list_parameters(peer, NODE))

    # Changes: each reaches the device, or is refused with the reason.
    assert set_parameter(peer, NODE, 'integer_64_bits', 2 ** 40 + 1).successful
    assert camera.control('integer_64_bits') == 2 ** 40 + 1
    refused = set_parameter(peer, NODE, 'integer_menu', 1)
    assert refused.reason == \
        'integer_menu: 1 is not one of its menu entries (2=2; 3=3; 4=5; 5=8; 6=13; 7=21; 8=42)'
    refused = set_parameter(peer, NODE, 'bitmask', 1)
    assert refused.reason == 'bitmask: 0x1 has bits outside its mask 0x80402010'
    assert camera.control('bitmask') == 0x80400010
    # A button: true presses it, and it reads back false; false presses nothing.
    assert set_parameter(peer, NODE, 'button', True).successful
    assert camera.control('button') == 2
    wait_until(lambda: value_of(get_parameters(peer, NODE, ['button'])[0]) is False, 10,
               what='the button to read back false')
    assert set_parameter(peer, NODE, 'button', False).successful
    assert camera.control('button') == 2


def test_a_refused_inactive_control_names_the_automatic_mode_holding_it(
        launch, peer, emulated_camera, ros_env):
    camera = emulated_camera('every_control')
    node = launch(NODE, params={'video_device': camera.device, 'image_width': 320,
                                'image_height': 240}, env=camera.env(ros_env))
    node.wait_for_output('opened', 30)
    wait_declared(peer, 'blue_balance')
    for name, holder in (('gain', 'gain_automatic'), ('hue', 'hue_automatic'),
                         ('red_balance', 'white_balance_automatic'),
                         ('blue_balance', 'white_balance_automatic')):
        assert set_parameter(peer, NODE, name, 5).reason == \
            '%s is inactive while %s is 1' % (name, holder), name
        (described,) = describe_parameters(peer, NODE, [name])
        assert described.additional_constraints.endswith('; inactive while %s is 1' % holder)
        assert camera.control(name) == camera.control_info(name)['default']
    assert set_parameter(peer, NODE, 'gain_automatic', False).successful
    assert set_parameter(peer, NODE, 'gain', 5).successful
    assert camera.control('gain') == 5


def test_the_viewers_panel_shows_every_type_and_presses_a_button(
        launch, emulated_camera, ros_env):
    import http.client
    import json
    camera = emulated_camera('every_control')
    launch(NODE, params={'video_device': camera.device, 'image_width': 320,
                         'image_height': 240}, env=camera.env(ros_env))
    viewer = launch('usbcam_subscriber', params={'display': 'web', 'web_port': 0})
    port = int(viewer.wait_for_output(r'viewer at http://[^\s/]+:(\d+)/').group(1))

    def request(method, path, body=None):
        connection = http.client.HTTPConnection('127.0.0.1', port, timeout=10)
        try:
            connection.request(method, path, body=body,
                               headers={'Content-Type': 'application/json'})
            response = connection.getresponse()
            return response.status, json.loads(response.read())
        finally:
            connection.close()

    def shown():
        status, state = request('GET', '/camera')
        return state['controls'] if status == 200 and 'button' in state['controls'] else None
    controls = wait_until(shown, 30, interval=0.2, what='the controls in GET /camera')
    assert controls['button']['button'] and controls['button']['type'] == 'bool'
    assert controls['integer_64_bits']['max'] == 2 ** 63 - 1
    assert controls['integer_menu']['menu'][-1] == {'value': 8, 'label': '42'}
    assert controls['gain']['inactive'] == 'while gain_automatic is 1'
    assert 'string' not in controls and 'area' not in controls
    status, answer = request('POST', '/camera/controls', json.dumps({'button': True}).encode())
    assert status == 200 and answer['results']['button']['applied'], answer
    assert camera.control('button') == 1
    wait_until(lambda: (shown() or {}).get('button', {}).get('value') is False, 10,
               what='the button to read back false in the panel')


def test_list_formats_names_every_control_with_its_type(launch, emulated_camera, ros_env):
    camera = emulated_camera('every_control')
    node = launch(NODE, params={'video_device': camera.device},
                  extra_args=['--list-formats'], env=camera.env(ros_env))
    assert node.wait_exit(20) == 0, node.output()
    listed = node.output()
    for line in (
            'gain (0x00980913): int 0..255, default 100, value 100, inactive',
            'do_white_balance (0x0098090d): button',
            'integer_64_bits (0x0098f903): int64 -9223372036854775808..9223372036854775807, '
            'default 0, value 0',
            'bitmask (0x0098f906): bitmask 0x80402010, default 0x80002000, value 0x80002000',
            'integer_menu (0x0098f907): integer menu 2=2; 3=3; 4=5; 5=8; 6=13; 7=21; 8=42, '
            'default 4, value 4',
            'string (0x0098f905): string, not a parameter',
            'u32_1_element_array (0x0098f908): array, not a parameter',
            'area (0x0098f90b): compound, not a parameter'):
        assert '\n  %s\n' % line in listed, line
