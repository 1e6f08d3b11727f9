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

"""CameraInfo, calibration files, set_camera_info and camera controls, through the nodes."""

import cv2
import numpy as np
from param_client import set_parameter
from py_vision.calibration import load_calibration
import pytest
from rclpy.qos import QoSProfile, ReliabilityPolicy
import ros_harness
from ros_harness import wait_until
from sensor_msgs.msg import CameraInfo, CompressedImage, Image
from sensor_msgs.srv import SetCameraInfo

RELIABLE = QoSProfile(depth=100, reliability=ReliabilityPolicy.RELIABLE)
EXAMPLE = 'package://py_vision/config/example_calibration.yaml'


def stamp(msg):
    return (msg.header.stamp.sec, msg.header.stamp.nanosec, msg.header.frame_id)


def mean_luma(msg):
    image = np.frombuffer(msg.data, np.uint8).reshape(msg.height, msg.width, 3)
    return float(cv2.cvtColor(image, cv2.COLOR_BGR2GRAY).mean())


@pytest.fixture
def ros_home(ros_env, tmp_path):
    """Keep the nodes' default calibration folder in the test's own directory."""
    ros_env['ROS_HOME'] = str(tmp_path / 'ros_home')
    return tmp_path / 'ros_home'


def test_the_calibration_is_in_every_camera_info_paired_with_its_image(launch, peer, ros_home):
    images = peer.collect(Image, 'usb_camera/image', RELIABLE)
    jpegs = peer.collect(CompressedImage, 'usb_camera/image/compressed', RELIABLE)
    infos = peer.collect(CameraInfo, 'usb_camera/camera_info', RELIABLE)
    launch('usbcam_publisher', {'video_device': 'synthetic', 'framerate': 20.0,
                                'camera_info_url': EXAMPLE, 'frame_id': 'cam'})
    wait_until(lambda: len(images) >= 10 and len(jpegs) >= 10, 30, what='frames')
    path = ros_harness.installed_env()['AMENT_PREFIX_PATH'].split(':')[0]
    _, expected = load_calibration(path + '/share/py_vision/config/example_calibration.yaml')
    wait_until(lambda: len(infos) >= 12, 20, what='CameraInfo')
    frames = list(images) + list(jpegs)
    by_stamp = {stamp(info): info for info in list(infos)}
    # The three subscriptions are discovered one by one: pair the frames from the first
    # CameraInfo received to the last.
    first, last = min(by_stamp), max(by_stamp)
    paired = [m for m in frames if first <= stamp(m) <= last]
    assert len(paired) >= 10, 'too few frames while CameraInfo arrived'
    for msg in paired:
        info = by_stamp.get(stamp(msg))
        assert info is not None, 'no CameraInfo with the header of the frame at %s' % (
            stamp(msg),)
        assert (info.width, info.height) == (640, 480)
        assert info.distortion_model == 'plumb_bob'
        for field in ('k', 'd', 'r', 'p'):
            assert np.allclose(getattr(info, field), getattr(expected, field)), field


def test_uncalibrated_camera_info_has_the_size_and_zero_matrices(launch, peer, ros_home):
    infos = peer.collect(CameraInfo, 'usb_camera/camera_info', RELIABLE)
    publisher = launch('usbcam_publisher', {'video_device': 'synthetic', 'framerate': 20.0,
                                            'image_width': 320, 'image_height': 240})
    wait_until(lambda: infos, 30, what='a CameraInfo')
    info = infos[-1]
    assert (info.width, info.height) == (320, 240)
    assert not any(info.k) and not any(info.p) and not any(info.d)
    assert 'uncalibrated' in publisher.output()


@pytest.mark.parametrize('content,words', [
    ('image_width: 640\nimage_height: [480\n', 'line'),
    ('image_width: 640\n', 'missing key image_height'),
])
def test_a_bad_calibration_file_is_one_warning_and_the_camera_goes_on(
        launch, peer, ros_home, tmp_path, content, words):
    path = tmp_path / 'bad.yaml'
    path.write_text(content)
    images = peer.collect(Image, 'usb_camera/image', RELIABLE)
    publisher = launch('usbcam_publisher', {'video_device': 'synthetic', 'framerate': 20.0,
                                            'camera_info_url': 'file://%s' % path})
    wait_until(lambda: len(images) >= 3, 30, what='frames despite the bad file')
    warnings = [line for line in publisher.output().splitlines() if 'WARN' in line]
    assert len(warnings) == 1 and words in warnings[0] and str(path) in warnings[0]
    assert 'Traceback' not in publisher.output()


def test_a_calibration_for_another_size_is_not_published(launch, peer, ros_home):
    infos = peer.collect(CameraInfo, 'usb_camera/camera_info', RELIABLE)
    publisher = launch('usbcam_publisher', {'video_device': 'synthetic', 'framerate': 20.0,
                                            'image_width': 320, 'image_height': 240,
                                            'camera_info_url': EXAMPLE})
    wait_until(lambda: len(infos) >= 3, 30, what='CameraInfo')
    assert not any(infos[-1].k) and (infos[-1].width, infos[-1].height) == (320, 240)
    assert '640x480' in publisher.output() and '320x240' in publisher.output()


