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
Two cameras on one USB 2.0 bus: the second stream has no room (ENOSPC at STREAMON).

The emulated cameras of one test share a bus: raw YUYV at 640x480 and 30 fps takes 3 x 1024
bytes of each 125 us microframe, and the host controller grants 6000 of them to such
streams: two do not fit; a compressed stream (1024) fits beside one.
"""

from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus
from rclpy.qos import QoSProfile, ReliabilityPolicy
from ros_harness import wait_until

RELIABLE = QoSProfile(depth=100, reliability=ReliabilityPolicy.RELIABLE)
FULL = ("streaming does not start (VIDIOC_STREAMON: the USB bus is full with another camera's "
        'stream); use pixel_format mjpg or h264, or a smaller size or rate (retrying)')


def camera_node(launch, camera, env, name, pixel_format='yuyv'):
    return launch('usbcam_publisher', params={
        'video_device': camera.by_id, 'pixel_format': pixel_format, 'framerate': 30.0},
        remaps={'__node': name, 'usb_camera/image': name + '/image'}, env=env)


def test_a_second_stream_without_room_says_why_in_one_line_and_starts_when_there_is_room(
        launch, emulated_camera, ros_env, peer):
    first = emulated_camera(model='webcam_1080p', node=41)
    second = emulated_camera(model='vga_yuyv', node=43)
    env = second.env(first.env(ros_env))
    arrays = peer.collect(DiagnosticArray, '/diagnostics', RELIABLE)
    front = camera_node(launch, first, env, 'front')
    front.wait_for_output(r'opened .*640x480 YUYV at 30 fps', 30)
    wait_until(lambda: first.frames_served > 0, 20, what='the first camera streaming')

    rear = camera_node(launch, second, env, 'rear')
    rear.wait_for_output(r'WARN.*cannot stream from video_device "%s": %s' % (
        second.by_id, FULL.replace('(', r'\(').replace(')', r'\)')), 30)
    assert second.frames_served == 0

    # /diagnostics says it, as an error of the rear camera.
    def rear_status():
        for array in list(arrays):
            for status in array.status:
                if status.name == 'rear: camera' and status.level == DiagnosticStatus.ERROR:
                    return status
        return None
    status = wait_until(rear_status, 20, 0.1, 'the rear camera ERROR on /diagnostics')
    assert FULL in status.message
    assert {kv.key: kv.value for kv in status.values}['waiting'] == status.message
    # It keeps trying (with back-off, saying so now and then), and never exits.
    assert rear.proc.poll() is None

    # The front camera stops: the rear one gets the bus.
    assert front.stop() == 0
    rear.wait_for_output(r'streams after \d+ attempt\(s\): the bus has room again', 30)
    wait_until(lambda: second.frames_served > 0, 20, what='the second camera streaming')
    warnings = [line for line in rear.output().splitlines() if 'the USB bus is full' in line]
    assert 1 <= len(warnings) <= 3, warnings
    assert rear.stop() == 0
    assert 'Traceback' not in rear.output()


def test_a_compressed_stream_fits_beside_a_raw_one(launch, emulated_camera, ros_env):
    first = emulated_camera(model='webcam_1080p', node=41)
    second = emulated_camera(model='h264_webcam', node=43)
    env = second.env(first.env(ros_env))
    front = camera_node(launch, first, env, 'front')
    wait_until(lambda: first.frames_served > 0, 20, what='the raw stream')
    for pixel_format, name in (('mjpg', 'rear'), ('h264', 'rear_h264')):
        rear = camera_node(launch, second, env, name, pixel_format)
        served = second.frames_served
        wait_until(lambda: second.frames_served > served + 5, 20,
                   what='the %s stream beside the raw one' % pixel_format)
        assert rear.stop() == 0
        assert 'the USB bus is full' not in rear.output()
    # Two reservations while both streamed; the front one alone now.
    assert len(first.bus_reservations()) == 1
    assert front.stop() == 0
