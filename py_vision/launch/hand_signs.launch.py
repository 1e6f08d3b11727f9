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
Hand signs drive the turtle: camera, the hand_signs step, the viewer, and turtlesim.

    ros2 launch py_vision hand_signs.launch.py
    ros2 launch py_vision hand_signs.launch.py video_device:=/dev/video2 display:=web
    ros2 launch py_vision hand_signs.launch.py video_device:=auto display:=web \
        web_host:=0.0.0.0                                    # on a board, watched from a PC

usb_camera/image -> vision_step (step hand_signs) -> vision_step/image -> usbcam_subscriber,
and vision_step's Twist on /turtle1/cmd_vel -> turtlesim_node, where the turtlesim package is
installed (the PetaLinux fragments install it on the boards) and there is a display to open
its window on (DISPLAY, WAYLAND_DISPLAY or a QT_QPA_PLATFORM of your choice); otherwise one
line says why not, and the rest runs. The camera's arguments are camera.launch.py's, except
that on an ARM board framerate, and on one of two cores the size, have defaults of their own
(board_defaults, below); threads, command_timeout and max_frame_age set vision_step's (the
last two with defaults of their own on an ARM board); display, web_host, web_port and
web_token set the viewer's parameters of those names (empty: the value in params_file).
docs/processing.md has the signs and their motions, docs/boards.md what the pipeline costs on
the boards and why these defaults.
"""

import os
import platform

from ament_index_python.packages import get_package_share_directory, PackageNotFoundError
from launch import LaunchDescription
from launch.actions import (
    DeclareLaunchArgument, IncludeLaunchDescription, LogInfo, OpaqueFunction)
from launch.launch_description_sources import PythonLaunchDescriptionSource
from launch.substitutions import LaunchConfiguration, PathJoinSubstitution
from launch_ros.actions import Node
from launch_ros.parameter_descriptions import ParameterValue
from launch_ros.substitutions import FindPackageShare

# The camera on the boards' Cortex-A53s (docs/boards.md, from bench/bench_hand_signs.py): the
# step processes 3 to 7 frames a second there, so 10 fps hands it a frame at most 0.1 s old
# while costing the camera a third to half a core at 640x480; on two cores (the ZUBoard 1CG)
# 640x480 leaves nothing of the board at 10 fps and next to nothing at 5, 320x240 at 10 fps
# a third to half a core (the models see the same either way).
BOARD_FRAMERATE = '10.0'
TWO_CORE_SIZE = {'image_width': '320', 'image_height': '240'}
# The command path's timings there: a processed frame every 0.14 to 0.33 s, and a command
# decided up to a frame period (0.1 s at 10 fps: the step takes the newest frame) plus its
# processing after its frame arrived. The step's own 0.5 s would stop the robot between frames
# or for a frame not yet old: 1.0 s, three times the longest, keeps the watchdog for a lost
# camera and stale frames.
BOARD_COMMAND_S = '1.0'
ARM_MACHINES = ('aarch64', 'arm64', 'armv7l', 'armv8l')
# The camera's arguments with a default of this launch's own: name -> meaning.
BOARD_ARGUMENTS = {
    'framerate': 'frames per second (%s on an ARM board, where the step processes a few frames '
                 'a second; elsewhere empty: the value in params_file)' % BOARD_FRAMERATE,
    'image_width': 'requested frame width in pixels (%s on an ARM board of two cores; elsewhere '
                   'empty: the value in params_file)' % TWO_CORE_SIZE['image_width'],
    'image_height': 'requested frame height in pixels (%s on an ARM board of two cores; '
                    'elsewhere empty: the value in params_file)' % TWO_CORE_SIZE['image_height'],
}

# What tells Qt, and so turtlesim's window, where to draw.
DISPLAY_VARIABLES = ('DISPLAY', 'WAYLAND_DISPLAY', 'QT_QPA_PLATFORM')

# vision_step's parameters that are launch arguments: name -> (type the node takes, meaning).
STEP_ARGUMENTS = {
    'threads': (int, 'CPU threads of the hand and palm models; 1 keeps the step from waiting '
                     'on cores the camera and the viewer hold'),
    'command_timeout': (float, 'seconds without a processed frame after which a stop command '
                               'goes out (%s on an ARM board, whatever params_file says; '
                               'elsewhere empty: the value in params_file)' % BOARD_COMMAND_S),
    'max_frame_age': (float, 'seconds since a frame arrived after which it stops the robot '
                             'instead of steering it (%s on an ARM board, whatever params_file '
                             'says; elsewhere empty: the value in params_file)' % BOARD_COMMAND_S),
}

# The viewer parameters that are launch arguments: name -> (type the node takes, meaning).
VIEWER_ARGUMENTS = {
    'display': (str, 'where the viewer shows the processed frames: window, web, none or auto'),
    'web_host': (str, 'address the browser viewer listens on (0.0.0.0: every interface, '
                      'behind a token)'),
    'web_port': (int, 'port of the browser viewer (0: any free port)'),
    'web_token': (str, 'the token the browser viewer requires off loopback (empty in '
                       'params_file: a random one, logged as the URL to open)'),
}


def board_defaults():
    """
    Return the arguments this launch gives by default on this machine: none on a PC.

    On an ARM machine (the boards: Cortex-A53s) the camera runs at BOARD_FRAMERATE, and with
    two cores or fewer (the ZUBoard 1CG) at 320x240 too; the step's command_timeout and
    max_frame_age are BOARD_COMMAND_S. Elsewhere (a PC, whose step keeps up with the camera)
    the values in params_file.
    """
    if platform.machine().lower() not in ARM_MACHINES:
        return {}
    defaults = {'framerate': BOARD_FRAMERATE, 'command_timeout': BOARD_COMMAND_S,
                'max_frame_age': BOARD_COMMAND_S}
    if (os.cpu_count() or 1) <= 2:
        defaults.update(TWO_CORE_SIZE)
    return defaults


def given(context, arguments):
    """Return the parameters of `arguments` (name -> (type, meaning)) given a value."""
    return {name: ParameterValue(LaunchConfiguration(name), value_type=kind)
            for name, (kind, _) in arguments.items()
            if LaunchConfiguration(name).perform(context)}


def start_step(context):
    """Return vision_step running hand_signs, with the step arguments given."""
    return [Node(package='py_vision', executable='vision_step', output='screen',
                 parameters=[LaunchConfiguration('params_file'),
                             dict(given(context, STEP_ARGUMENTS), step='hand_signs')])]


def start_viewer(context):
    """Return the subscriber, remapped to vision_step/image, with the viewer arguments given."""
    return [Node(package='py_vision', executable='usbcam_subscriber', output='screen',
                 parameters=[LaunchConfiguration('params_file'),
                             given(context, VIEWER_ARGUMENTS)],
                 remappings=[('usb_camera/image', 'vision_step/image')])]


def start_turtlesim(context):
    """Return turtlesim_node where it is installed and has a display, else a line saying why."""
    try:
        get_package_share_directory('turtlesim')
    except PackageNotFoundError:
        return [LogInfo(msg='turtlesim is not installed: not started; the Twists still go '
                            'out on /turtle1/cmd_vel (install ros-<distro>-turtlesim to see '
                            'the turtle move)')]
    # Its Qt window needs a display: without one turtlesim_node aborts at start.
    if not any(os.environ.get(name) for name in DISPLAY_VARIABLES):
        return [LogInfo(msg='no display here (DISPLAY is not set): turtlesim not started; the '
                            'Twists still go out on /turtle1/cmd_vel, for a turtlesim on a '
                            "machine with a screen (DISPLAY=:0 for a board's own, ssh -X for "
                            "your PC's: docs/boards.md)")]
    return [Node(package='turtlesim', executable='turtlesim_node', output='screen')]


def generate_launch_description():
    """Declare the arguments, include the camera, start the step, the viewer and turtlesim."""
    defaults = board_defaults()
    return LaunchDescription([
        DeclareLaunchArgument(
            'params_file', description='parameter file of the py_vision nodes',
            default_value=PathJoinSubstitution(
                [FindPackageShare('py_vision'), 'config', 'params.yaml'])),
        # Declared before camera.launch.py, whose own declarations then keep these defaults.
        *[DeclareLaunchArgument(name, default_value=defaults.get(name, ''),
                                description=meaning)
          for name, meaning in BOARD_ARGUMENTS.items()],
        *[DeclareLaunchArgument(name, default_value=defaults.get(name, ''), description=(
            meaning if 'params_file' in meaning else '%s (empty: the value in params_file)'
            % meaning))
          for name, (_, meaning) in list(STEP_ARGUMENTS.items()) + list(
              VIEWER_ARGUMENTS.items())],
        IncludeLaunchDescription(PythonLaunchDescriptionSource(PathJoinSubstitution(
            [FindPackageShare('py_vision'), 'launch', 'camera.launch.py']))),
        OpaqueFunction(function=start_step),
        OpaqueFunction(function=start_viewer),
        OpaqueFunction(function=start_turtlesim),
    ])
