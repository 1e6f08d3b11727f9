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


"""The synthetic V4L2 source: sizes, pacing, YUYV, frame index code, faults, spec strings."""

import time

import cv2
from fake_clock import FakeClock
import numpy as np
from py_vision.capture.pixel_formats import find
from py_vision.capture.synthetic_device import (
    bus_max_fps, parse_synthetic_spec, SyntheticCamera, SyntheticDevices)
from py_vision.capture.synthetic_picture import (
    bgr_to_yuyv, read_frame_index, synthetic_frame, synthetic_yuyv)
from py_vision.cv_bridge import CvBridge
import pytest

SIZES = [(160, 120), (640, 480), (1280, 720), (1920, 1080)]


@pytest.fixture
def clock():
    return FakeClock()


@pytest.fixture
def devices(clock):
    """Return the synthetic devices of one test, paced by its fake clock."""
    return SyntheticDevices(clock)


def size_of(cap):
    return cap.get(cv2.CAP_PROP_FRAME_WIDTH), cap.get(cv2.CAP_PROP_FRAME_HEIGHT)


@pytest.mark.parametrize('width,height', SIZES)
def test_frames_have_the_requested_size(devices, width, height):
    cam = SyntheticCamera(width, height, 30.0, devices=devices)
    assert cam.isOpened()
    assert size_of(cam) == (width, height)
    # YUYV, the format it opens in, is limited by the USB 2.0 bus.
    assert cam.get(cv2.CAP_PROP_FPS) == min(30.0, bus_max_fps(find('yuyv'), width, height))
    ok, frame = cam.read()
    assert ok
    assert frame.shape == (height, width, 3) and frame.dtype == np.uint8
    assert frame.flags['C_CONTIGUOUS']


def test_set_changes_the_size_like_a_driver(devices):
    cam = SyntheticCamera(640, 480, 10.0, devices=devices)
    assert cam.set(cv2.CAP_PROP_FRAME_WIDTH, 321)
    assert cam.set(cv2.CAP_PROP_FRAME_HEIGHT, 241)
    # YUYV carries pixel pairs: an odd width is rounded down, and get() tells the truth.
    assert size_of(cam) == (320, 241)
    assert cam.read()[1].shape == (241, 320, 3)
    assert cam.set(cv2.CAP_PROP_FRAME_WIDTH, 1)
    assert cam.get(cv2.CAP_PROP_FRAME_WIDTH) == 2
    assert SyntheticCamera(641, 480, devices=devices).get(cv2.CAP_PROP_FRAME_WIDTH) == 640


@pytest.mark.parametrize('value', [0, -4, 8193, 1e9, float('nan'), float('inf')])
def test_absurd_sizes_are_refused_and_the_size_kept(devices, value):
    cam = SyntheticCamera(320, 240, 10.0, devices=devices)
    assert not cam.set(cv2.CAP_PROP_FRAME_WIDTH, value)
    assert not cam.set(cv2.CAP_PROP_FRAME_HEIGHT, value)
    assert size_of(cam) == (320, 240)
    assert cam.read()[1].shape == (240, 320, 3)
    with pytest.raises(ValueError, match='size'):
        SyntheticCamera(value, 240, devices=devices)


def test_fps_property_and_refused_properties(devices):
    cam = SyntheticCamera(160, 120, 10.0, devices=devices)
    assert cam.set(cv2.CAP_PROP_FPS, 25)
    assert cam.get(cv2.CAP_PROP_FPS) == 25.0
    assert not cam.set(cv2.CAP_PROP_FPS, 0)
    assert not cam.set(cv2.CAP_PROP_FPS, -1)
    assert cam.get(cv2.CAP_PROP_FPS) == 25.0
    assert not cam.set(cv2.CAP_PROP_ZOOM, 2)
    assert cam.get(cv2.CAP_PROP_ZOOM) == 0.0
    fourcc = int(cam.get(cv2.CAP_PROP_FOURCC))
    assert bytes((fourcc >> s) & 0xFF for s in (0, 8, 16, 24)) == b'YUYV'
    with pytest.raises(ValueError, match='framerate'):
        SyntheticCamera(160, 120, 0, devices=devices)


