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

"""The camera passthrough end to end, across processes, with the colcon-installed executables."""

import signal

import cv2
import numpy as np
from py_vision.capture.synthetic_picture import read_frame_index, synthetic_frame
import pytest
from rclpy.qos import QoSProfile, ReliabilityPolicy
from ros_harness import wait_until
from sensor_msgs.msg import Image

RELIABLE = QoSProfile(depth=100, reliability=ReliabilityPolicy.RELIABLE)


def as_image(msg):
    return np.frombuffer(msg.data, np.uint8).reshape(msg.height, msg.width, 3)


def stamp_ns(msg):
    return msg.header.stamp.sec * 10**9 + msg.header.stamp.nanosec


def test_synthetic_frames_arrive_intact_and_in_order(launch, peer):
    received = peer.collect(Image, 'usb_camera/image', RELIABLE)
    publisher = launch('usbcam_publisher', {'video_device': 'synthetic', 'framerate': 20.0})
    wait_until(lambda: len(received) >= 15, 30, what='15 frames')
    frames = list(received)
    for msg in frames:
        assert (msg.width, msg.height, msg.encoding) == (640, 480, 'bgr8')
        assert msg.step == 640 * 3 and len(msg.data) == 640 * 480 * 3
        assert msg.header.frame_id == 'usb_camera'
        assert msg.is_bigendian == 0
    stamps = [stamp_ns(m) for m in frames]
    assert all(b > a for a, b in zip(stamps, stamps[1:])), 'stamps must increase'
    indexes = [read_frame_index(as_image(m)) for m in frames]
    assert None not in indexes
    assert all(b > a for a, b in zip(indexes, indexes[1:])), 'frames out of order'
    for msg, index in zip(frames, indexes):
        expected = synthetic_frame(index, 640, 480)
        assert np.array_equal(as_image(msg), expected), 'frame %d differs' % index
    # Stamps are capture times: 20 fps frames are about 50 ms apart per index step.
    periods = [(stamps[i + 1] - stamps[i]) / (indexes[i + 1] - indexes[i])
               for i in range(len(frames) - 1)]
    assert 40e6 < float(np.median(periods)) < 60e6
    assert publisher.proc.poll() is None


def test_requested_size_and_frame_id_are_published(launch, peer):
    received = peer.collect(Image, 'usb_camera/image', RELIABLE)
    publisher = launch('usbcam_publisher', {
        'video_device': 'synthetic', 'image_width': 320, 'image_height': 240,
        'framerate': 30, 'frame_id': 'front_camera'})
    wait_until(lambda: len(received) >= 3, 30, what='frames')
    msg = received[-1]
    assert (msg.width, msg.height, msg.step, msg.header.frame_id) == (
        320, 240, 960, 'front_camera')
    assert np.array_equal(as_image(msg), synthetic_frame(read_frame_index(as_image(msg)),
                                                         320, 240))
    assert '320x240' in publisher.output()


def test_remapped_topic(launch, peer):
    received = peer.collect(Image, 'front/image_raw', RELIABLE)
    launch('usbcam_publisher', {'video_device': 'synthetic'},
           remaps={'usb_camera/image': 'front/image_raw'})
    wait_until(lambda: received, 30, what='a frame on the remapped topic')


def test_subscriber_reports_received_frames(launch):
    launch('usbcam_publisher', {'video_device': 'synthetic', 'framerate': 20.0})
    subscriber = launch('usbcam_subscriber', {'display': 'none', 'stats_period': 1.0})
    match = subscriber.wait_for_output(
        r'received (\d+) frames \(([\d.]+) fps\).* 640x480 bgr8 on /usb_camera/image', 30)
    assert int(match.group(1)) > 0 and float(match.group(2)) > 0


@pytest.mark.parametrize('publisher_reliability', ['reliable', 'best_effort'])
def test_subscriber_hears_either_publisher_reliability(launch, peer, publisher_reliability):
    # The subscriber starts first, as it often does: it must still match the publisher, and
    # be reliable exactly when the publisher is.
    subscriber = launch('usbcam_subscriber', {'display': 'none', 'stats_period': 1.0})
    subscriber.wait_for_output('no frames on /usb_camera/image', 20)
    launch('usbcam_publisher', {'video_device': 'synthetic', 'framerate': 20.0,
                                'reliability': publisher_reliability})
    subscriber.wait_for_output(r'received [1-9]\d* frames', 30)
    wanted = {'reliable': ReliabilityPolicy.RELIABLE,
              'best_effort': ReliabilityPolicy.BEST_EFFORT}[publisher_reliability]

    def subscription_reliability():
        infos = peer.node.get_subscriptions_info_by_topic('/usb_camera/image')
        return [i.qos_profile.reliability for i in infos if i.node_name == 'usbcam_subscriber']
    wait_until(lambda: subscription_reliability() == [wanted], 10, what='matching reliability')


