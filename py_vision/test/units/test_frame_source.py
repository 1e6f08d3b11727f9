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


"""open_capture: what each kind of video_device opens, and the one-line errors."""

import os
import sys

import cv2
from fake_clock import FakeClock
import numpy as np
from py_vision.capture import camera as camera_module
from py_vision.capture import open_source, SourceError, SyntheticDevices
from py_vision.capture.synthetic_device import SyntheticCamera
from py_vision.capture.synthetic_picture import read_frame_index, synthetic_frame
from py_vision.capture.video_file import video_file_support, VideoFileSource
import pytest

linux_only = pytest.mark.skipif(not sys.platform.startswith('linux'),
                                reason='V4L2 device nodes exist on Linux only')


@pytest.fixture
def clock():
    return FakeClock()


@pytest.fixture
def paced(clock):
    """open_source with its pacing and its synthetic devices on the test's fake clock."""
    devices = SyntheticDevices(clock)

    def open_paced(video_device, width, height, fps):
        return open_source(video_device, width, height, fps, synthetic=devices, clock=clock)
    return open_paced


@pytest.fixture
def video(tmp_path):
    """Write a 6-frame 160 x 120 MJPG AVI at 25 fps whose frames carry indices 0..5."""
    path = tmp_path / 'clip.avi'
    writer = cv2.VideoWriter(str(path), cv2.VideoWriter_fourcc(*'MJPG'), 25.0, (160, 120))
    assert writer.isOpened(), 'this OpenCV cannot write MJPG AVI files'
    for index in range(6):
        writer.write(synthetic_frame(index, 160, 120))
    writer.release()
    return path


def open_error(video_device, paced=open_source):
    with pytest.raises(SourceError) as error:
        paced(video_device, 640, 480, 10.0)
    message = str(error.value)
    assert '\n' not in message
    assert '"%s"' % video_device in message
    return message


def test_a_missing_device_or_file_is_one_clear_error(tmp_path):
    assert 'no such device or file' in open_error('/dev/video77')
    assert 'no such device or file' in open_error(str(tmp_path / 'missing.mp4'))


@linux_only
def test_a_missing_camera_index_names_its_device_node():
    index = next(n for n in range(64, 128) if not os.path.exists('/dev/video%d' % n))
    assert '/dev/video%d' % index in open_error(str(index))


def test_a_directory_is_not_a_video_device(tmp_path):
    assert 'directory' in open_error(str(tmp_path))


def test_a_file_opencv_cannot_read(tmp_path):
    path = tmp_path / 'notes.txt'
    path.write_text('not a video\n')
    error = open_error(str(path))
    assert 'not a video file' in error and '\n' not in error
    # Where this OpenCV lacks FFmpeg (the boards'), the error says what files depend on.
    assert error.endswith(video_file_support(cv2.getBuildInformation()))


BUILD = """
  Video I/O:
    DC1394:                      NO
    FFMPEG:                      %s
      avcodec:                   YES (58.134.100)
    GStreamer:                   %s
    v4l/v4l2:                    YES (linux/videodev2.h)
"""


def test_an_opencv_without_ffmpeg_names_what_video_files_depend_on():
    assert video_file_support(BUILD % ('YES', 'NO')) == ''
    assert video_file_support(BUILD % ('YES', 'YES (1.20.3)')) == ''
    gstreamer = video_file_support(BUILD % ('NO', 'YES (1.20.3)'))
    assert 'no FFmpeg' in gstreamer and 'GStreamer plugins' in gstreamer
    neither = video_file_support(BUILD % ('NO', 'NO'))
    assert 'neither FFmpeg nor GStreamer' in neither and 'MJPEG .avi' in neither


def test_an_unreadable_file_says_permission_denied(tmp_path, monkeypatch, video):
    # Tests may run as root, which reads any file: make the access check say no.
    monkeypatch.setattr(camera_module.os, 'access', lambda path, mode: False)
    assert 'permission denied' in open_error(str(video))


