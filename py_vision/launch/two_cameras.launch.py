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
Start two cameras, each named by its /dev/v4l/by-id link and in a namespace of its own.

    ros2 launch py_vision two_cameras.launch.py \
        front_device:=/dev/v4l/by-id/usb-046d_HD_Pro_Webcam_C920_A1B2C3D4-video-index0 \
        rear_device:=/dev/v4l/by-id/usb-Generic_USB2.0_Camera_0001-video-index0

`usbcam_publisher --list-devices` prints each camera's by-id link. A by-id link names the
camera wherever it is plugged and whatever /dev/videoN it gets, so the front camera stays
/front/usb_camera/image after a reboot; the rear one publishes /rear/usb_camera/image. Each
is camera.launch.py in its namespace, with the other camera arguments shared (two cameras on
one USB 2.0 bus: pixel_format mjpeg or h264, docs/cameras.md).
"""

from launch import LaunchDescription
from launch.actions import (
    DeclareLaunchArgument, GroupAction, IncludeLaunchDescription)
from launch.launch_description_sources import PythonLaunchDescriptionSource
from launch.substitutions import LaunchConfiguration, PathJoinSubstitution
from launch_ros.actions import PushRosNamespace
from launch_ros.substitutions import FindPackageShare

# The cameras' devices: launch argument -> (type, meaning); the namespace is its first word.
DEVICE_ARGUMENTS = {
    'front_device': (str, 'the front camera (namespace front), by its /dev/v4l/by-id/ link'),
    'rear_device': (str, 'the rear camera (namespace rear), by its /dev/v4l/by-id/ link'),
}


def generate_launch_description():
    """Declare the two devices and start camera.launch.py for each in its namespace."""
    arguments = [DeclareLaunchArgument(
        'params_file', description='parameter file of the py_vision nodes',
        default_value=PathJoinSubstitution(
            [FindPackageShare('py_vision'), 'config', 'params.yaml']))]
    arguments += [DeclareLaunchArgument(name, description=meaning)
                  for name, (_, meaning) in DEVICE_ARGUMENTS.items()]
    groups = [
        GroupAction([
            PushRosNamespace(name.split('_')[0]),
            IncludeLaunchDescription(PythonLaunchDescriptionSource(PathJoinSubstitution(
                [FindPackageShare('py_vision'), 'launch', 'camera.launch.py'])),
                launch_arguments={'video_device': LaunchConfiguration(name),
                                  'params_file': LaunchConfiguration('params_file')}.items()),
        ])
        for name in DEVICE_ARGUMENTS]
    return LaunchDescription(arguments + groups)
