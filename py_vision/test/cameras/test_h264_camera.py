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
pixel_format:=h264 on an emulated H.264 UVC camera: the camera's access units, untouched.

The camera (`h264_webcam`) serves the recorded clip's access units, one per buffer, looping;
it records each unit it hands out (index, length, CRC-32). Where foxglove_msgs is not
installed (these test machines) the units go out as sensor_msgs/CompressedImage on
usb_camera/image/h264.
"""

import re
import statistics

from emulated_camera import jpeg_digest
import numpy as np
from py_vision.annexb import inspect
from py_vision.capture.synthetic_picture import read_frame_index
from py_vision.transport import CompressedVideo
from rclpy.qos import QoSProfile, ReliabilityPolicy
from ros_harness import wait_until
from sensor_msgs.msg import CompressedImage, Image
from video_clip import access_units, FRAMES, HEIGHT, KEYINT, WIDTH

RELIABLE = QoSProfile(depth=100, reliability=ReliabilityPolicy.RELIABLE)
VIDEO_TOPIC = '/usb_camera/image/' + ('foxglove' if CompressedVideo is not None else 'h264')
VIDEO_TYPE = CompressedVideo or CompressedImage
RATE = 30.0


def stamp_s(msg):
    stamp = msg.timestamp if CompressedVideo is not None else msg.header.stamp
    return stamp.sec + stamp.nanosec * 1e-9


def start(launch, emulated_camera, ros_env):
    camera = emulated_camera(model='h264_webcam', node=46)
    node = launch('usbcam_publisher', params={
        'video_device': camera.by_id, 'pixel_format': 'h264', 'framerate': RATE},
        env=camera.env(ros_env))
    node.wait_for_output(r'opened .*: 640x480 H264 at 30 fps, publishing on %s' % VIDEO_TOPIC,
                         30)
    return camera, node


def test_a_subscriber_gets_the_cameras_access_units_byte_for_byte_in_order(
        launch, emulated_camera, ros_env, peer):
    camera, node = start(launch, emulated_camera, ros_env)
    # It joins a stream that runs already, mid-way through a group of pictures.
    wait_until(lambda: camera.frames_served > FRAMES // 2 + 3, 20, what='the camera streaming')
    received = peer.collect(VIDEO_TYPE, VIDEO_TOPIC, RELIABLE)
    wait_until(lambda: len(received) >= 3 * KEYINT, 30, interval=0.05,
               what='%d access units' % (3 * KEYINT))
    messages = list(received)
    units = [bytes(msg.data) for msg in messages]
    clip = access_units()

    # Byte for byte the camera's own units: each is the one it served, in its order, none lost.
    served = {record.index: record.digest for record in camera.served_jpegs()}
    first = next(index for index in sorted(served) if clip[index % FRAMES] == units[0])
    for offset, unit in enumerate(units):
        index = first + offset
        assert jpeg_digest(unit) == (len(unit), served[index]), 'unit %d' % offset
        assert unit == clip[index % FRAMES]

    # A subscriber that joins gets the SPS and an IDR within a keyframe interval of its first
    # unit: well within 2 s of joining, by the camera's own clock (the stamps).
    starts = [offset for offset, unit in enumerate(units) if inspect(unit).decodable_start]
    assert starts and starts[0] < KEYINT, starts
    assert stamp_s(messages[starts[0]]) - stamp_s(messages[0]) < 2.0
    assert inspect(units[starts[0]]).nal_types[:4] == (9, 7, 8, 5)

    # Stamped with each buffer's capture time: one frame period apart.
    gaps = [stamp_s(b) - stamp_s(a) for a, b in zip(messages, messages[1:])]
    assert min(gaps) > 0
    assert abs(statistics.median(gaps) - 1 / RATE) < 0.2 / RATE, gaps
    assert {msg.header.frame_id if CompressedVideo is None else msg.frame_id
            for msg in messages} == {'usb_camera'}
    if CompressedVideo is None:
        assert {msg.format for msg in messages} == {'h264'}
    assert node.stop() == 0
    # Nobody subscribed to the images: nothing was decoded.
    assert re.search(r'camera released after \d+ frames \(\d+ H264 published; 0 decoded',
                     node.output()), node.output()


def test_the_image_topic_is_decoded_from_the_units_each_with_its_units_header(
        launch, emulated_camera, ros_env, peer):
    camera, node = start(launch, emulated_camera, ros_env)
    units = peer.collect(VIDEO_TYPE, VIDEO_TOPIC, RELIABLE)
    images = peer.collect(Image, '/usb_camera/image', RELIABLE)
    wait_until(lambda: len(images) >= KEYINT, 30, interval=0.05, what='decoded images')
    clip = access_units()
    by_stamp = {stamp_s(msg): bytes(msg.data) for msg in list(units)}
    checked = 0
    for image in list(images):
        assert (image.width, image.height, image.encoding) == (WIDTH, HEIGHT, 'bgr8')
        picture = np.frombuffer(image.data, np.uint8).reshape(HEIGHT, WIDTH, 3)
        index = read_frame_index(picture)
        stamp = image.header.stamp.sec + image.header.stamp.nanosec * 1e-9
        if stamp in by_stamp:
            # The picture is the one its own unit holds: the header went with the right unit.
            assert by_stamp[stamp] == clip[index], "a picture with another unit's header"
            checked += 1
    assert checked >= KEYINT // 2, 'too few images matched a unit by stamp (%d)' % checked
    assert node.stop() == 0
    assert 'Traceback' not in node.output()


def test_list_formats_lists_h264(launch, emulated_camera, ros_env):
    camera = emulated_camera(model='h264_webcam', node=46)
    node = launch('usbcam_publisher', params={'video_device': camera.by_id},
                  extra_args=['--list-formats'], env=camera.env(ros_env))
    assert node.wait_exit(20) == 0
    assert re.search(r'^H264 \(H.264\), compressed video: the camera\'s access units are '
                     r'published as they are \(pixel_format:=h264\)\n  640x480: 30, 15 fps$',
                     node.output(), re.MULTILINE), node.output()