def test_video_file_is_published_and_loops(launch, peer, tmp_path):
    path = str(tmp_path / 'clip.avi')
    writer = cv2.VideoWriter(path, cv2.VideoWriter_fourcc(*'MJPG'), 25.0, (160, 120))
    assert writer.isOpened()
    for i in range(8):
        frame = np.full((120, 160, 3), (i * 30, 255 - i * 30, 128), np.uint8)
        cv2.putText(frame, str(i), (50, 90), cv2.FONT_HERSHEY_SIMPLEX, 2, (255, 255, 255), 3)
        writer.write(frame)
    writer.release()
    capture = cv2.VideoCapture(path)
    decoded = []
    ok, frame = capture.read()
    while ok:
        decoded.append(frame)
        ok, frame = capture.read()
    capture.release()
    assert len(decoded) == 8

    received = peer.collect(Image, 'usb_camera/image', RELIABLE)
    launch('usbcam_publisher', {'video_device': path, 'framerate': 40.0})
    wait_until(lambda: len(received) >= 20, 30, what='20 frames of the looping file')
    images = [as_image(m) for m in received[:20]]
    assert all(m.width == 160 and m.height == 120 for m in received[:20])
    positions = [next(i for i, d in enumerate(decoded) if np.array_equal(d, image))
                 for image in images]
    # Published in file order, and past the end it starts again from the first frame.
    steps = [(b - a) % 8 for a, b in zip(positions, positions[1:])]
    assert all(step == 1 for step in steps), positions


def test_missing_device_is_one_clear_line_and_status_1(launch):
    publisher = launch('usbcam_publisher', {'video_device': '/dev/video_py_vision_missing'})
    assert publisher.wait_exit(20) == 1
    out = publisher.output()
    assert 'Traceback' not in out
    lines = [line for line in out.splitlines() if line.strip()]
    assert len(lines) == 1, out
    assert '/dev/video_py_vision_missing' in lines[0] and 'ERROR' in lines[0]


@pytest.mark.parametrize('sig', [signal.SIGINT, signal.SIGTERM])
def test_publisher_stops_cleanly_and_releases_the_camera(launch, sig):
    publisher = launch('usbcam_publisher', {'video_device': 'synthetic'})
    publisher.wait_for_output('opened synthetic', 20)
    assert publisher.stop(sig, timeout=3) == 0
    out = publisher.output()
    assert 'Traceback' not in out
    assert 'camera released' in out


@pytest.mark.parametrize('sig', [signal.SIGINT, signal.SIGTERM])
def test_subscriber_stops_cleanly(launch, sig):
    subscriber = launch('usbcam_subscriber', {'display': 'none', 'stats_period': 1.0})
    subscriber.wait_for_output('no frames', 20)
    assert subscriber.stop(sig, timeout=3) == 0
    assert 'Traceback' not in subscriber.output()


def test_window_display_falls_back_to_stats_without_gui(launch):
    launch('usbcam_publisher', {'video_device': 'synthetic', 'framerate': 20.0})
    subscriber = launch('usbcam_subscriber', {'display': 'window', 'stats_period': 1.0})
    line = subscriber.wait_for_output(r'.*display:=window is not possible: .*', 20).group(0)
    assert 'statistics only' in line
    subscriber.wait_for_output(r'received [1-9]\d* frames', 30)


def test_three_node_pipeline_from_the_readme(launch):
    launch('usbcam_publisher', {'video_device': 'synthetic', 'framerate': 20.0})
    launch('cv_bridge_test')
    subscriber = launch('usbcam_subscriber', {'display': 'none', 'stats_period': 1.0},
                        remaps={'usb_camera/image': 'cv_bridge_image'})
    subscriber.wait_for_output(r'received [1-9]\d* frames .* 640x480 bgr8 on /cv_bridge_image',
                               30)