def test_frames_are_paced_at_the_requested_rate(clock, devices):
    cam = SyntheticCamera(160, 120, 10.0, devices=devices)
    start = clock.t
    for n in range(5):
        ok, frame = cam.read()
        assert ok
        # Frame n is due at t0 + n / fps; read() returns then, not earlier.
        assert clock.t == pytest.approx(start + n * 0.1, abs=1e-9)
        assert cam.last_capture_time == pytest.approx(start + n * 0.1, abs=1e-9)
        assert cam.get(cv2.CAP_PROP_POS_MSEC) == pytest.approx(cam.last_capture_time * 1000)
        assert cam.last_index == n == read_frame_index(frame)
        assert cam.get(cv2.CAP_PROP_POS_FRAMES) == n + 1


def test_a_late_reader_gets_the_newest_frame_and_loses_the_others(clock, devices):
    cam = SyntheticCamera(160, 120, 10.0, devices=devices)
    start = clock.t
    cam.read()
    clock.t += 0.45  # the caller was busy for four and a half frame periods
    ok, frame = cam.read()
    assert ok and cam.last_index == 4 == read_frame_index(frame)
    assert cam.last_capture_time == pytest.approx(start + 0.4)
    assert clock.slept == 0
    # Frames never pile up: the next one comes when it is due, not at once.
    ok, frame = cam.read()
    assert cam.last_index == 5
    assert clock.t == pytest.approx(start + 0.5)


def test_a_size_change_restarts_the_schedule_and_the_sequence_goes_on(clock, devices):
    cam = SyntheticCamera(160, 120, 10.0, devices=devices)
    for _ in range(3):
        cam.read()
    clock.t += 0.1
    assert cam.set(cv2.CAP_PROP_FRAME_WIDTH, 320)
    before = clock.t
    ok, frame = cam.read()
    assert ok and frame.shape == (120, 320, 3)
    assert clock.t == before  # a new schedule starts with a frame at once
    # Frame 3 was due 0.3 s after the start: the new schedule carries on from it.
    assert cam.last_index == read_frame_index(frame) == 3


def test_real_time_pacing():
    fps = 20.0
    cam = SyntheticCamera(160, 120, fps, name='realtime')
    stamps = []
    for _ in range(11):
        ok, _ = cam.read()
        assert ok
        stamps.append(time.monotonic())
        assert cam.last_capture_time <= stamps[-1]
    mean_period = (stamps[-1] - stamps[0]) / 10
    assert mean_period == pytest.approx(1 / fps, rel=0.2)


def test_frames_are_the_v4l2_conversion_of_a_yuyv_buffer():
    for width, height in SIZES[:2]:
        yuyv = synthetic_yuyv(41, width, height)
        assert yuyv.shape == (height, width, 2)
        frame = synthetic_frame(41, width, height)
        assert np.array_equal(frame, cv2.cvtColor(yuyv, cv2.COLOR_YUV2BGR_YUYV))
        # A frame already in the YUYV gamut survives another round trip.
        again = cv2.cvtColor(bgr_to_yuyv(frame), cv2.COLOR_YUV2BGR_YUYV)
        assert np.abs(again.astype(int) - frame).max() <= 3


def test_the_code_blocks_are_pure_black_and_white():
    frame = synthetic_frame(0x5A5A5A5A, 640, 480)
    # At 640 x 480 the code is 4 x 11 blocks of 16 pixels, 8 pixels from the corner.
    code = frame[480 - 8 - 64:480 - 8, 640 - 8 - 176:640 - 8]
    assert set(np.unique(code)) == {0, 255}
    assert np.array_equal(code[:, :, 0], code[:, :, 1])
    assert np.array_equal(code[:, :, 1], code[:, :, 2])


def test_content_is_deterministic_and_changes_every_frame(devices):
    one = SyntheticCamera(640, 480, 10.0, name='one', devices=devices)
    two = SyntheticCamera(640, 480, 10.0, name='two', devices=devices)
    previous = None
    for n in range(4):
        ok1, frame1 = one.read()
        ok2, frame2 = two.read()
        assert ok1 and ok2 and one.last_index == two.last_index == n
        assert np.array_equal(frame1, frame2)
        assert np.array_equal(frame1, synthetic_frame(n, 640, 480))
        if previous is not None:
            assert not np.array_equal(frame1, previous)
        previous = frame1


