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

"""The camera layer on the synthetic USB 2.0 camera: pixel formats, rates, JPEG, controls."""

import cv2
from fake_clock import FakeClock
import numpy as np
from py_vision.capture import Camera as _Camera, SourceError, StreamFormat, SyntheticDevices
from py_vision.capture.controls import CID
from py_vision.capture.pixel_formats import find, FORMATS
from py_vision.capture.source import Frame
from py_vision.capture.synthetic_device import SyntheticCamera
from py_vision.capture.synthetic_picture import (
    JPEG_QUALITY, read_frame_index, synthetic_frame, synthetic_jpeg, synthetic_yuyv)
from py_vision.capture.v4l2 import V4L2Device, V4L2Error
from py_vision.control_names import ControlNames, param_name
import pytest


class Camera:
    """Camera.open on synthetic devices paced by a fake clock."""

    @staticmethod
    def open(*args, **kwargs):  # noqa: A003
        clock = FakeClock()
        return _Camera.open(*args, synthetic=SyntheticDevices(clock), clock=clock, **kwargs)


@pytest.mark.parametrize('width,height,fps,fmt,rate', [
    (640, 480, 30.0, 'YUYV', 30.0),      # YUYV fits the bus at VGA 30
    (1280, 720, 30.0, 'MJPG', 30.0),     # YUYV would give 10: MJPEG reaches 30
    (1920, 1080, 30.0, 'MJPG', 30.0),    # YUYV would give 5
    (1280, 720, 10.0, 'YUYV', 10.0),     # YUYV reaches 10 at 720p
    (640, 480, 200.0, 'MJPG', 200.0),
])
def test_auto_reaches_the_requested_rate(width, height, fps, fmt, rate):
    camera = Camera.open('synthetic', width, height, fps, 'auto')
    assert (camera.pixel_format.fourcc, camera.fps) == (fmt, rate)
    assert (camera.width, camera.height) == (width, height)
    assert camera.notes == []


@pytest.mark.parametrize('width,height,rate', [(640, 480, 30.0), (1280, 720, 10.0),
                                               (1920, 1080, 5.0)])
def test_yuyv_is_limited_by_the_bus_and_says_so(width, height, rate):
    camera = Camera.open('synthetic', width, height, 30.0, 'yuyv')
    assert (camera.pixel_format.fourcc, camera.fps) == ('YUYV', rate)
    if rate < 30:
        assert camera.notes == [
            '30 fps requested, the camera gives %g fps in YUYV (YUYV at this size is limited '
            'by the bus; pixel_format:=mjpg or auto reaches higher rates)' % rate]
    assert 'YUYV at %g fps' % rate in camera.describe()


def test_a_format_the_camera_refuses_is_one_note_naming_what_it_gives():
    camera = Camera.open('synthetic?formats=yuyv', 640, 480, 30.0, 'mjpg')
    assert camera.pixel_format.fourcc == 'YUYV'
    assert camera.notes == [
        'the camera refuses pixel_format mjpg (it offers YUYV); it gives YUYV instead']
    camera = Camera.open('synthetic?formats=mjpg', 640, 480, 30.0, 'yuyv')
    assert camera.pixel_format.fourcc == 'MJPG'


def test_auto_stays_with_yuyv_when_the_camera_has_no_mjpeg():
    camera = Camera.open('synthetic?formats=yuyv', 1280, 720, 30.0, 'auto')
    assert (camera.pixel_format.fourcc, camera.fps) == ('YUYV', 10.0)
    assert camera.notes == ['30 fps requested, the camera gives 10 fps in YUYV']


@pytest.mark.parametrize('offered,output,chosen', [
    ('grey,yuyv', 'bgr8', 'YUYV'),       # colour wins for a colour output
    ('grey,yuyv', 'mono8', 'GREY'),      # the least work for mono8
    ('grey,y16', 'mono16', 'Y16'),       # the most bits for mono16
    ('grey,y16', 'mono8', 'GREY'),
    ('rgb3,bgr3,yuyv', 'bgr8', 'BGR3'),  # a view beats a swap beats a conversion
    ('rgb3,bgr3,yuyv', 'rgb8', 'RGB3'),
    ('nv12,uyvy', 'native', 'UYVY'),     # sensor_msgs has UYVY (yuv422), not NV12
    ('grey', 'bgr8', 'GREY'),            # a camera that sends neither YUYV nor MJPEG opens
])
def test_auto_chooses_the_least_work_for_the_output(offered, output, chosen):
    camera = Camera.open('synthetic?formats=%s' % offered, 640, 480, 15.0, 'auto', output)
    assert camera.pixel_format.fourcc == chosen and camera.notes == []


