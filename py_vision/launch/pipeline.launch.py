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
Start the pipeline: camera publisher, cv_bridge_test, and the viewer watching its output.

    ros2 launch py_vision pipeline.launch.py video_device:=synthetic display:=web
    ros2 launch py_vision pipeline.launch.py display:=web web_host:=0.0.0.0

usb_camera/image -> cv_bridge_test (draws a red circle) -> cv_bridge_image -> usbcam_subscriber.
The camera's arguments are camera.launch.py's; display, web_host, web_port and web_token set
the viewer's parameters of those names (empty: the value in params_file). On a headless board,
web_host:=0.0.0.0 serves the camera panel to the network, behind a token (docs/panel.md).
"""

from launch import LaunchDescription
from launch.actions import DeclareLaunchArgument, IncludeLaunchDescription, OpaqueFunction
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
    """Return the subscriber, remapped to cv_bridge_image, with the viewer arguments given."""
    given = {name: ParameterValue(LaunchConfiguration(name), value_type=kind)
             for name, (kind, _) in VIEWER_ARGUMENTS.items()
             if LaunchConfiguration(name).perform(context)}
    return [Node(package='py_vision', executable='usbcam_subscriber', output='screen',
                 parameters=[LaunchConfiguration('params_file'), given],
                 remappings=[('usb_camera/image', 'cv_bridge_image')])]


def generate_launch_description():
    """Declare the arguments, include the camera, start the processing node and the viewer."""
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
        Node(package='py_vision', executable='cv_bridge_test', output='screen',
             parameters=[LaunchConfiguration('params_file')]),
        OpaqueFunction(function=start_viewer),
    ])
