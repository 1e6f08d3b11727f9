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

"""The executables as a ROS user types them: --help, bad arguments, typed parameters, signals."""

import os
from pathlib import Path
import random
import re
import shutil
import signal
import subprocess
import sys
import time

from param_client import describe_parameters, get_parameters
import pytest
from rcl_interfaces.msg import ParameterType
from rclpy.qos import QoSProfile, ReliabilityPolicy
import ros_harness
from ros_harness import wait_until
from sensor_msgs.msg import Image

EXECUTABLES = ('usbcam_publisher', 'usbcam_subscriber', 'cv_bridge_test', 'vision_step')
# The node each one runs, with parameters that start it without a camera or a port.
RUNNABLE = {
    'usbcam_publisher': {'video_device': 'synthetic', 'framerate': 30.0},
    'usbcam_subscriber': {'display': 'web', 'web_port': 0, 'stats_period': 1.0},
    'cv_bridge_test': {'display': 'web', 'web_port': 0},
    'vision_step': {'display': 'web', 'web_port': 0},
}
# What each one prints once it is fully up.
UP = {'usbcam_publisher': 'opened synthetic', 'usbcam_subscriber': 'browser viewer at',
      'cv_bridge_test': 'publishing them on', 'vision_step': 'publishing them on'}
# What each one prints last when it stops cleanly.
STOPPED = {'usbcam_publisher': 'camera released after'}


@pytest.mark.parametrize('executable', EXECUTABLES)
@pytest.mark.parametrize('flag', ['--help', '-h'])
def test_help_lists_the_parameters_and_starts_nothing(launch, executable, flag):
    node = launch(executable, extra_args=[flag])
    assert node.wait_exit(20) == 0
    out = node.output()
    assert out.startswith('usage: ros2 run py_vision %s' % executable)
    if executable == 'usbcam_publisher':
        assert re.search(r'framerate \(double, a number > 0 and <= 1000; default 10\.0\)', out)
        assert 'image_width (integer, 1..8192; default 640)' in out
        assert "brightness (integer, the camera's own range; default not set" in out
        assert 'autoexposure (bool, true or false; default not set' in out
        assert 'pixel_format (string, auto, or a FourCC: yuyv, uyvy,' in out
        assert "or usb_cam's mjpeg, mono8, mono16, rgb24, bgr24; default 'auto')" in out
    else:
        assert 'web_port (integer, 0..65535; default 8080)' in out
    # Nothing started: no node, no device, no viewer.
    assert 'opened' not in out and 'viewer at' not in out and '[INFO]' not in out


@pytest.mark.parametrize('executable', EXECUTABLES)
@pytest.mark.parametrize('args,words', [
    (['--ros-args', '-p', 'framerate=30'], "Couldn't parse parameter override rule"),
    (['--ros-args', '--no-such-flag'], 'unknown ROS arguments'),
    (['--ros-args', '-r', 'just_a_name'], "Couldn't parse remap rule"),
])
def test_malformed_ros_args_are_one_line_and_status_2(launch, executable, args, words):
    node = launch(executable, extra_args=args)
    assert node.wait_exit(20) == 2
    lines = [line for line in node.output().splitlines() if line.strip()]
    assert len(lines) == 1, node.output()
    assert lines[0].startswith('%s: invalid command line arguments' % executable)
    assert words in lines[0]


def test_parameters_have_their_real_type_and_range(launch, peer):
    launch('usbcam_publisher', {'video_device': 'synthetic', 'framerate': 15,
                                'image_width': 320, 'image_height': 240})
    names = ['framerate', 'image_width', 'video_device', 'jpeg_quality', 'frame_id',
             'brightness']
    values = get_parameters(peer, 'usbcam_publisher', names)
    assert values[0].type == ParameterType.PARAMETER_DOUBLE and values[0].double_value == 15.0
    assert values[1].type == ParameterType.PARAMETER_INTEGER and values[1].integer_value == 320
    assert values[2].type == ParameterType.PARAMETER_STRING
    # A camera control: the synthetic camera's own value, type and range.
    assert values[5].type == ParameterType.PARAMETER_INTEGER and values[5].integer_value == 0
    framerate, width, device, quality, frame_id, brightness = describe_parameters(
        peer, 'usbcam_publisher', names)
    assert framerate.type == ParameterType.PARAMETER_DOUBLE
    assert (framerate.floating_point_range[0].from_value,
            framerate.floating_point_range[0].to_value) == (0.0, 1000.0)
    assert (width.integer_range[0].from_value, width.integer_range[0].to_value) == (1, 8192)
    assert (quality.integer_range[0].from_value, quality.integer_range[0].to_value) == (1, 100)
    assert width.read_only and device.read_only
    assert not quality.read_only and not frame_id.read_only and not brightness.read_only
    assert (brightness.integer_range[0].from_value, brightness.integer_range[0].to_value) == \
        (-64, 64)
    assert framerate.description and quality.description