def test_auto_prefers_a_format_that_reaches_the_rate_over_less_work():
    # RGB3 at 640x480 is 27.6 MB/s at 30 fps: more than USB 2.0 carries (15 fps).
    camera = Camera.open('synthetic?formats=rgb3,yuyv', 640, 480, 30.0, 'auto', 'rgb8')
    assert (camera.pixel_format.fourcc, camera.fps) == ('YUYV', 30.0)
    camera = Camera.open('synthetic?formats=rgb3,yuyv', 640, 480, 15.0, 'auto', 'rgb8')
    assert (camera.pixel_format.fourcc, camera.fps) == ('RGB3', 15.0)


def test_mjpeg_frames_are_the_cameras_jpeg_and_decode_only_on_demand():
    camera = Camera.open('synthetic', 1280, 720, 30.0, 'mjpg')
    frame = camera.read()
    assert frame.jpeg is not None and frame.jpeg.ndim == 1
    assert bytes(frame.jpeg[:2]) == b'\xff\xd8'
    assert not frame.decoded
    assert bytes(frame.jpeg) == synthetic_jpeg(frame.index, 1280, 720)
    image = frame.bgr()
    assert frame.decoded and image.shape == (720, 1280, 3)
    assert read_frame_index(image) == frame.index
    # Within JPEG error of the camera's own picture.
    error = np.abs(image.astype(int) - synthetic_frame(frame.index, 1280, 720)).mean()
    assert error < 3.0
    assert frame.bgr() is image  # decoded once


class ScriptedSource:
    """A 640x480 MJPEG source that gives the camera these byte strings as frames, in turn."""

    def __init__(self, payloads):
        self.payloads = list(payloads)

    def next_frame(self):
        data = np.frombuffer(self.payloads.pop(0), np.uint8)
        return Frame(None, None, find('mjpg'), 640, 480, data)


