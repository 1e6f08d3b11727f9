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
py_vision's own V4L2 streaming (capture/v4l2_stream.py) on emulated UVC cameras.

Every raw format the pixel format table knows streams as the camera sends it (the bytes of
each buffer, exactly) and converts to the right picture; frames the buffers' sequence numbers
skip and buffers the driver flags as errors are counted on /diagnostics and never published;
stamps are the buffers' own capture times; a managed node's deactivate stops the stream and
keeps the device (another program gets EBUSY), activate resumes at once. The cameras are
docs/emulated_cameras.md's; what the library served is read back from the test.
"""

import errno
import json
import os
import subprocess
import sys

import cv2
from emulated_camera import expected_frame, expected_yuyv, HERE
from lifecycle_client import CameraStatus, Lifecycle, RELIABLE
from lifecycle_msgs.msg import Transition
import numpy as np
from py_vision.capture.synthetic_picture import read_frame_index
from py_vision.cv_bridge import CvBridge
import pytest
from ros_harness import installed_env, wait_until
from sensor_msgs.msg import CompressedImage, Image

SIZE = (320, 240)
BRIDGE = CvBridge()
CHILD = """
import json, sys, time
from py_vision.capture import Camera
from py_vision.capture.synthetic_picture import read_frame_index
device, formats = sys.argv[1], sys.argv[2].split(',')
for fourcc in formats:
    camera = Camera.open(device, 320, 240, 15.0, fourcc)
    camera.start()
    for _ in range(3):
        frame = camera.read()
        bgr = frame.image('bgr8')
        print(json.dumps({
            'fourcc': fourcc, 'got': camera.pixel_format.fourcc, 'notes': camera.notes,
            'index': read_frame_index(bgr), 'sequence': frame.index,
            'age': time.monotonic() - frame.capture_time, 'sent': frame.data.tobytes().hex(),
            'bgr': bgr.tobytes().hex(), 'native': frame.encoding('native')}), flush=True)
    camera.release()
"""


def camera_env(camera):
    env = camera.env(installed_env())
    env['PYTHONPATH'] = os.pathsep.join([str(HERE), env.get('PYTHONPATH', '')])
    return env


def expected_bgr(fourcc, index):
    """Return the picture a frame of this format shows: colour, or its luma for a grey one."""
    yuyv = expected_yuyv(index, *SIZE)
    if fourcc in ('GREY', 'Y16', 'Y10'):
        return cv2.cvtColor(yuyv[:, :, 0], cv2.COLOR_GRAY2BGR)
    return cv2.cvtColor(yuyv, cv2.COLOR_YUV2BGR_YUYV)


def test_every_raw_format_streams_as_the_camera_sends_it(emulated_camera):
    camera = emulated_camera(model='raw_formats')
    formats = [fmt['fourcc'] for fmt in camera.model['formats']]
    result = subprocess.run([sys.executable, '-c', CHILD, camera.device, ','.join(formats)],
                            env=camera_env(camera), capture_output=True, text=True,
                            timeout=120)
    assert result.returncode == 0, result.stderr[-3000:]
    frames = [json.loads(line) for line in result.stdout.splitlines()]
    assert [frame['fourcc'] for frame in frames] == [f for f in formats for _ in range(3)]
    for frame in frames:
        fourcc, index = frame['fourcc'], frame['index']
        assert (frame['got'], frame['notes']) == (fourcc, []), frame['notes']
        assert index is not None, '%s: no frame index in the picture' % fourcc
        # The buffer's bytes (bytesused of them), as the camera filled it: nothing more.
        assert bytes.fromhex(frame['sent']) == expected_frame(fourcc, index, *SIZE).tobytes(), \
            fourcc
        # Converted right: the colour bars and the grey ramp, within what sampling loses.
        bgr = np.frombuffer(bytes.fromhex(frame['bgr']), np.uint8).reshape(SIZE[1], SIZE[0], 3)
        error = np.abs(bgr.astype(int) - expected_bgr(fourcc, index)).mean()
        assert error < 2.0, '%s converts to a wrong picture (mean error %.1f)' % (fourcc, error)
        # Stamped with the buffer's own capture time (CLOCK_MONOTONIC), a moment ago.
        assert 0 <= frame['age'] < 1.0, fourcc
    natives = {frame['fourcc']: frame['native'] for frame in frames}
    assert natives == {'GREY': 'mono8', 'Y16': 'mono16', 'Y10': 'mono16', 'UYVY': 'yuv422',
                       'YVYU': 'bgr8', 'NV12': 'bgr8', 'NV21': 'nv21', 'YU12': 'bgr8',
                       'YV12': 'bgr8', 'NV24': 'nv24', 'RGB3': 'rgb8', 'BGR3': 'bgr8',
                       'BA81': 'bayer_bggr8', 'GBRG': 'bayer_gbrg8', 'GRBG': 'bayer_grbg8',
                       'RGGB': 'bayer_rggb8'}


USER_MEMORY = """
import json, sys
import numpy as np
from py_vision.capture import Camera
from py_vision.capture.synthetic_picture import read_frame_index
camera = Camera.open(sys.argv[1], 320, 240, 30.0, 'yuyv', 'native')
arrays = [np.zeros(camera.buffer_bytes, np.uint8) for _ in range(camera.buffer_count)]
assert camera.capture_into(arrays)
methods = [camera.io_method]
camera.start()
methods.append(camera.io_method)
for _ in range(6):
    frame = camera.read()
    while frame is None:   # a read that timed out on a loaded machine
        frame = camera.read()
    inside = [i for i, a in enumerate(arrays) if np.shares_memory(a, frame.data)]
    print(json.dumps({'user_buffer': frame.user_buffer, 'inside': inside,
                      'index': read_frame_index(frame.image('bgr8')),
                      'sent': frame.data.tobytes().hex()}), flush=True)