def test_a_dumped_null_control_leaves_the_cameras_own_value(launch, peer, tmp_path):
    # What older versions' `ros2 param dump` wrote for a control left at the camera's value.
    dump = tmp_path / 'dump.yaml'
    dump.write_text('usbcam_publisher:\n  ros__parameters:\n    brightness: null\n'
                    '    contrast: 40\n    video_device: synthetic\n')
    node = launch('usbcam_publisher', extra_args=['--params-file', str(dump)])
    node.wait_for_output('opened synthetic', 20)
    brightness, contrast = get_parameters(peer, 'usbcam_publisher', ['brightness', 'contrast'])
    assert brightness.type == ParameterType.PARAMETER_INTEGER and brightness.integer_value == 0
    assert contrast.integer_value == 40


def test_a_numeric_video_device_is_a_camera_index(launch):
    node = launch('usbcam_publisher', {'video_device': 97})
    assert node.wait_exit(20) == 1
    out = node.output()
    assert 'no camera 97 (/dev/video97 does not exist)' in out and 'must be' not in out


@pytest.mark.parametrize('params,named', [
    ({'frame_id': "''"}, 'frame_id'),  # YAML's empty string, as a shell passes ''
    ({'camera_name': 'front-left'}, 'camera_name'),
    ({'framerate': 'fast'}, 'framerate'),
    ({'image_width': 9000}, 'image_width'),
])
def test_unusable_values_are_one_clear_error(launch, params, named):
    node = launch('usbcam_publisher', dict({'video_device': 'synthetic'}, **params))
    assert node.wait_exit(20) == 1
    lines = [line for line in node.output().splitlines() if line.strip()]
    assert len(lines) == 1 and named in lines[0] and 'ERROR' in lines[0], node.output()


def test_logs_follow_the_nodes_real_name_and_namespace(launch):
    node = launch('usbcam_publisher', {'video_device': 'synthetic'},
                  extra_args=['-r', '__node:=cam_left', '-r', '__ns:=/robot'])
    node.wait_for_output('opened synthetic', 20)
    assert node.stop(signal.SIGINT) == 0
    lines = [line for line in node.output().splitlines() if line.startswith('[')]
    assert len(lines) >= 3
    for line in lines:
        assert '[robot.cam_left' in line, line
    assert 'usbcam_publisher' not in node.output()


def sigterm_handled(pid):
    """Return True once py_vision has its own SIGTERM handler (its package is importing)."""
    status = Path('/proc/%d/status' % pid).read_text()
    caught = int(re.search(r'SigCgt:\s*([0-9a-f]+)', status).group(1), 16)
    # Python catches SIGINT from its first instant; SIGTERM only once py_vision asks.
    return bool(caught & (1 << (signal.SIGTERM - 1)))


@pytest.mark.parametrize('executable', EXECUTABLES)
def test_signals_at_random_moments_of_start_up_and_running_end_cleanly(launch, executable):
    # Many starts, each signalled at its own random moment from the package's first import
    # to well after start-up: importing, rclpy.init, node creation, opening the camera or the
    # port, spinning. The moment is drawn, not timed: load only moves where it falls.
    rng = random.Random(executable)
    runs = []
    for number in range(6):
        sig = rng.choice([signal.SIGINT, signal.SIGTERM])
        node = launch(executable, RUNNABLE[executable], name='%s_%d' % (executable, number))
        wait_until(lambda: sigterm_handled(node.proc.pid), 30, interval=0.005,
                   what='%s to import py_vision' % executable)
        time.sleep(rng.uniform(0.0, 3.0))  # the random moment itself, not a synchronisation
        node.proc.send_signal(sig)
        runs.append((node, sig))
    for node, sig in runs:
        status = node.wait_exit(20)
        out = node.output()
        assert status == 0 and 'Traceback' not in out, '%s after %s:\n%s' % (
            node.name, signal.Signals(sig).name, out)