def test_a_broken_jpeg_is_corrupt_even_after_whole_ones_with_the_same_header():
    whole = synthetic_jpeg(3, 640, 480)
    noisy = bytearray(whole)
    noisy[2:300] = bytes((7 * i) % 255 for i in range(298))  # header noise, EOI still there
    frames = [whole, whole + bytes(16), bytes(noisy), whole[:len(whole) // 2], whole[:-2],
              whole]
    camera = _Camera(ScriptedSource(frames), 'scripted', StreamFormat('MJPG', 640, 480, 30.0),
                     [])
    corrupt = [camera.read().corrupt for _ in frames]
    # Padding after EOI is a UVC payload's and harmless; noise, a cut or no EOI are not.
    assert corrupt == [False, False, True, True, True, False]
    assert cv2.imdecode(np.frombuffer(bytes(noisy), np.uint8), cv2.IMREAD_COLOR) is None


RAW = [pixel_format for pixel_format in FORMATS.values() if not pixel_format.compressed]


@pytest.mark.parametrize('pixel_format', RAW, ids=lambda pixel_format: pixel_format.fourcc)
def test_every_raw_format_comes_as_sent_and_converts_right(pixel_format):
    camera = Camera.open('synthetic?formats=%s' % pixel_format.fourcc.lower(), 320, 240, 15.0,
                         pixel_format.fourcc.lower())
    assert camera.pixel_format is pixel_format and camera.notes == []
    frame = camera.read()
    sent = np.ascontiguousarray(pixel_format.from_yuyv(synthetic_yuyv(frame.index, 320, 240)))
    assert frame.data.tobytes() == sent.tobytes()
    native = frame.image('native')
    expected = synthetic_frame(frame.index, 320, 240)
    if pixel_format.encoding is not None:
        assert frame.encoding('native') == pixel_format.encoding
        assert native.reshape(-1).view(np.uint8).tobytes() == sent.tobytes()
    else:
        assert frame.encoding('native') == pixel_format.native_encoding
    bgr = frame.image('bgr8')
    assert bgr.shape == (240, 320, 3) and read_frame_index(bgr) == frame.index
    if pixel_format.mono:   # a grey camera's pixels are its luma
        expected = cv2.cvtColor(synthetic_yuyv(frame.index, 320, 240)[:, :, 0],
                                cv2.COLOR_GRAY2BGR)
    # The colour bars and the ramp, within what the format's sampling loses.
    assert np.abs(bgr.astype(int) - expected).mean() < 2.0
    assert np.array_equal(frame.image('rgb8'), bgr[:, :, ::-1])
    mono8, mono16 = frame.image('mono8'), frame.image('mono16')
    assert mono8.shape == (240, 320) and mono16.dtype == np.uint16
    assert np.abs(mono16.astype(int) // 256 - mono8).max() <= 1


def test_yuyv_frames_are_bgr_and_exact():
    camera = Camera.open('synthetic', 640, 480, 30.0, 'yuyv')
    frame = camera.read()
    assert frame.jpeg is None
    assert np.array_equal(frame.bgr(), synthetic_frame(frame.index, 640, 480))


def test_spliced_mjpeg_is_byte_identical_to_a_whole_frame_encode():
    # The synthetic camera encodes only the code strip per frame; the result must be the
    # same bytes as encoding the whole frame, frame after frame.
    for width, height in ((640, 480), (1280, 720), (1920, 1080), (100, 60)):
        params = [cv2.IMWRITE_JPEG_QUALITY, JPEG_QUALITY,
                  cv2.IMWRITE_JPEG_RST_INTERVAL, (width + 15) // 16]
        for index in (3, 3 + 64, 3 + 128, 70):
            whole = cv2.imencode('.jpg', synthetic_frame(index, width, height), params)[1]
            assert synthetic_jpeg(index, width, height) == whole.tobytes()


def test_raw_mode_conversion_switch_behaves_like_opencv():
    cam = SyntheticCamera(640, 480, 30.0)
    assert cam.set(cv2.CAP_PROP_FOURCC, cv2.VideoWriter_fourcc(*'MJPG'))
    assert cam.read()[1].shape == (480, 640, 3)  # converted to BGR by default
    assert cam.set(cv2.CAP_PROP_CONVERT_RGB, 0)
    assert cam.get(cv2.CAP_PROP_CONVERT_RGB) == 0.0
    data = cam.read()[1]
    assert data.ndim == 1 and data.dtype == np.uint8 and bytes(data[:2]) == b'\xff\xd8'
    assert not cam.set(cv2.CAP_PROP_FOURCC, cv2.VideoWriter_fourcc(*'H264'))
    fourcc = int(cam.get(cv2.CAP_PROP_FOURCC))
    assert bytes((fourcc >> s) & 0xFF for s in (0, 8, 16, 24)) == b'MJPG'


def mean_bgr(camera):
    return camera.read().bgr().reshape(-1, 3).mean(axis=0)


def value(camera, cid):
    """Return a control's value as the camera reports it now."""
    return next(control.value for control in camera.controls() if control.cid == cid)


def refusal(camera, cid, value):
    """Set one control; return the camera's refusal in words (None: set)."""
    refused = camera.set_controls({cid: value})
    return ControlNames(camera.controls()).words(refused[cid]) if refused else None


@pytest.mark.parametrize('fmt', ['yuyv', 'mjpg'])
def test_controls_change_the_picture_in_the_expected_direction(fmt):
    camera = Camera.open('synthetic', 320, 240, 30.0, fmt)
    base = mean_bgr(camera)
    assert camera.set_controls({CID.BRIGHTNESS: 40}) == {}
    assert value(camera, CID.BRIGHTNESS) == 40
    assert mean_bgr(camera).mean() > base.mean() + 20
    # Manual exposure and the exposure time in one batch: the mode goes first.
    assert camera.set_controls({CID.BRIGHTNESS: 0, CID.EXPOSURE_ABSOLUTE: 400,
                                CID.EXPOSURE_AUTO: 1}) == {}
    assert mean_bgr(camera).mean() > base.mean() + 10
    camera.set_controls({CID.EXPOSURE_ABSOLUTE: 166, CID.WHITE_BALANCE_TEMPERATURE: 2800,
                         CID.AUTO_WHITE_BALANCE: 0})   # a low temperature: bluer
    b, g, r = mean_bgr(camera)
    assert b - r > (base[0] - base[2]) + 10
    camera.set_controls({CID.AUTO_WHITE_BALANCE: 1})

    def luma_spread():
        return cv2.cvtColor(camera.read().bgr(), cv2.COLOR_BGR2GRAY).astype(float).std()
    contrast_base = luma_spread()
    camera.set_controls({CID.CONTRAST: 8})
    assert luma_spread() < contrast_base * 0.5
    camera.set_controls({CID.CONTRAST: 32, CID.FOCUS_AUTO: 0, CID.FOCUS_ABSOLUTE: 200})

    def edge_energy(image):
        luma = cv2.cvtColor(image, cv2.COLOR_BGR2GRAY).astype(float)
        return np.square(np.diff(luma, axis=1)).mean()
    blurred = camera.read().bgr()
    assert edge_energy(blurred) < edge_energy(synthetic_frame(0, 320, 240)) * 0.3


def test_controls_are_the_devices_own_and_checked_against_its_ranges():
    camera = Camera.open('synthetic', 320, 240, 30.0, 'yuyv')
    assert {param_name(control.label) for control in camera.controls()} == {
        'brightness', 'contrast', 'saturation', 'sharpness', 'gain', 'white_balance_automatic',
        'white_balance_temperature', 'auto_exposure', 'exposure_time_absolute',
        'focus_automatic_continuous', 'focus_absolute'}
    assert refusal(camera, CID.BRIGHTNESS, 200) == \
        "brightness: 200 is out of the camera's range -64..64"
    assert camera.source.get(cv2.CAP_PROP_BRIGHTNESS) == 0
    assert refusal(camera, CID.EXPOSURE_AUTO, 1) is None
    assert camera.source.get(cv2.CAP_PROP_AUTO_EXPOSURE) == 1
    assert refusal(camera, CID.EXPOSURE_AUTO, 2) == \
        'auto_exposure: 2 is not one of its menu entries (1=Manual Mode; ' \
        '3=Aperture Priority Mode)'
    assert refusal(camera, 0x00980999, 1) == 'control 0x00980999: the camera has no such control'


def test_a_control_an_automatic_mode_holds_is_refused_naming_the_mode():
    camera = Camera.open('synthetic', 320, 240, 30.0, 'yuyv')
    exposure = next(c for c in camera.controls() if c.cid == CID.EXPOSURE_ABSOLUTE)
    assert exposure.inactive and exposure.governor == CID.EXPOSURE_AUTO
    assert refusal(camera, CID.EXPOSURE_ABSOLUTE, 300) == \
        'exposure_time_absolute is inactive while auto_exposure is 3'
    assert value(camera, CID.EXPOSURE_ABSOLUTE) == 166   # nothing reached the device
    assert refusal(camera, CID.EXPOSURE_AUTO, 1) is None
    assert refusal(camera, CID.EXPOSURE_ABSOLUTE, 300) is None
    assert value(camera, CID.EXPOSURE_ABSOLUTE) == 300


def test_a_file_has_no_controls_and_says_which(tmp_path):
    path = str(tmp_path / 'clip.avi')
    writer = cv2.VideoWriter(path, cv2.VideoWriter_fourcc(*'MJPG'), 10.0, (64, 48))
    for _ in range(3):
        writer.write(np.zeros((48, 64, 3), np.uint8))
    writer.release()
    camera = Camera.open(path, 640, 480, 10.0, 'mjpg')
    assert camera.file and camera.controls() == []
    assert camera.describe() == "64x48 video file at 10 fps (the file's own size; 640x480 " \
        'requested)'
    assert refusal(camera, CID.GAIN, 3) == 'control 0x00980913: the camera has no such control'


def test_a_missing_device_is_a_source_error():
    with pytest.raises(SourceError, match='no such device'):
        Camera.open('/dev/video_py_vision_missing', 640, 480, 10.0)


def test_something_that_is_not_a_v4l2_device_says_so(tmp_path):
    plain = tmp_path / 'not_a_camera'
    plain.write_bytes(b'')
    with pytest.raises(V4L2Error, match='not a video capture device'):
        V4L2Device(str(plain))
    with pytest.raises(V4L2Error, match='no such device'):
        V4L2Device(str(tmp_path / 'missing'))


@pytest.mark.parametrize('device', ['\u00b2', ' 9\u2079 '])
def test_a_device_of_digits_that_are_no_number_is_one_clear_error(device):
    # str.isdigit() holds for superscripts, which int() refuses: not a camera index, a name.
    from py_vision.listing import device_listing
    with pytest.raises(SourceError, match='cannot open video_device'):
        _Camera.open(device, 160, 120, 10.0)
    with pytest.raises(SourceError, match='cannot open video_device'):
        device_listing(device)


@pytest.mark.parametrize('fourcc,sends', [
    ('yuyv', True), ('uyvy', True), ('grey', True), ('nv21', True), ('ba81', True),
    ('nv12', False),    # no sensor_msgs encoding: native is converted
    ('yu12', False), ('y10', False), ('mjpg', False)])
def test_native_frames_are_a_messages_bytes_only_for_a_raw_format_with_an_encoding(
        fourcc, sends):
    # Only then may the camera capture them into the published messages (USERPTR).
    camera = Camera.open('synthetic?formats=%s' % fourcc, 320, 240, 15.0, fourcc, 'native')
    try:
        assert camera.sends_messages is sends
    finally:
        camera.release()
