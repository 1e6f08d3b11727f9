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
`usbcam_publisher --list-formats`: what a camera offers, printed without a ROS graph.

On the emulated UVC cameras (docs/emulated_cameras.md) the listing comes from py_vision's own
V4L2 ioctls in the publisher's process: every pixel format, size and rate of the camera's data
file, and every control with its range, menu and value. A device that cannot be opened is one
error line and status 1.
"""

from listing_text import control_line, formats, offered
import pytest


def list_formats(launch, env, device, extra=()):
    node = launch('usbcam_publisher', params={'video_device': device},
                  extra_args=['--list-formats'] + list(extra), env=env)
    status = node.wait_exit(20)
    return status, node.output()


@pytest.mark.parametrize('model', ['webcam_1080p', 'vga_yuyv', 'synthetic'])
def test_every_format_size_and_rate_the_camera_offers_is_listed(
        launch, emulated_camera, ros_env, model):
    camera = emulated_camera(model=model)
    status, out = list_formats(launch, camera.env(ros_env), camera.by_id)
    assert status == 0, out
    expected = {fmt['fourcc']: {(frame['width'], frame['height']):
                                [float(rate) for rate in frame['rates']]
                                for frame in fmt['frames']}
                for fmt in camera.model['formats']}
    assert offered(out) == expected
    assert camera.model['product'] in out.splitlines()[0]
    assert camera.device in out.splitlines()[0]  # the by-id link, followed
    for control in camera.model['controls']:
        line = control_line(out, control['name'])
        assert line is not None, 'control %s missing:\n%s' % (control['name'], out)
        assert '0x%08x' % control['id'] in line
        if control['type'] == 'integer':
            assert '%d..%d' % (control['min'], control['max']) in line
        for value, label in control.get('menu', {}).items():
            assert '%d=%s' % (value, label) in line
        assert line.endswith('read-only') == bool(control.get('read_only'))
    assert '[' not in out  # no ROS graph, no log lines: the listing only


def test_the_synthetic_camera_lists_its_formats_and_controls(launch, ros_env):
    status, out = list_formats(launch, ros_env, 'synthetic')
    assert status == 0, out
    sizes = offered(out)
    assert sizes['YUYV'][(1280, 720)] == [10.0, 5.0]    # limited by USB 2.0
    assert sizes['MJPG'][(1280, 720)][0] == 30.0
    assert 'auto_exposure (0x009a0901): menu 1=Manual Mode; 3=Aperture Priority Mode' in out


def test_the_synthetic_camera_and_the_emulated_one_from_its_file_list_the_same(
        launch, emulated_camera, ros_env):
    # One description of a camera: what the synthetic camera offers is what the emulator
    # serves from the same data file, formats, sizes, rates and controls alike.
    camera = emulated_camera(model='synthetic')
    status, emulated = list_formats(launch, camera.env(ros_env), camera.by_id)
    assert status == 0, emulated
    status, synthetic = list_formats(launch, ros_env, 'synthetic')
    assert status == 0, synthetic
    assert offered(emulated) == offered(synthetic)
    assert formats(emulated) == formats(synthetic)

    def controls(out):
        return out[out.index('controls'):].splitlines()[1:]
    assert controls(emulated) == controls(synthetic)


def test_the_device_comes_from_a_params_file(launch, emulated_camera, ros_env, tmp_path):
    camera = emulated_camera(model='vga_yuyv')
    params = tmp_path / 'params.yaml'
    params.write_text('usbcam_publisher:\n  ros__parameters:\n    video_device: %s\n'
                      % camera.device)
    node = launch('usbcam_publisher', extra_args=['--list-formats', '--ros-args',
                                                  '--params-file', str(params)],
                  env=camera.env(ros_env))
    assert node.wait_exit(20) == 0
    assert list(offered(node.output())) == ['YUYV']


@pytest.mark.parametrize('content', ['- a list, not a mapping\n', 'usbcam_publisher: 5\n',
                                     'usbcam_publisher:\n  ros__parameters: [1, 2]\n'])
def test_a_params_file_the_node_could_not_read_is_one_line_and_status_2(
        launch, ros_env, tmp_path, content):
    # A YAML file that is not a mapping of node: {ros__parameters: {...}}: rcl refuses it, and
    # so does the listing, which reads the command line as the node does (ros_arguments):
    # one line naming the file, the status of malformed arguments, never a traceback.
    params = tmp_path / 'params.yaml'
    params.write_text(content)
    status, out = list_formats(launch, ros_env, 'synthetic',
                               ['--ros-args', '--params-file', str(params)])
    assert status == 2 and 'Traceback' not in out, out
    assert out.strip().count('\n') == 0 and str(params) in out, out
    assert out.startswith('usbcam_publisher: invalid command line arguments: '), out


def test_a_device_that_cannot_be_opened_is_one_line_and_status_1(
        launch, emulated_camera, ros_env):
    camera = emulated_camera(model='vga_yuyv')
    camera.deny()
    for device, words in ((camera.device, 'permission denied'),
                          ('/dev/video_py_vision_missing', 'no such device'),
                          ('/dev/null', 'not a video capture device')):
        status, out = list_formats(launch, camera.env(ros_env), device)
        lines = [line for line in out.splitlines() if line.strip()]
        assert status == 1 and len(lines) == 1, out
        assert lines[0].startswith('usbcam_publisher: cannot open video_device "%s"' % device)
        assert words in lines[0]
