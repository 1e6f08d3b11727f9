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
with the device's ranges too. The synthetic camera's controls appear the same way.
"""

from param_client import describe_parameters, get_parameters, set_parameter
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
