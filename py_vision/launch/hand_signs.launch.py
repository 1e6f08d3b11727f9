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

usb_camera/image -> vision_step (step hand_signs) -> vision_step/image -> usbcam_subscriber,
and vision_step's Twist on /turtle1/cmd_vel -> turtlesim_node, where the turtlesim package is
installed (the PetaLinux fragments install it on the boards; otherwise one line says it is
not, and the rest runs). The camera's arguments are camera.launch.py's; display, web_host,
web_port and web_token set the viewer's parameters of those names (empty: the value in
params_file). docs/processing.md has the signs and their motions.
"""

from ament_index_python.packages import get_package_share_directory, PackageNotFoundError
from launch import LaunchDescription
from launch.actions import (
    DeclareLaunchArgument, IncludeLaunchDescription, LogInfo, OpaqueFunction)
from launch.launch_description_sources import PythonLaunchDescriptionSource
from launch.substitutions import LaunchConfiguration, PathJoinSubstitution
from launch_ros.actions import Node
from launch_ros.parameter_descriptions import ParameterValue
from launch_ros.substitutions import FindPackageShare

# The viewer parameters that are launch arguments: name -> (type the node takes, meaning).
VIEWER_ARGUMENTS = {
    'display': (str, 'where the viewer shows the processed frames: window, web, none or auto'),
    'web_host': (str, 'address the browser viewer listens on (0.0.0.0: every interface, '
                      'behind a token)'),
    'web_port': (int, 'port of the browser viewer (0: any free port)'),
    'web_token': (str, 'the token the browser viewer requires off loopback (empty in '
                       'params_file: a random one, logged as the URL to open)'),
}


def start_viewer(context):
    """Return the subscriber, remapped to vision_step/image, with the viewer arguments given."""
    given = {name: ParameterValue(LaunchConfiguration(name), value_type=kind)
             for name, (kind, _) in VIEWER_ARGUMENTS.items()
             if LaunchConfiguration(name).perform(context)}
    return [Node(package='py_vision', executable='usbcam_subscriber', output='screen',
                 parameters=[LaunchConfiguration('params_file'), given],
                 remappings=[('usb_camera/image', 'vision_step/image')])]


def start_turtlesim(context):
    """Return turtlesim_node where turtlesim is installed, else a line saying it is not."""
    try:
        get_package_share_directory('turtlesim')
    except PackageNotFoundError:
        return [LogInfo(msg='turtlesim is not installed: not started; the Twists still go '
                            'out on /turtle1/cmd_vel (install ros-<distro>-turtlesim to see '
                            'the turtle move)')]
    return [Node(package='turtlesim', executable='turtlesim_node', output='screen')]


def generate_launch_description():
    """Declare the arguments, include the camera, start the step, the viewer and turtlesim."""
    return LaunchDescription([
        DeclareLaunchArgument(
            'params_file', description='parameter file of the py_vision nodes',
            default_value=PathJoinSubstitution(
                [FindPackageShare('py_vision'), 'config', 'params.yaml'])),
        *[DeclareLaunchArgument(name, default_value='',
                                description='%s (empty: the value in params_file)' % meaning)
          for name, (_, meaning) in VIEWER_ARGUMENTS.items()],
        IncludeLaunchDescription(PythonLaunchDescriptionSource(PathJoinSubstitution(
            [FindPackageShare('py_vision'), 'launch', 'camera.launch.py']))),
        Node(package='py_vision', executable='vision_step', output='screen',
             parameters=[LaunchConfiguration('params_file'), {'step': 'hand_signs'}]),
        OpaqueFunction(function=start_viewer),
        OpaqueFunction(function=start_turtlesim),
    ])
