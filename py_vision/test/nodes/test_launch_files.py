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
The installed launch files, run for real with `ros2 launch`, every argument checked on the nodes.

Each launch file is started with its arguments, and what every node really got is read back:
its parameters over its parameter services (as `ros2 param get` does), what it opened (its
log), where the viewer listens (its socket, and the token it asks for), the lifecycle state of a
managed camera. What hand_signs.launch.py does on a board is seen by running `ros2 launch` as
on one (its process told that the machine is aarch64), and turtlesim through a stand-in package
whose node only waits for Ctrl-C (the tests' environments have no turtlesim, nor a screen).
This needs launch_ros and ros2cli: the board-version run has the boards' own
(Humble: launch_ros 0.19.2, ros2cli 0.18.3), as has `colcon test` on a ROS installation. The
PyPI Jazzy wheels of the main run have neither: there these tests are skipped with that reason.
"""

import importlib.util
import os
from pathlib import Path
import re
import shutil
import signal
import subprocess
import sys
import urllib.error
import urllib.request

from ament_index_python.packages import get_package_share_directory, PackageNotFoundError
from geometry_msgs.msg import Twist
from lifecycle_client import Lifecycle
from lifecycle_msgs.msg import Transition
from param_client import get_parameters
import pytest
from rclpy.parameter import parameter_value_to_python
import ros_harness
from ros_harness import wait_until
from sensor_msgs.msg import Image

ROS2 = shutil.which('ros2', path=ros_harness.installed_env().get('PATH'))
needs_launch = pytest.mark.skipif(
    ROS2 is None or importlib.util.find_spec('launch_ros') is None,
    reason='ros2 launch is not installed: the PyPI Jazzy wheels have no launch_ros or ros2cli '
           "(the board-version run has Humble's)")

LAUNCH_DIR = ros_harness.SHARE / 'launch'
CAMERA_ARGUMENTS = {'params_file', 'video_device', 'image_width', 'image_height', 'framerate',
                    'pixel_format', 'managed', 'autostart'}
PROMISED = {
    'camera.launch.py': CAMERA_ARGUMENTS,
    'pipeline.launch.py': CAMERA_ARGUMENTS | {'display', 'web_host', 'web_port', 'web_token'},
    'two_cameras.launch.py': CAMERA_ARGUMENTS | {'front_device', 'rear_device'},
    'hand_signs.launch.py': CAMERA_ARGUMENTS | {'threads', 'command_timeout', 'max_frame_age',
                                                'display', 'web_host', 'web_port', 'web_token'},
}
TOKEN = 'launch-test-token-0123456789'
# Generous: Humble's launch, three nodes and their DDS discovery on a loaded 2-core machine.
START_S = 30.0
# Runs `ros2 launch` (the script named next) as on a machine MACHINE/CPUS (the first
# argument): platform.machine() and os.cpu_count() answer that in this process, where the launch
# file runs and takes its defaults; the nodes are processes of their own, untouched.
AS_ON_MACHINE = ("import os, platform, runpy, sys; machine, cpus = sys.argv.pop(1).split('/'); "
                 'platform.machine = lambda: machine; os.cpu_count = lambda: int(cpus); '
                 "sys.argv.pop(0); runpy.run_path(sys.argv[0], run_name='__main__')")


@pytest.fixture
def ros2_launch(ros_env, request):
    """Start `ros2 launch py_vision FILE name:=value ...`; stopped (Ctrl-C) after the test."""
    started = request.node.node_processes = []

    def start(launch_file, machine=None, env=None, via=(), **arguments):
        # via: a command that execs the rest (`env --ignore-signal=INT`), before `ros2 launch`.
        args = ['launch', 'py_vision', launch_file] + [
            '%s:=%s' % (name, value) for name, value in arguments.items()]
        if machine is None:
            cmd = [ROS2] + args
        else:
            cmd = [sys.executable, '-c', AS_ON_MACHINE, machine, ROS2] + args
        cmd = list(via) + cmd
        proc = ros_harness.NodeProcess(cmd[0], cmd[1:], env or ros_env, name=launch_file)
        started.append(proc)
        return proc
    yield start
    for proc in started:
        proc.kill()


def parameters(peer, node, names):
    """Return {name: value} of a running node's parameters, read over its services."""
    return {name: parameter_value_to_python(value)
            for name, value in zip(names, get_parameters(peer, node, names))}


def stops_cleanly(proc, nodes):
    """Ctrl-C the launch: it and every node it started (names, repeated) end cleanly."""
    assert proc.stop(timeout=20.0) == 0, proc.tail()
    nodes_finished_cleanly(proc, nodes)


def nodes_finished_cleanly(proc, nodes):
    """Every node the launch started (names, repeated) finished cleanly, launch says."""
    output = proc.output()
    for node in set(nodes):
        assert len(re.findall(r'\[%s-\d+\]: process has finished cleanly' % node, output)) \
            == nodes.count(node), proc.tail()


def test_the_launch_files_are_installed():
    assert sorted(path.name for path in LAUNCH_DIR.iterdir()) == sorted(PROMISED)


@needs_launch
@pytest.mark.parametrize('launch_file', sorted(PROMISED))
def test_a_launch_file_shows_the_promised_arguments(ros_env, launch_file):
    shown = subprocess.run([ROS2, 'launch', 'py_vision', launch_file, '--show-args'],
                           env=ros_env, capture_output=True, text=True, timeout=START_S)
    assert shown.returncode == 0, shown.stdout + shown.stderr
    assert set(re.findall(r"^    '(\w+)':$", shown.stdout, re.MULTILINE)) == \
        PROMISED[launch_file], shown.stdout


@needs_launch
def test_camera_arguments_reach_the_publisher(ros2_launch, peer):
    # framerate:=15 is an integer to launch: it must reach the node as the double 15.0.
    proc = ros2_launch('camera.launch.py', video_device='synthetic', image_width=320,
                       image_height=240, framerate=15, pixel_format='mjpeg')
    proc.wait_for_output(r'opened synthetic: 320x240 MJPE?G at 15 fps', START_S)
    assert parameters(peer, 'usbcam_publisher', [
        'video_device', 'image_width', 'image_height', 'framerate', 'pixel_format',
        'managed']) == {'video_device': 'synthetic', 'image_width': 320, 'image_height': 240,
                        'framerate': 15.0, 'pixel_format': 'mjpeg', 'managed': False}
    stops_cleanly(proc, ['usbcam_publisher'])


@needs_launch
def test_an_argument_wins_over_the_params_file_the_rest_is_the_files(
        ros2_launch, peer, tmp_path):
    params_file = tmp_path / 'my_params.yaml'
    params_file.write_text('usbcam_publisher:\n  ros__parameters:\n    video_device: synthetic\n'
                           '    image_width: 320\n    image_height: 240\n'
                           '    framerate: 5.0\n    jpeg_quality: 50\n')
    proc = ros2_launch('camera.launch.py', params_file=params_file, framerate=7)
    proc.wait_for_output(r'opened synthetic: 320x240 \w+ at 7 fps', START_S)
    assert parameters(peer, 'usbcam_publisher', [
        'video_device', 'image_width', 'framerate', 'jpeg_quality']) == {
        'video_device': 'synthetic', 'image_width': 320, 'framerate': 7.0, 'jpeg_quality': 50}


@needs_launch
def test_video_device_0_reaches_the_node_as_camera_index_0(ros2_launch):
    # As a string: the integer 0 would be refused as a video_device of the wrong type.
    proc = ros2_launch('camera.launch.py', video_device=0)
    proc.wait_for_output(r'cannot open video_device "0": no camera 0', START_S)
    proc.wait_for_output(r'\[usbcam_publisher-\d+\]: process has died .*exit code 1', START_S)


@needs_launch
def test_managed_camera_is_configured_and_activated(ros2_launch, peer):
    frames = peer.collect(Image, '/usb_camera/image')
    proc = ros2_launch('camera.launch.py', video_device='synthetic', managed='true')
    lifecycle = Lifecycle(peer)
    wait_until(lambda: lifecycle.get() == 'active', START_S, 0.2, what='the camera active')
    wait_until(lambda: len(frames) >= 3, START_S, what='frames from the managed camera')
    assert parameters(peer, 'usbcam_publisher', ['managed', 'video_device']) == {
        'managed': True, 'video_device': 'synthetic'}
    stops_cleanly(proc, ['usbcam_publisher'])


@needs_launch
def test_managed_camera_without_autostart_waits_unconfigured(ros2_launch, peer):
    frames = peer.collect(Image, '/usb_camera/image')
    proc = ros2_launch('camera.launch.py', video_device='synthetic', managed='true',
                       autostart='false')
    lifecycle = Lifecycle(peer)
    # launch emits no transition: the node answers from the state it started in.
    assert lifecycle.get() == 'unconfigured', proc.tail()
    assert not frames
    assert lifecycle.set(Transition.TRANSITION_CONFIGURE)
    assert lifecycle.set(Transition.TRANSITION_ACTIVATE)
    wait_until(lambda: len(frames) >= 3, START_S, what='frames once a manager activated it')


def listening_address(port):
    """Return the IPv4 address a local TCP socket listens on at port (/proc/net/tcp), or None."""
    with open('/proc/net/tcp') as table:
        for line in table.readlines()[1:]:
            local, state = line.split()[1], line.split()[3]
            address, local_port = local.split(':')
            if int(local_port, 16) == port and state == '0A':  # TCP_LISTEN
                return '.'.join(str(int(address[i:i + 2], 16)) for i in (6, 4, 2, 0))
    return None


def http_status(url):
    try:
        with urllib.request.urlopen(url, timeout=10) as answer:
            return answer.status
    except urllib.error.HTTPError as error:
        return error.code


@needs_launch
def test_pipeline_viewer_arguments_reach_the_viewer(ros2_launch, peer):
    # The README's headless-board command, on a free port and with a token of our own.
    processed = peer.collect(Image, '/cv_bridge_image')
    proc = ros2_launch('pipeline.launch.py', video_device='synthetic', framerate=15,
                       display='web', web_host='0.0.0.0', web_port=0, web_token=TOKEN)
    url = proc.wait_for_output(
        r'\[usbcam_subscriber\]: browser viewer at (http://[^\s/]+:(\d+)/)\?token=(\S+)',
        START_S)
    port = int(url.group(2))
    assert url.group(3) == TOKEN
    assert listening_address(port) == '0.0.0.0'
    # Off loopback every request needs the token; with it the viewer answers.
    local = 'http://127.0.0.1:%d/stats' % port
    assert http_status(local) == 401
    assert http_status(local + '?token=' + TOKEN) == 200
    assert parameters(peer, 'usbcam_subscriber', [
        'display', 'web_host', 'web_port', 'web_token']) == {
        'display': 'web', 'web_host': '0.0.0.0', 'web_port': 0, 'web_token': TOKEN}
    # The camera's arguments reach the camera, and the processing node is in between.
    proc.wait_for_output(r'\[usbcam_publisher\]: opened synthetic: 640x480 \w+ at 15 fps',
                         START_S)
    assert parameters(peer, 'cv_bridge_test', ['display']) == {'display': 'none'}
    wait_until(lambda: len(processed) >= 3, START_S, what='processed frames')
    stops_cleanly(proc, ['usbcam_publisher', 'cv_bridge_test', 'usbcam_subscriber'])


def turtlesim_installed():
    try:
        get_package_share_directory('turtlesim')
    except PackageNotFoundError:
        return False
    return True


DISPLAY_VARIABLES = ('DISPLAY', 'WAYLAND_DISPLAY', 'QT_QPA_PLATFORM')


@needs_launch
def test_hand_signs_runs_camera_step_viewer_and_says_why_turtlesim_is_not_up(
        ros2_launch, peer, ros_env):
    # No display (as on a board reached by ssh): no real turtlesim window opens here; the
    # display case is the stand-in's test below.
    env = {name: value for name, value in ros_env.items() if name not in DISPLAY_VARIABLES}
    twists = peer.collect(Twist, '/turtle1/cmd_vel')
    shown = peer.collect(Image, '/vision_step/image')
    proc = ros2_launch('hand_signs.launch.py', env=env, video_device='synthetic', framerate=10,
                       image_width=320, image_height=240, display='web', web_port=0)
    proc.wait_for_output(r'\[vision_step\]: running step hand_signs .*hand_landmark_lite',
                         START_S)
    proc.wait_for_output(r'\[usbcam_subscriber\]: browser viewer at http://127.0.0.1:\d+/',
                         START_S)
    assert parameters(peer, 'usbcam_subscriber', ['display']) == {'display': 'web'}
    # The synthetic camera shows no hand: the turtle is told to stand still.
    wait_until(lambda: len(twists) >= 3 and shown, START_S, what='Twists and processed frames')
    assert all((t.linear.x, t.angular.z) == (0.0, 0.0) for t in list(twists))
    if turtlesim_installed():
        assert 'no display here (DISPLAY is not set): turtlesim not started' in proc.output(), \
            proc.tail()
    else:
        assert 'turtlesim is not installed: not started' in proc.output(), proc.tail()
    stops_cleanly(proc, ['usbcam_publisher', 'vision_step', 'usbcam_subscriber'])


# A stand-in for turtlesim_node: says it started, ends cleanly on Ctrl-C. No window.
STAND_IN_TURTLESIM = (
    'import signal\n'
    'signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGINT, signal.SIGTERM})\n'
    "print('stand-in turtlesim_node', flush=True)\n"
    'signal.sigwait({signal.SIGINT, signal.SIGTERM})\n')


def install_stand_in_turtlesim(prefix):
    """Make a prefix in which the ament index finds a turtlesim package and its node."""
    index = prefix / 'share' / 'ament_index' / 'resource_index' / 'packages'
    index.mkdir(parents=True)
    (index / 'turtlesim').write_text('')
    (prefix / 'share' / 'turtlesim').mkdir()
    node = prefix / 'lib' / 'turtlesim' / 'turtlesim_node'
    node.parent.mkdir(parents=True)
    node.write_text('#!%s\n%s' % (sys.executable, STAND_IN_TURTLESIM))
    node.chmod(0o755)


@needs_launch
@pytest.mark.parametrize('display', [':0', None])
def test_hand_signs_starts_turtlesim_only_where_it_has_a_display(
        ros2_launch, peer, ros_env, tmp_path, display):
    # turtlesim's Qt window aborts without a display: a board reached by plain ssh has none.
    install_stand_in_turtlesim(tmp_path)
    env = dict(ros_env, AMENT_PREFIX_PATH='%s:%s' % (tmp_path, ros_env['AMENT_PREFIX_PATH']))
    for name in DISPLAY_VARIABLES:
        env.pop(name, None)
    if display:
        env['DISPLAY'] = display
    twists = peer.collect(Twist, '/turtle1/cmd_vel')
    proc = ros2_launch('hand_signs.launch.py', env=env, video_device='synthetic',
                       image_width=320, image_height=240, display='none')
    wait_until(lambda: len(twists) >= 3, START_S, what='Twists from the step')
    nodes = ['usbcam_publisher', 'vision_step', 'usbcam_subscriber']
    if display:
        proc.wait_for_output(r'\[turtlesim_node-\d+\] stand-in turtlesim_node', START_S)
        nodes.append('turtlesim_node')
    else:
        assert 'no display here (DISPLAY is not set): turtlesim not started' in proc.output()
        assert 'turtlesim_node' not in proc.output(), proc.tail()
    stops_cleanly(proc, nodes)


@needs_launch
@pytest.mark.parametrize('machine, given, camera, command', [
    ('aarch64/2', {}, (320, 240, 10.0), (1.0, 1.0)),      # ZUBoard 1CG: two Cortex-A53s
    ('aarch64/4', {'framerate': 12, 'max_frame_age': 0.8},  # four: the size of params_file;
     (640, 480, 12.0), (1.0, 0.8)),                       # an argument wins
    ('x86_64/2', {'threads': 2}, (640, 480, 10.0), (0.5, 0.5)),  # a PC: params_file
])
def test_hand_signs_camera_on_a_board_and_on_a_pc_and_step_arguments_reach_the_step(
        ros2_launch, peer, machine, given, camera, command):
    twists = peer.collect(Twist, '/turtle1/cmd_vel')
    proc = ros2_launch('hand_signs.launch.py', machine=machine, video_device='synthetic',
                       display='none', **given)
    proc.wait_for_output(r'\[usbcam_publisher\]: opened synthetic: %dx%d \w+ at %g fps' % camera,
                         START_S)
    assert parameters(peer, 'usbcam_publisher', ['image_width', 'image_height', 'framerate']) \
        == dict(zip(('image_width', 'image_height', 'framerate'), camera))
    assert parameters(peer, 'vision_step', ['step', 'threads', 'command_timeout',
                                            'max_frame_age']) == {
        'step': 'hand_signs', 'threads': given.get('threads', 1),
        'command_timeout': command[0], 'max_frame_age': command[1]}
    wait_until(lambda: len(twists) >= 3, START_S, what='Twists from the step')


@needs_launch
def test_two_cameras_each_in_its_namespace_with_its_device(ros2_launch, peer):
    front = peer.collect(Image, '/front/usb_camera/image')
    rear = peer.collect(Image, '/rear/usb_camera/image')
    proc = ros2_launch('two_cameras.launch.py', front_device='synthetic',
                       rear_device='synthetic')
    for side, frames in (('front', front), ('rear', rear)):
        assert parameters(peer, '%s/usbcam_publisher' % side, ['video_device']) == {
            'video_device': 'synthetic'}
        wait_until(lambda: len(frames) >= 3, START_S, what='frames on /%s' % side)
    stops_cleanly(proc, ['usbcam_publisher', 'usbcam_publisher'])


@needs_launch
def test_a_launch_stops_cleanly_when_the_tests_were_started_in_the_background(
        started_in_the_background, ros2_launch):
    # scripts/test.sh started by a script in the background runs every test so: the launch
    # must still stop on the test's Ctrl-C (Humble's kept the SIGINT it inherited ignored).
    proc = ros2_launch('camera.launch.py', video_device='synthetic')
    proc.wait_for_output(r'opened synthetic', START_S)
    stops_cleanly(proc, ['usbcam_publisher'])


def ignores(pid, sig):
    """Return whether process pid ignores signal sig (/proc/PID/status)."""
    status = Path('/proc/%d/status' % pid).read_text()
    return bool(int(re.search(r'SigIgn:\s*([0-9a-f]+)', status).group(1), 16) & (1 << (sig - 1)))


@needs_launch
def test_a_launch_that_inherited_ctrl_c_ignored_stops_on_ctrl_c_to_its_process_group(
        ros2_launch, peer):
    # docs/boards.md: a launch a script started with `&` (an init script, a CI runner) inherits
    # SIGINT ignored and keeps it so; SIGINT to its whole process group, as a terminal's Ctrl-C
    # sends it, stops every node cleanly, and the launch ends with them.
    env = shutil.which('env')
    front = peer.collect(Image, '/front/usb_camera/image')
    rear = peer.collect(Image, '/rear/usb_camera/image')
    proc = ros2_launch('two_cameras.launch.py', via=[env, '--ignore-signal=INT'],
                       front_device='synthetic', rear_device='synthetic')
    wait_until(lambda: len(front) >= 3 and len(rear) >= 3, START_S,
               what='frames from both cameras')
    assert ignores(proc.pid, signal.SIGINT), proc.tail()
    os.killpg(proc.pid, signal.SIGINT)  # the harness started it in a session of its own
    assert proc.wait_exit(START_S) == 0, proc.tail()
    assert 'user interrupted with ctrl-c' not in proc.output(), proc.tail()
    nodes_finished_cleanly(proc, ['usbcam_publisher', 'usbcam_publisher'])