@linux_only
def test_a_device_that_does_not_open_is_one_line_without_opencv_noise(capfd):
    # /dev/null is a character device that exists and is not a camera.
    message = open_error('/dev/null')
    assert 'not a video capture device' in message
    assert capfd.readouterr().err == ''


def test_synthetic_devices(paced):
    cap = paced('synthetic', 321, 240, 20.0)
    assert isinstance(cap, SyntheticCamera)
    assert (cap.get(cv2.CAP_PROP_FRAME_WIDTH), cap.get(cv2.CAP_PROP_FRAME_HEIGHT)) == (320, 240)
    assert cap.get(cv2.CAP_PROP_FPS) == 20.0
    ok, frame = cap.read()
    assert ok and read_frame_index(frame) == 0
    assert 'fail_open' in open_error('synthetic?fail_open=1')
    assert 'bogus' in open_error('synthetic?bogus=1')
    assert 'size' in str(pytest.raises(SourceError, paced, 'synthetic', 0, 480, 10.0).value)


def test_an_unplugged_synthetic_device_does_not_reopen(paced):
    cap = paced('synthetic?stop_after=1', 160, 120, 10.0)
    assert cap.read()[0] and not cap.read()[0]
    assert 'unplugged' in open_error('synthetic?stop_after=1', paced)


def test_a_video_file_plays_at_its_own_size_and_loops(clock, paced, video):
    cap = paced(str(video), 640, 480, 50.0)
    assert isinstance(cap, VideoFileSource) and cap.isOpened()
    # A file is not resized: get() reports what it really is.
    assert (cap.get(cv2.CAP_PROP_FRAME_WIDTH), cap.get(cv2.CAP_PROP_FRAME_HEIGHT)) == (160, 120)
    assert not cap.set(cv2.CAP_PROP_FRAME_WIDTH, 640)
    start = clock.t
    seen = []
    for n in range(14):
        ok, frame = cap.read()
        assert ok and frame.shape == (120, 160, 3) and frame.dtype == np.uint8
        assert cap.last_index == n
        assert cap.last_capture_time == pytest.approx(start + n / 50.0)
        seen.append(read_frame_index(frame))
    assert seen == [0, 1, 2, 3, 4, 5] * 2 + [0, 1]
    assert clock.t == pytest.approx(start + 13 / 50.0)
    cap.release()
    assert not cap.isOpened() and cap.read() == (False, None)


def test_a_video_file_uses_its_own_rate_when_fps_is_not_positive(clock, paced, video):
    cap = paced(str(video), 640, 480, 0)
    assert cap.get(cv2.CAP_PROP_FPS) == pytest.approx(25.0)
    start = clock.t
    cap.read()
    cap.read()
    assert clock.t == pytest.approx(start + 0.04)


def test_a_late_reader_does_not_skip_file_frames(clock, paced, video):
    cap = paced(str(video), 640, 480, 25.0)
    cap.read()
    clock.t += 1.0
    ok, frame = cap.read()
    assert ok and read_frame_index(frame) == 1
    resumed = clock.t
    cap.read()
    assert clock.t == pytest.approx(resumed + 0.04)


@pytest.mark.parametrize('after', [2, 6])
def test_reads_fail_once_the_file_is_gone(paced, video, after):
    cap = paced(str(video), 640, 480, 100.0)
    for _ in range(after):
        assert cap.read()[0]
    video.unlink()
    assert cap.read() == (False, None)
    assert cap.read() == (False, None)
    assert 'no such device or file' in open_error(str(video))


def test_a_file_that_becomes_unreadable_at_the_loop_fails(paced, video):
    cap = paced(str(video), 640, 480, 100.0)
    for _ in range(6):
        assert cap.read()[0]
    video.write_bytes(b'not a video any more')
    assert cap.read() == (False, None)
