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
usbcam_publisher on emulated UVC cameras: OpenCV's real V4L2 backend and py_vision's ioctls.

What a user with a USB camera sees: the size and rate the camera offers nearest to the request,
YUYV frames exact, MJPEG passed through as the camera's own bytes, an unplug and a replug under
another /dev/video node followed through the by-id link with the controls set again, a stall
handled as a loss instead of a hang, corrupt JPEGs never published, one-line errors for a busy
device, a denied one and one that is not a camera, and never a raw OpenCV line. The cameras are
docs/emulated_cameras.md's; the faults are injected from here.
"""

import json
import os
from pathlib import Path
import re
import subprocess
import sys
import time

import cv2
from emulated_camera import expected_yuyv, HERE, jpeg_digest
import numpy as np
from py_vision.capture import Camera, SyntheticDevices
from py_vision.capture.synthetic_picture import read_frame_index
import pytest
from ros_harness import installed_env, wait_until
from sensor_msgs.msg import CompressedImage, Image

LOG_LINE = ('[INFO]', '[WARN]', '[ERROR]')


def start(launch, camera, ros_env, **params):
    params.setdefault('video_device', camera.device)
    return launch('usbcam_publisher', params=params, env=camera.env(ros_env))


def own_words_only(node):
    """Assert that every line the node printed is its own log line (no raw OpenCV line)."""
    raw = [line for line in node.output().splitlines()
           if line.strip() and not line.startswith(LOG_LINE)]
    assert not raw, "lines that are not the node's own:\n%s" % '\n'.join(raw)


def image_of(msg):
    return np.frombuffer(msg.data, np.uint8).reshape(msg.height, msg.width, 3)


def test_the_nearest_size_and_rate_the_camera_offers_and_exact_yuyv_frames(
        launch, peer, emulated_camera, ros_env):
    camera = emulated_camera(model='vga_yuyv')   # YUYV only, at most 640x480, 30 or 15 fps
    frames = peer.collect(Image, 'usb_camera/image')
    node = start(launch, camera, ros_env, image_width=1280, image_height=720, framerate=25.0)
    node.wait_for_output(r'opened %s: 640x480 YUYV at 30 fps \(1280x720 at 25 fps requested: '
                         r'the nearest the camera offers\)' % camera.device, 30)
    wait_until(lambda: len(frames) >= 5, 30, what='5 frames')
    for msg in list(frames)[:5]:
        image = image_of(msg)
        index = read_frame_index(image)
        assert index is not None
        # OpenCV's V4L2 backend converts the camera's YUYV buffer exactly.
        assert np.array_equal(image, cv2.cvtColor(expected_yuyv(index, 640, 480),
                                                  cv2.COLOR_YUV2BGR_YUYV))
    own_words_only(node)


def index_of_jpeg(data):
    image = cv2.imdecode(np.frombuffer(data, np.uint8), cv2.IMREAD_COLOR)
    return None if image is None else read_frame_index(image)


def test_mjpeg_is_the_cameras_own_jpeg_published_untouched(
        launch, peer, emulated_camera, ros_env):
    camera = emulated_camera()   # webcam_1080p
    compressed = peer.collect(CompressedImage, 'usb_camera/image/compressed')
    node = start(launch, camera, ros_env, image_width=1280, image_height=720, framerate=30.0)
    node.wait_for_output('opened %s: 1280x720 MJPG at 30 fps, publishing' % camera.device, 30)
    wait_until(lambda: len(compressed) >= 10, 30, what='10 compressed frames')
    indexes = []
    for msg in list(compressed)[:10]:
        data = bytes(msg.data)
        index = index_of_jpeg(data)
        assert index is not None
        # Byte for byte the JPEG the camera served as that frame (its length and CRC-32).
        assert jpeg_digest(data) == camera.served_jpeg_digest(index), index
        indexes.append(index)
    assert indexes == sorted(set(indexes))
    assert node.stop() == 0
    assert 'camera released after' in node.output()
    assert re.search(r'\(0 raw, \d+ compressed published; 0 JPEG encoded, 0 decoded\)',
                     node.output())
    own_words_only(node)


def test_a_camera_plugged_back_elsewhere_is_found_by_id_with_its_controls(
        launch, peer, emulated_camera, ros_env):
    camera = emulated_camera()
    frames = peer.collect(Image, 'usb_camera/image')
    # native: each image published is the camera's own buffer, which the node must let go.
    node = start(launch, camera, ros_env, video_device=camera.by_id, framerate=30.0,
                 brightness=200, auto_white_balance=False, white_balance=3000,
                 output_encoding='native')
    # The node streams only once the controls it was given are set on the camera ('opened'
    # is logged before that), so its first frame is the moment to read them.
    wait_until(lambda: frames, 30, what='frames')
    assert (camera.control('brightness'), camera.control('white_balance_automatic'),
            camera.control('white_balance_temperature')) == (200, 0, 3000)
    camera.unplug()
    node.wait_for_output('lost %s' % camera.by_id, 30)
    # Released: none of its buffers stays mapped (a kernel driver frees the device's number
    # only then, and a camera plugged back comes back under it).
    maps = Path('/proc', str(node.pid), 'maps')
    wait_until(lambda: 'memfd:uvc-emulator' not in maps.read_text(), 10,
               what="the unplugged camera's buffers unmapped")
    camera.replug(node=camera.node + 2)   # another /dev/video node; by-id follows
    assert camera.control('brightness') == camera.control_info('brightness')['default']
    node.wait_for_output('is back after', 30)
    # The controls were set again on the camera, which had come back with its defaults.
    assert (camera.control('brightness'), camera.control('white_balance_automatic'),
            camera.control('white_balance_temperature')) == (200, 0, 3000)
    count = len(frames)
    wait_until(lambda: len(frames) > count + 5, 30, what='frames after the replug')
    stamps = [msg.header.stamp.sec * 10**9 + msg.header.stamp.nanosec for msg in frames]
    assert stamps == sorted(stamps)
    own_words_only(node)


def test_a_stall_is_a_loss_noticed_in_seconds_and_no_old_frame_follows(
        launch, peer, emulated_camera, ros_env):
    camera = emulated_camera()
    frames = peer.collect(Image, 'usb_camera/image')
    node = start(launch, camera, ros_env, framerate=30.0)
    node.wait_for_output('opened', 30)
    wait_until(lambda: len(frames) >= 5, 30, what='frames')
    camera.stall()
    stalled_at = time.monotonic()
    node.wait_for_output(r'sent no frame for [\d.]+ s \(stalled\)', 30)
    # OpenCV alone waits 10 s for each frame of a stalled camera.
    assert time.monotonic() - stalled_at < 8.0
    before = [read_frame_index(image_of(msg)) for msg in frames]
    camera.resume()
    node.wait_for_output('is back after', 30)
    count = len(frames)
    wait_until(lambda: len(frames) > count + 5, 30, what='frames after the stall')
    after = [read_frame_index(image_of(msg)) for msg in list(frames)[count:]]
    assert min(after) > max(before)
    own_words_only(node)


def test_corrupt_jpegs_are_counted_and_never_published(launch, peer, emulated_camera, ros_env):
    camera = emulated_camera(model='corrupt_mjpeg')   # every 5th JPEG broken, three ways
    compressed = peer.collect(CompressedImage, 'usb_camera/image/compressed')
    raw = peer.collect(Image, 'usb_camera/image')
    node = start(launch, camera, ros_env, pixel_format='mjpeg', framerate=30.0)
    node.wait_for_output('opened', 30)
    wait_until(lambda: len(compressed) >= 30 and len(raw) >= 30, 60, what='30 frames each')
    node.wait_for_output(r'sent a corrupt frame \(1 so far\); skipped, never published', 10)
    published = [bytes(msg.data) for msg in compressed]
    for data in published:
        index = index_of_jpeg(data)
        assert index is not None and jpeg_digest(data) == camera.served_jpeg_digest(index)
    broken = {(jpeg.length, jpeg.digest) for jpeg in camera.served_jpegs() if jpeg.corrupt}
    assert broken   # the camera did send broken ones (the log says so)
    assert not broken & {jpeg_digest(data) for data in published}
    for msg in list(raw):
        assert read_frame_index(image_of(msg)) is not None
    own_words_only(node)   # nor a line of libjpeg's


@pytest.mark.parametrize('fault,words', [
    ('busy', 'the device is busy (another program is streaming from it)'),
    ('denied', 'permission denied (add the user to the "video" group'),
    ('not a camera', 'not a video capture device'),
])
def test_a_camera_that_cannot_be_used_is_one_line_and_status_1(
        launch, emulated_camera, ros_env, fault, words):
    camera = emulated_camera(model='vga_yuyv')
    device = '/dev/null' if fault == 'not a camera' else camera.device
    if fault == 'denied':
        camera.deny()
    if fault == 'busy':
        with camera.busy():
            node = start(launch, camera, ros_env, video_device=device)
            status = node.wait_exit(30)
    else:
        node = start(launch, camera, ros_env, video_device=device)
        status = node.wait_exit(30)
    lines = [line for line in node.output().splitlines() if line.strip()]
    assert status == 1 and len(lines) == 1, node.output()
    assert 'cannot open video_device "%s": %s' % (device, words) in lines[0]


# Requests both cameras offer (the synthetic one also scales to any size and, in MJPEG, takes
# any rate): the synthetic model must negotiate them as the emulated USB 2.0 webcam does.
AGREEMENT = [(640, 480, 30.0, 'auto'), (1280, 720, 30.0, 'auto'), (1920, 1080, 15.0, 'auto'),
             (1280, 720, 30.0, 'yuyv'), (1920, 1080, 30.0, 'yuyv'), (800, 600, 30.0, 'yuyv'),
             (320, 240, 25.0, 'mjpg'), (1280, 720, 10.0, 'auto'), (160, 120, 5.0, 'auto')]
NEGOTIATE = """
import json, sys
from py_vision.capture import Camera
for width, height, fps, fmt in json.loads(sys.argv[2]):
    camera = Camera.open(sys.argv[1], width, height, fps, fmt)
    print(json.dumps([camera.pixel_format.fourcc, camera.width, camera.height, camera.fps,
                      camera.notes]))
    camera.release()
"""


def negotiated(camera):
    return [json.loads(line) for line in subprocess.run(
        [sys.executable, '-c', NEGOTIATE, camera.device, json.dumps(AGREEMENT)],
        env=camera.env(dict(installed_env(), PYTHONPATH=os.pathsep.join(
            [str(HERE), installed_env().get('PYTHONPATH', '')]))),
        capture_output=True, text=True, timeout=60, check=True).stdout.splitlines()]


def test_the_synthetic_camera_negotiates_as_the_emulated_webcam_does(emulated_camera):
    emulated = negotiated(emulated_camera())
    devices = SyntheticDevices()
    for (width, height, fps, fmt), got in zip(AGREEMENT, emulated):
        synthetic = Camera.open('synthetic', width, height, fps, fmt, synthetic=devices)
        assert [synthetic.pixel_format.fourcc, synthetic.width, synthetic.height,
                synthetic.fps, synthetic.notes] == got, (width, height, fps, fmt)
        synthetic.release()
    assert len(emulated) == len(AGREEMENT)