def test_set_camera_info_stores_a_file_that_reloads_and_is_published_at_once(
        launch, peer, ros_home, tmp_path):
    target = tmp_path / 'new' / 'dir' / 'calibration.yaml'
    infos = peer.collect(CameraInfo, 'usb_camera/camera_info', RELIABLE)
    params = {'video_device': 'synthetic', 'framerate': 20.0,
              'camera_info_url': 'file://%s' % target}
    publisher = launch('usbcam_publisher', params)
    wait_until(lambda: infos, 30, what='a CameraInfo')
    new = CameraInfo(width=640, height=480, distortion_model='plumb_bob')
    new.k = [500.0, 0.0, 320.0, 0.0, 501.0, 240.0, 0.0, 0.0, 1.0]
    new.d = [0.1, -0.2, 0.001, 0.002, 0.0]
    new.r = [1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0]
    new.p = [505.0, 0.0, 321.0, 0.0, 0.0, 506.0, 241.0, 0.0, 0.0, 0.0, 1.0, 0.0]
    client = peer.node.create_client(SetCameraInfo, '/usb_camera/set_camera_info')
    assert client.wait_for_service(timeout_sec=20)
    future = client.call_async(SetCameraInfo.Request(camera_info=new))
    wait_until(future.done, 20, what='the set_camera_info answer')
    assert future.result().success, future.result().status_message
    wait_until(lambda: list(infos[-1].k) == list(new.k), 10, what='the new calibration')
    assert target.is_file()
    assert publisher.stop() == 0
    infos.clear()
    launch('usbcam_publisher', params, name='usbcam_publisher_again')
    wait_until(lambda: infos, 30, what='a CameraInfo after the restart')
    for field in ('k', 'd', 'r', 'p'):
        assert list(getattr(infos[-1], field)) == list(getattr(new, field)), field


def test_set_camera_info_refuses_a_package_url_with_the_reason(launch, peer, ros_home):
    launch('usbcam_publisher', {'video_device': 'synthetic', 'camera_info_url': EXAMPLE})
    client = peer.node.create_client(SetCameraInfo, '/usb_camera/set_camera_info')
    assert client.wait_for_service(timeout_sec=20)
    future = client.call_async(SetCameraInfo.Request(camera_info=CameraInfo(
        width=640, height=480, k=[1.0, 0.0, 1.0, 0.0, 1.0, 1.0, 0.0, 0.0, 1.0],
        p=[1.0, 0.0, 1.0, 0.0, 0.0, 1.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0])))
    wait_until(future.done, 20, what='the set_camera_info answer')
    assert not future.result().success
    assert 'package://' in future.result().status_message


def test_controls_change_the_frames_live_and_survive_a_reconnect(launch, peer):
    images = peer.collect(Image, 'usb_camera/image', RELIABLE)
    publisher = launch('usbcam_publisher', {
        'video_device': 'synthetic?stop_after=60&unplugged_for=1', 'framerate': 20.0,
        'pixel_format': 'yuyv'})
    wait_until(lambda: len(images) >= 3, 30, what='frames')
    before = mean_luma(images[-1])
    assert set_parameter(peer, 'usbcam_publisher', 'brightness', 50).successful
    wait_until(lambda: mean_luma(images[-1]) > before + 25, 10, what='brighter frames')
    publisher.wait_for_output('publishing resumes', 30)
    count = len(images)
    wait_until(lambda: len(images) >= count + 3, 20, what='frames after the reconnect')
    assert mean_luma(images[-1]) > before + 25, 'brightness lost in the reconnect'


def test_a_control_the_camera_lacks_or_a_value_out_of_its_range_is_refused(
        launch, peer, tmp_path):
    publisher = launch('usbcam_publisher', {'video_device': 'synthetic', 'brightness': 100,
                                            'framerate': 20.0})
    publisher.wait_for_output('opened synthetic', 20)
    line = publisher.wait_for_output(r'.*brightness: 100 is out of the camera.*', 10).group(0)
    assert 'WARN' in line and '-64..64' in line
    # The parameter has the camera's range: ROS itself refuses a value outside it.
    result = set_parameter(peer, 'usbcam_publisher', 'brightness', 80)
    assert not result.successful and 'out of range' in result.reason
    assert set_parameter(peer, 'usbcam_publisher', 'brightness', 10).successful
    result = set_parameter(peer, 'usbcam_publisher', 'brightness', 'bright')
    assert not result.successful

    path = str(tmp_path / 'clip.avi')
    writer = cv2.VideoWriter(path, cv2.VideoWriter_fourcc(*'MJPG'), 10.0, (64, 48))
    for _ in range(3):
        writer.write(np.zeros((48, 64, 3), np.uint8))
    writer.release()
    publisher.stop()
    files = launch('usbcam_publisher', {'video_device': path, 'gain': 5}, name='file_publisher')
    files.wait_for_output('gain: %s has no such control; the value is not used' % path, 20)
    result = set_parameter(peer, 'usbcam_publisher', 'gain', 5)
    assert not result.successful   # a file has no controls: no such parameter
