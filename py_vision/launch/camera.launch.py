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
Start the camera publisher with the shipped parameters (config/params.yaml).

    ros2 launch py_vision camera.launch.py video_device:=synthetic framerate:=15.0
    ros2 launch py_vision camera.launch.py video_device:=synthetic managed:=true
    ros2 launch py_vision camera.launch.py --show-args

A launch argument left empty keeps the value in params_file; a given one reaches the node with
the type the node declares, so video_device:=0 is the string '0' (camera index 0) and
framerate:=15 the number 15.0.

managed:=true starts the publisher as a lifecycle node (launch_ros's LifecycleNode) and, with
autostart:=true (the default), configures it and activates it once configured; with
autostart:=false it waits unconfigured for a lifecycle manager or `ros2 lifecycle set`.
"""

from launch import LaunchDescription
from launch.actions import (
    DeclareLaunchArgument, EmitEvent, OpaqueFunction, RegisterEventHandler)
from launch.events import matches_action
from launch.substitutions import LaunchConfiguration, PathJoinSubstitution
from launch_ros.actions import LifecycleNode, Node
from launch_ros.event_handlers import OnStateTransition
from launch_ros.events.lifecycle import ChangeState
from launch_ros.parameter_descriptions import ParameterValue
from launch_ros.substitutions import FindPackageShare
from lifecycle_msgs.msg import Transition

# The publisher parameters that are launch arguments: name -> (type the node takes, meaning).
CAMERA_ARGUMENTS = {
    'video_device': (str, 'V4L2 device path, camera index (0), video file or synthetic'),
    'image_width': (int, 'requested frame width in pixels'),
    'image_height': (int, 'requested frame height in pixels'),
    'framerate': (float, 'frames per second'),
    'pixel_format': (str, 'what the camera sends: auto, or a FourCC --list-formats prints'),
}


def start_publisher(context):
    """Return the publisher with params_file and the parameters given as launch arguments."""
    given = {name: ParameterValue(LaunchConfiguration(name), value_type=kind)
             for name, (kind, _) in CAMERA_ARGUMENTS.items()
             if LaunchConfiguration(name).perform(context)}
    if LaunchConfiguration('managed').perform(context) != 'true':
        return [Node(package='py_vision', executable='usbcam_publisher', output='screen',
                     parameters=[LaunchConfiguration('params_file'), given])]
    given['managed'] = True
    camera = LifecycleNode(package='py_vision', executable='usbcam_publisher', output='screen',
                           name='usbcam_publisher', namespace='',
                           parameters=[LaunchConfiguration('params_file'), given])
    if LaunchConfiguration('autostart').perform(context) != 'true':
        return [camera]

    def transition(transition_id):
        return EmitEvent(event=ChangeState(lifecycle_node_matcher=matches_action(camera),
                                           transition_id=transition_id))
    # Activate once configure has succeeded (not after a later deactivate).
    activate_when_configured = RegisterEventHandler(OnStateTransition(
        target_lifecycle_node=camera, start_state='configuring', goal_state='inactive',
        entities=[transition(Transition.TRANSITION_ACTIVATE)]))
    return [activate_when_configured, camera, transition(Transition.TRANSITION_CONFIGURE)]


def generate_launch_description():
    """Declare the arguments and start the publisher."""
    arguments = [DeclareLaunchArgument(
        'params_file', description='parameter file of the py_vision nodes',
        default_value=PathJoinSubstitution(
            [FindPackageShare('py_vision'), 'config', 'params.yaml']))]
    arguments += [
        DeclareLaunchArgument(name, default_value='',
                              description='%s (empty: the value in params_file)' % meaning)
        for name, (_, meaning) in CAMERA_ARGUMENTS.items()]
    arguments += [
        DeclareLaunchArgument('managed', default_value='false', choices=['true', 'false'],
                              description='start the publisher as a lifecycle node'),
        DeclareLaunchArgument('autostart', default_value='true', choices=['true', 'false'],
                              description='with managed:=true, configure and activate it at '
                                          'once (false: leave it unconfigured)')]
    return LaunchDescription(arguments + [OpaqueFunction(function=start_publisher)])