camera.release()
print(json.dumps({'io methods': methods + [camera.io_method]}))
"""


@pytest.mark.parametrize('no_userptr', [False, 'reqbufs', 'qbuf'])
def test_frames_are_captured_into_memory_the_program_gives(emulated_camera, no_userptr):
    # uvcvideo takes user memory (V4L2_MEMORY_USERPTR): the camera writes each frame where
    # the program wants it (the message it publishes); a driver without it (REQBUFS EINVAL),
    # or one that cannot use the memory it is given (QBUF EFAULT), streams into its own
    # buffers instead, the same frames.
    camera = emulated_camera(model='vga_yuyv', no_userptr=no_userptr)
    result = subprocess.run([sys.executable, '-c', USER_MEMORY, camera.device],
                            env=camera_env(camera), capture_output=True, text=True,
                            timeout=120)
    assert result.returncode == 0, result.stderr[-3000:]
    frames = [json.loads(line) for line in result.stdout.splitlines()]
    # What /diagnostics says: no buffers before start() and after release(), then which.
    assert frames.pop()['io methods'] == ['', 'mmap' if no_userptr else 'userptr', '']
    assert len(frames) == 6
    for frame in frames:
        assert frame['index'] is not None
        assert bytes.fromhex(frame['sent']) == expected_yuyv(frame['index'], *SIZE).tobytes()
        if no_userptr:
            assert (frame['user_buffer'], frame['inside']) == (None, [])
        else:
            assert frame['inside'] == [frame['user_buffer']]
    if not no_userptr:   # every buffer used in turn, none twice in a row
        buffers = [frame['user_buffer'] for frame in frames]
        assert len(set(buffers)) >= 2 and all(a != b for a, b in zip(buffers, buffers[1:]))


def start(launch, camera, ros_env, **params):
    params.setdefault('video_device', camera.device)
    return launch('usbcam_publisher', params=params, env=camera.env(ros_env))


def image_of(msg):
    return np.frombuffer(msg.data, np.uint8).reshape(msg.height, msg.width, 3)


# pixel_format, output_encoding: the format the camera sends, the encoding published.
OUTPUTS = [
    ('auto', 'bgr8', 'BGR3', 'bgr8'),        # no work at all
    ('grey', 'bgr8', 'GREY', 'bgr8'),
    ('NV12', 'bgr8', 'NV12', 'bgr8'),
    ('mono8', 'native', 'GREY', 'mono8'),     # usb_cam's name for GREY
    ('y16', 'native', 'Y16', 'mono16'),
    ('uyvy', 'native', 'UYVY', 'yuv422'),
    ('nv21', 'native', 'NV21', 'nv21'),
    ('rgb3', 'native', 'RGB3', 'rgb8'),
    ('ba81', 'native', 'BA81', 'bayer_bggr8'),
    ('nv12', 'native', 'NV12', 'bgr8'),       # sensor_msgs has no NV12: converted
    ('auto', 'native', 'UYVY', 'yuv422'),     # colour, with an encoding, no work
    ('auto', 'mono16', 'Y16', 'mono16'),      # the most bits
    ('nv12', 'rgb8', 'NV12', 'rgb8'),
]


@pytest.mark.parametrize('pixel_format,output,fourcc,encoding', OUTPUTS)
def test_a_camera_that_sends_neither_yuyv_nor_mjpeg_publishes_any_output(
        launch, peer, emulated_camera, ros_env, pixel_format, output, fourcc, encoding):
    camera = emulated_camera(model='raw_formats')
    frames = peer.collect(Image, 'usb_camera/image', RELIABLE)
    jpegs = peer.collect(CompressedImage, 'usb_camera/image/compressed', RELIABLE)
    node = start(launch, camera, ros_env, image_width=320, image_height=240, framerate=15.0,
                 pixel_format=pixel_format, output_encoding=output)
    node.wait_for_output('opened %s: 320x240 %s at 15 fps, publishing on /usb_camera/image%s'
                         % (camera.device, fourcc, '' if encoding == 'bgr8' else
                            ' as %s' % encoding), 30)
    wait_until(lambda: len(frames) >= 3 and jpegs, 30, what='3 frames and a JPEG')
    for msg in list(frames)[:3]:
        assert msg.encoding == encoding and (msg.width, msg.height) == SIZE
        bgr = BRIDGE.imgmsg_to_cv2(msg, 'bgr8')
        index = read_frame_index(bgr)
        assert index is not None
        if output == 'native' and encoding != 'bgr8':
            # The camera's bytes, unconverted.
            assert bytes(msg.data) == expected_frame(fourcc, index, *SIZE).tobytes()
        else:
            image = BRIDGE.imgmsg_to_cv2(msg)
            picture = expected_bgr(fourcc, index)
            if encoding == 'rgb8':
                picture = picture[:, :, ::-1]
            elif encoding in ('mono8', 'mono16'):
                picture = expected_yuyv(index, *SIZE)[:, :, 0]
                image = image // 257 if encoding == 'mono16' else image
            error = np.abs(image.astype(int) - picture).mean()
            assert error < 2.0, 'mean error %.1f' % error
    # The compressed topic: encoded from the same frames, in colour or grey as they are.
    jpeg = jpegs[0]
    grey = fourcc in ('GREY', 'Y16')
    assert jpeg.format == ('mono8; jpeg compressed mono8' if grey else
                           'bgr8; jpeg compressed bgr8')
    decoded = BRIDGE.compressed_imgmsg_to_cv2(jpeg, 'bgr8')
    assert read_frame_index(decoded) is not None


def stamp_s(msg):
    return msg.header.stamp.sec + msg.header.stamp.nanosec * 1e-9


@pytest.mark.parametrize('no_userptr', [False, 'reqbufs', 'qbuf'])
def test_native_frames_are_the_cameras_bytes_with_or_without_user_memory(
        launch, peer, emulated_camera, ros_env, no_userptr):
    # With user memory the node publishes the message the camera wrote into; without, a copy.
    camera = emulated_camera(model='vga_yuyv', no_userptr=no_userptr)
    frames = peer.collect(Image, 'usb_camera/image', RELIABLE)
    status = CameraStatus(peer)
    start(launch, camera, ros_env, image_width=320, image_height=240, framerate=30.0,
          output_encoding='native', frame_id='a_frame_id_longer_than_the_first')
    wait_until(lambda: len(frames) >= 8, 30, what='8 frames')
    _, values = status.wait_reports()
    assert values['io method'] == ('mmap' if no_userptr else 'userptr'), values
    indexes = []
    for msg in list(frames)[:8]:
        assert (msg.encoding, msg.width, msg.height, msg.step) == ('yuv422_yuy2', 320, 240, 640)
        assert msg.header.frame_id == 'a_frame_id_longer_than_the_first'
        index = read_frame_index(BRIDGE.imgmsg_to_cv2(msg, 'bgr8'))
        assert bytes(msg.data) == expected_yuyv(index, *SIZE).tobytes()
        indexes.append(index)
    assert indexes == sorted(set(indexes)), 'each frame once, in order'


def test_stamps_are_the_buffers_capture_times(launch, peer, emulated_camera, ros_env):
    camera = emulated_camera(model='vga_yuyv')
    frames = peer.collect(Image, 'usb_camera/image', RELIABLE)
    start(launch, camera, ros_env, framerate=30.0)
    wait_until(lambda: len(frames) >= 30, 30, what='30 frames')
    stamps = [stamp_s(msg) for msg in list(frames)[:30]]
    # The camera captures a frame every 1/30 s exactly: stamps of when the node read them
    # would wander by the machine's load; the buffers' own times do not.
    for earlier, later in zip(stamps, stamps[1:]):
        periods = (later - earlier) * 30.0
        assert round(periods) >= 1 and abs(periods - round(periods)) < 0.01, \
            (later - earlier)


def test_frames_the_sequence_skips_are_counted_as_dropped(
        launch, peer, emulated_camera, ros_env):
    camera = emulated_camera(model='vga_yuyv', drop_every=5)
    frames = peer.collect(Image, 'usb_camera/image', RELIABLE)
    status = CameraStatus(peer)
    start(launch, camera, ros_env, framerate=30.0)
    wait_until(lambda: len(frames) >= 20, 30, what='20 frames')
    status_now, values = status.wait_reports()
    assert int(values['dropped']) >= 3, values
    assert 'dropped lately' in status_now.message
    indexes = [read_frame_index(image_of(msg)) for msg in list(frames)[:20]]
    assert None not in indexes and not any(index % 5 == 4 for index in indexes)


def test_buffers_flagged_as_errors_are_dropped_and_counted(
        launch, peer, emulated_camera, ros_env):
    camera = emulated_camera(model='vga_yuyv', error_every=4)
    frames = peer.collect(Image, 'usb_camera/image', RELIABLE)
    status = CameraStatus(peer)
    node = start(launch, camera, ros_env, framerate=30.0)
    node.wait_for_output(r'delivered a frame flagged as an error \(1 so far\); dropped, never '
                         r'published', 30)
    wait_until(lambda: len(frames) >= 20, 30, what='20 frames')
    status_now, values = status.wait_reports()
    # An error buffer still has its sequence number: it is not a drop as well (a loaded
    # machine may drop one now and then).
    errors, dropped = int(values['error frames']), int(values['dropped'])
    assert errors >= 3 and dropped < errors / 2, values
    assert 'flagged as errors lately' in status_now.message
    indexes = [read_frame_index(image_of(msg)) for msg in list(frames)[:20]]
    assert None not in indexes and not any(index % 4 == 3 for index in indexes)


OTHER_PROCESS = """
import errno, sys
import v4l2_ioctl
fd = v4l2_ioctl.open_device(sys.argv[1])
try:
    v4l2_ioctl.set_format(fd, 'YUYV', 640, 480)
    print('granted')