def test_each_read_returns_a_new_array(devices):
    cam = SyntheticCamera(320, 240, 10.0, devices=devices)
    _, first = cam.read()
    kept = first.copy()
    _, second = cam.read()
    assert second is not first
    assert np.array_equal(first, kept)


def test_grab_and_retrieve(devices):
    cam = SyntheticCamera(160, 120, 10.0, devices=devices)
    assert cam.retrieve() == (False, None)
    assert cam.grab()
    ok, frame = cam.retrieve()
    assert ok and read_frame_index(frame) == cam.last_index == 0


def test_release_closes(devices):
    cam = SyntheticCamera(160, 120, 10.0, devices=devices)
    cam.release()
    assert not cam.isOpened()
    assert cam.read() == (False, None)
    assert cam.get(cv2.CAP_PROP_FRAME_WIDTH) == 0.0


@pytest.mark.parametrize('width,height', SIZES + [(64, 48), (100, 76), (322, 242)])
def test_index_reads_back_from_raw_frames(width, height):
    for index in (0, 1, 9, 1234, 99999, 2 ** 32 - 1):
        assert read_frame_index(synthetic_frame(index, width, height)) == index


@pytest.mark.parametrize('quality', [50, 75, 95])
@pytest.mark.parametrize('width,height', [(160, 120), (640, 480), (1920, 1080)])
def test_index_survives_jpeg(width, height, quality):
    for index in (7, 65535, 3141592653):
        ok, data = cv2.imencode('.jpg', synthetic_frame(index, width, height),
                                [cv2.IMWRITE_JPEG_QUALITY, quality])
        assert ok
        assert read_frame_index(cv2.imdecode(data, cv2.IMREAD_COLOR)) == index


@pytest.mark.parametrize('encoding', ['bgr8', 'rgb8', 'bgra8', 'rgba8', 'mono8', 'mono16',
                                      'bgr16'])
def test_index_survives_the_bridge(encoding):
    bridge = CvBridge()
    msg = bridge.cv2_to_imgmsg(synthetic_frame(4242, 320, 240), 'bgr8')
    assert read_frame_index(bridge.imgmsg_to_cv2(msg, encoding)) == 4242
    jpeg = bridge.cv2_to_compressed_imgmsg(synthetic_frame(4243, 320, 240))
    assert read_frame_index(bridge.compressed_imgmsg_to_cv2(jpeg)) == 4243