@pytest.mark.parametrize('executable', EXECUTABLES)
def test_a_second_sigint_does_not_cut_the_clean_up_short(launch, peer, executable):
    # ros2 launch forwards Ctrl-C to a node that got the terminal's already: two SIGINTs
    # about 100 ms apart, many times.
    if executable == 'usbcam_publisher':
        seen = peer.collect(Image, 'usb_camera/image',
                            QoSProfile(depth=5, reliability=ReliabilityPolicy.BEST_EFFORT))
    for number in range(5):
        node = launch(executable, RUNNABLE[executable], name='%s_%d' % (executable, number))
        node.wait_for_output(UP[executable], 30)
        if executable == 'usbcam_publisher':
            seen.clear()
            wait_until(lambda: seen, 20, what='frames')
        node.proc.send_signal(signal.SIGINT)
        time.sleep(0.1)  # the second Ctrl-C's delay is the point of this test
        node.proc.send_signal(signal.SIGINT)
        status = node.wait_exit(20)
        out = node.output()
        assert status == 0 and 'Traceback' not in out, out
        # The clean-up ran to its end: the node's own clean-up line, then node_main's last.
        assert 'stopped by SIGINT' in out.splitlines()[-1], out
        if executable in STOPPED:
            assert STOPPED[executable] in out, out


@pytest.mark.parametrize('executable', EXECUTABLES)
def test_a_node_that_inherited_ctrl_c_ignored_still_stops_cleanly_on_it(ros_env, executable):
    # Under a `ros2 launch` that a script started with `&` (an init script, a CI runner), every
    # node inherits SIGINT ignored: Ctrl-C to the launch's process group, what docs/boards.md
    # says to send, must still stop it cleanly, as a ROS node's own handler does.
    node = ros_harness.NodeProcess(
        shutil.which('env'), ['--ignore-signal=INT', str(ros_harness.EXECUTABLES / executable)]
        + ros_harness.ros_args(RUNNABLE[executable]), ros_env, name=executable)
    try:
        node.wait_for_output(UP[executable], 30)
        assert node.stop(signal.SIGINT, timeout=20) == 0
        out = node.output()
        assert 'Traceback' not in out and 'stopped by SIGINT' in out.splitlines()[-1], out
        if executable in STOPPED:
            assert STOPPED[executable] in out, out
    finally:
        node.kill()


@pytest.mark.parametrize('executable', EXECUTABLES)
def test_without_a_sourced_workspace_it_says_what_to_source(executable):
    # What a user gets who forgot `source install/setup.bash`: no PYTHONPATH, no ament index.
    env = {'PATH': os.environ.get('PATH', '/usr/bin:/bin'), 'HOME': os.environ.get('HOME', '/')}
    done = subprocess.run([str(ros_harness.EXECUTABLES / executable)], env=env,
                          capture_output=True, text=True, timeout=60)
    assert done.returncode == 1
    lines = done.stderr.splitlines()
    assert len(lines) == 1 and 'source install/setup.bash' in lines[0], done.stderr
    assert lines[0].startswith('%s: cannot start' % executable)


# A node whose command is interrupted by Ctrl-C while it works (the signal is its own, sent
# from inside the command: no timing involved).
INTERRUPTED_COMMAND = """
import os, signal, sys
from py_vision.node_main import run

class Lister:
    NODE_NAME = 'lister'
    def listing(argv):
        print('listing...', flush=True)
        os.kill(os.getpid(), signal.%s)
        print('listed')
        return 0
    COMMANDS = {'--list': listing}

sys.exit(run(Lister, ['lister', '--list']))
"""


@pytest.mark.parametrize('name,status', [('SIGINT', 130), ('SIGTERM', 143)])
def test_a_command_interrupted_by_a_signal_ends_quietly(ros_env, name, status):
    done = subprocess.run([sys.executable, '-c', INTERRUPTED_COMMAND % name],
                          env=ros_env, capture_output=True, text=True, timeout=60)
    assert (done.returncode, done.stdout, done.stderr) == (status, 'listing...\n', '')