except OSError as error:
    print(errno.errorcode[error.errno])
"""


def another_program_asks_for_it(camera):
    """Return what another process gets asking the camera for a format: granted, EBUSY..."""
    result = subprocess.run([sys.executable, '-c', OTHER_PROCESS, camera.device],
                            env=camera_env(camera), capture_output=True, text=True,
                            timeout=60)
    assert result.returncode == 0, result.stderr
    return result.stdout.strip()


def test_deactivate_stops_the_stream_and_keeps_the_device(
        launch, peer, emulated_camera, ros_env):
    camera = emulated_camera(model='vga_yuyv')
    frames = peer.collect(Image, 'usb_camera/image', RELIABLE)
    node = start(launch, camera, ros_env, framerate=30.0, managed=True)
    lifecycle = Lifecycle(peer)
    assert lifecycle.set(Transition.TRANSITION_CONFIGURE)
    assert lifecycle.set(Transition.TRANSITION_ACTIVATE)
    wait_until(lambda: len(frames) >= 5, 30, what='frames while active')
    assert lifecycle.set(Transition.TRANSITION_DEACTIVATE)
    node.wait_for_output('deactivated: streaming stopped after', 10)
    # The stream stopped: the camera fills no buffer any more.
    served = camera.frames_served
    status = CameraStatus(peer)
    status.wait_reports()
    assert camera.frames_served == served
    # The device is still the node's: another program cannot take it.
    assert another_program_asks_for_it(camera) == 'EBUSY'
    count = len(frames)
    assert lifecycle.set(Transition.TRANSITION_ACTIVATE)
    wait_until(lambda: len(frames) >= count + 5, 30, what='frames after activating again')
    assert node.output().count('opened %s' % camera.device) == 1   # never reopened
    assert lifecycle.set(Transition.TRANSITION_DEACTIVATE)
    assert lifecycle.set(Transition.TRANSITION_CLEANUP)
    # Released at cleanup: now another program may have it.
    wait_until(lambda: another_program_asks_for_it(camera) == 'granted', 20,
               what='the camera free after cleanup')


def test_a_stream_that_does_not_start_is_one_error_line_and_status_1(
        launch, emulated_camera, ros_env):
    # (ENOSPC, a USB bus without room, is waited out instead: test_usb_bus.)
    camera = emulated_camera(model='vga_yuyv', streamon_errno=errno.EIO)
    node = start(launch, camera, ros_env)
    assert node.wait_exit(30) == 1
    # The camera opened ('opened ...'); the stream's start is the one error, with the reason.
    errors = [line for line in node.output().splitlines() if 'ERROR' in line]
    assert len(errors) == 1 and 'Traceback' not in node.output(), node.output()
    assert 'cannot stream from video_device "%s": streaming does not start (VIDIOC_STREAMON: ' \
        '%s)' % (camera.device, os.strerror(errno.EIO)) in errors[0]