def test_no_index_in_other_images():
    rng = np.random.default_rng(1)
    images = [
        np.zeros((480, 640, 3), np.uint8),
        np.full((480, 640, 3), 255, np.uint8),
        rng.integers(0, 256, (480, 640, 3), dtype=np.uint8),
        cv2.GaussianBlur(rng.integers(0, 256, (480, 640), dtype=np.uint8), (0, 0), 6),
        np.tile(np.linspace(0, 255, 640).astype(np.uint8), (480, 1)),
        # a checkerboard of the code's block size
        (np.indices((480, 640)).sum(axis=0) // 16 % 2 * 255).astype(np.uint8),
        synthetic_frame(5, 48, 40),  # too small to carry the code
    ]
    for image in images:
        assert read_frame_index(image) is None
    assert read_frame_index(None) is None
    assert read_frame_index(np.zeros(10, np.uint8)) is None
    # Random blocks in the code's own grid: sync blocks and the CRC reject nearly all.
    hits = 0
    frame = synthetic_frame(0, 640, 480)
    for _ in range(200):
        blocks = rng.integers(0, 2, (4, 11)).astype(np.uint8) * 255
        frame[-72:-8, -184:-8] = np.repeat(np.repeat(blocks, 16, 0), 16, 1)[:, :, None]
        hits += read_frame_index(frame) is not None
    assert hits <= 2


def test_a_damaged_code_is_rejected():
    frame = synthetic_frame(123456, 640, 480)
    # Flip one data block (row 1, column 5 of the 4 x 11 grid of 16-pixel blocks).
    x0, y0 = 640 - 8 - 11 * 16, 480 - 8 - 4 * 16
    block = frame[y0 + 16:y0 + 32, x0 + 80:x0 + 96]
    block[...] = 255 - block
    assert read_frame_index(frame) is None


def test_fail_open(devices):
    cam = SyntheticCamera(fail_open=True, devices=devices)
    assert not cam.isOpened()
    assert cam.read() == (False, None)
    assert 'fail_open' in cam.error


def test_stop_after_unplugs_for_good(clock, devices):
    cam = devices.open('synthetic?stop_after=3', 160, 120, 10.0)
    assert [cam.read()[0] for _ in range(5)] == [True, True, True, False, False]
    assert cam.isOpened()  # as with V4L2: the device stays open, its reads fail
    assert 'unplugged' in cam.error
    clock.t += 1e6
    assert not devices.open('synthetic?stop_after=3', 160, 120, 10.0).isOpened()
    # Another spec is another device.
    assert devices.open('synthetic', 160, 120, 10.0).read()[0]


def test_unplugged_for_comes_back_after_the_delay(clock, devices):
    spec = 'synthetic?stop_after=3&unplugged_for=2'
    cam = devices.open(spec, 160, 120, 10.0)
    assert [cam.read()[0] for _ in range(4)] == [True, True, True, False]
    unplugged_at = clock.t
    cam.release()
    clock.t = unplugged_at + 1.9
    again = devices.open(spec, 160, 120, 10.0)
    assert not again.isOpened() and again.read() == (False, None)
    clock.t = unplugged_at + 2.0
    back = devices.open(spec, 160, 120, 10.0)
    assert back.isOpened()
    indices = []
    for _ in range(8):  # more than stop_after: it does not unplug a second time
        ok, frame = back.read()
        assert ok
        indices.append(read_frame_index(frame))
    # The sequence goes on; the 2 s away are 20 lost frames at 10 fps.
    assert indices == list(range(22, 30))


def test_fail_every_fails_single_reads(clock, devices):
    cam = SyntheticCamera(160, 120, 10.0, fail_every=3, devices=devices)
    results = []
    for _ in range(7):
        ok, frame = cam.read()
        results.append(read_frame_index(frame) if ok else None)
        assert cam.isOpened()
    # Reads 3 and 6 fail; their frames are lost, the schedule keeps going.
    assert results == [0, 1, None, 3, 4, None, 6]
    assert clock.t == pytest.approx(1000.6)


def test_spec_strings():
    assert parse_synthetic_spec('synthetic') == {}
    assert parse_synthetic_spec('synthetic?fail_open=true') == {'fail_open': True}
    assert parse_synthetic_spec('synthetic?fail_open=0&stop_after=30&unplugged_for=1.5'
                                '&fail_every=7') == {'fail_open': False, 'stop_after': 30,
                                                     'unplugged_for': 1.5, 'fail_every': 7}
    cam = SyntheticDevices().open('synthetic?fail_every=2', 321, 240, 15)
    assert size_of(cam) == (320, 240) and cam.get(cv2.CAP_PROP_FPS) == 15


@pytest.mark.parametrize('spec,words', [
    ('synthetic?speed=3', ['speed', 'fail_open', 'stop_after', 'unplugged_for', 'fail_every']),
    ('synthetic?fail_open=maybe', ['fail_open', '0, 1, true or false', 'maybe']),
    ('synthetic?stop_after=x', ['stop_after', 'integer', '"x"']),
    ('synthetic?stop_after=-1', ['stop_after', '>= 0']),
    ('synthetic?stop_after=', ['stop_after']),
    ('synthetic?fail_every=0', ['fail_every', '>= 1']),
    ('synthetic?unplugged_for=nan', ['unplugged_for', 'number']),
    ('synthetic?stop_after=1&stop_after=2', ['stop_after', 'twice']),
    ('synthetic?garbage', ['garbage', 'key=value']),
    ('synthetics', ['synthetics']),
])
def test_bad_spec_strings_name_the_problem(spec, words):
    with pytest.raises(ValueError) as error:
        SyntheticDevices().open(spec, 640, 480, 10.0)
    message = str(error.value)
    for word in words:
        assert word in message
    assert '\n' not in message
