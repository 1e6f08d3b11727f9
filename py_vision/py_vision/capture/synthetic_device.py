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
The synthetic V4L2 device: a camera with OpenCV's VideoCapture interface and no hardware.

`SyntheticCamera` behaves like a USB 2.0 UVC camera seen through OpenCV's V4L2 backend: it
honours the requested size and frame rate (an odd width is rounded down to even, as YUYV
needs), builds every frame as a packed YUYV 4:2:2 buffer (synthetic_picture) and converts it
with ``cv2.COLOR_YUV2BGR_YUYV`` as OpenCV's V4L2 backend does, and paces frames in real time
with a single buffer: a caller that falls behind gets the newest frame and the frames in between
are lost (their indices are skipped). read() returns a new array every time.

What it is comes from its data file (camera_model.SYNTHETIC, the format the tests' emulated
cameras are described in): the formats a USB webcam offers (YUYV and MJPEG), or any formats of
the pixel format table it is asked for, at the file's sizes and rates; its controls; the bus's
bandwidth. A raw format is limited by the bus (camera_model.bus_rates: the highest listed
rate whose frames fit; YUYV, two bytes a pixel: 640x480 at 30, 1280x720 at 10, 1920x1080 at
5 fps); a compressed one runs at the requested rate at any size. Raw frames are made from its
YUYV picture the way the table says (`PixelFormat.from_yuyv`). The FOURCC is chosen with
``set(CAP_PROP_FOURCC)`` and, as in OpenCV's V4L2 backend, the first format offered is the one
it opens with; with
``CAP_PROP_CONVERT_RGB`` off read() returns the buffer as the camera sent it (a 1-D uint8
array: the JPEG's bytes in MJPEG mode), otherwise a BGR image. As a FrameSource (`configure`,
`next_frame`, ...) it hands out the buffer as sent.

Its controls (the data file's, with V4L2 ids and names as uvcvideo reports them) are read with
controls() and set with set_control() (and, as OpenCV does, through the CAP_PROP_* properties),
and change the picture visibly and deterministically; as on a UVC camera, a control an
automatic mode holds (the file's inactive_unless) is inactive while that mode is on.

Faults for tests, as constructor options or in a ``video_device`` string
(`SyntheticDevices.open`): ``fail_open`` (never opens), ``stop_after`` (unplugged after N
frames), ``unplugged_for`` (reopening works again that many seconds after the unplug) and
``fail_every`` (every K-th read fails while the device stays open); ``formats`` says what
the camera offers, by FourCC (``synthetic?formats=grey`` or ``yuyv,mjpg``).
Cameras opened through one `SyntheticDevices` with the same name and options share one state:
the frame index and an unplug carry over to the next camera opened with them. The devices'
clock is a constructor argument (a fake one in tests).
"""

import math
import threading
from typing import Dict, List, Optional
from urllib.parse import parse_qsl

import cv2
import numpy as np
from py_vision.capture import camera_model
from py_vision.capture.controls import CID, ControlInfo, MENU
from py_vision.capture.pacing import FramePacer
from py_vision.capture.pixel_formats import find, FORMATS, PixelFormat
from py_vision.capture.source import Clock, Frame, FrameFormat, MONOTONIC, StreamFormat
from py_vision.capture.synthetic_picture import (
    apply_controls, frame_layout, mjpeg_encoder, yuyv_to_bgr)

MAX_SIZE = 8192
MAX_FPS = 1000.0
_OPTIONS = 'fail_open, stop_after, unplugged_for, fail_every, formats'
# The formats it makes pictures in: every one of the table but a camera's own video.
_PICTURE_FORMATS = [fourcc for fourcc, listed in FORMATS.items() if not listed.video]


def _picture_format(name):
    """Return the format a name gives, or None when it is unknown or a camera's own video."""
    found = find(name)
    return None if found is None or found.video else found


MODEL = camera_model.load(camera_model.SYNTHETIC)
_CONTROL_OF = {control.info.cid: control for control in MODEL.controls}
# OpenCV's V4L2 backend maps these properties onto the controls.
_PROPS = {
    cv2.CAP_PROP_BRIGHTNESS: CID.BRIGHTNESS, cv2.CAP_PROP_CONTRAST: CID.CONTRAST,
    cv2.CAP_PROP_SATURATION: CID.SATURATION, cv2.CAP_PROP_SHARPNESS: CID.SHARPNESS,
    cv2.CAP_PROP_GAIN: CID.GAIN, cv2.CAP_PROP_AUTO_WB: CID.AUTO_WHITE_BALANCE,
    cv2.CAP_PROP_WB_TEMPERATURE: CID.WHITE_BALANCE_TEMPERATURE,
    cv2.CAP_PROP_AUTO_EXPOSURE: CID.EXPOSURE_AUTO, cv2.CAP_PROP_EXPOSURE: CID.EXPOSURE_ABSOLUTE,
    cv2.CAP_PROP_FOCUS: CID.FOCUS_ABSOLUTE, cv2.CAP_PROP_AUTOFOCUS: CID.FOCUS_AUTO,
}
_DEFAULTS = {control.info.cid: control.info.default for control in MODEL.controls}


def _model_format(pixel_format: PixelFormat) -> camera_model.ModelFormat:
    """Return a format as the camera offers it: the file's, or any other at the first's sizes."""
    for offered in MODEL.formats:
        if offered.pixel_format is pixel_format:
            return offered
    first = MODEL.formats[0]
    return camera_model.ModelFormat(pixel_format, pixel_format.description, first.sizes,
                                    first.rates)


def bus_max_fps(pixel_format: PixelFormat, width: int, height: int) -> float:
    """Return the highest listed rate at which frames of a format fit the camera's bus."""
    return camera_model.bus_rates(pixel_format, width, height,
                                  _model_format(pixel_format).rates, MODEL.bandwidth)[0]


class _DeviceState:
    """What outlives one SyntheticCamera object: the frame sequence and an unplug."""

    def __init__(self):
        self.last_index = None
        self.last_time = None
        self.unplugged_at = None
        self.recovered = False


class SyntheticDevices:
    """
    The synthetic devices of one process (or one test): their clock and their shared state.

    Cameras opened through the same SyntheticDevices with the same name and options continue
    one frame sequence and see one unplug, as reopening a real device does.
    """

    def __init__(self, clock: Clock = MONOTONIC):
        self.clock = clock
        self._states: Dict[tuple, _DeviceState] = {}
        self._lock = threading.Lock()

    def state(self, key) -> _DeviceState:
        """Return the shared state of the device with this name and options."""
        with self._lock:
            return self._states.setdefault(key, _DeviceState())

    def open(self, spec, width, height, fps):  # noqa: A003
        """
        Open the synthetic camera a video_device string names; ValueError if it is bad.

        The whole string names the device, so reopening it finds the same frame sequence and
        unplug state.
        """
        options = parse_synthetic_spec(spec)
        return SyntheticCamera(width, height, fps, name=spec, devices=self, **options)


def _positive_at_most(value, limit):
    """Return value when it is a number in (0, limit] (not a bool, nan or inf), else None."""
    if not isinstance(value, (int, float, np.integer, np.floating)) or isinstance(value, bool):
        return None
    if not math.isfinite(value) or value <= 0 or value > limit:
        return None
    return value


def _check_size(value):
    value = _positive_at_most(value, MAX_SIZE)
    return None if value is None else int(value)


def _check_fps(value):
    value = _positive_at_most(value, MAX_FPS)
    return None if value is None else float(value)


class SyntheticCamera:
    """
    A V4L2 camera without hardware, with OpenCV's VideoCapture interface.

    `last_index` is the frame index of the image the last successful read() returned and
    `last_capture_time` the time.monotonic() at which it was captured (its due time; earlier
    than the read's return when the caller was late). `error` says why the device is not
    open, or why its reads fail, or is None. `formats` names the pixel formats it offers (by
    FourCC); it opens in the first of them.
    """

    def __init__(self, width=640, height=480, fps=10.0, *, fail_open=False, stop_after=None,
                 unplugged_for=None, fail_every=None,
                 formats=tuple(f.pixel_format.fourcc for f in MODEL.formats),
                 name='synthetic', devices: Optional[SyntheticDevices] = None):
        w, h, rate = _check_size(width), _check_size(height), _check_fps(fps)
        if w is None or h is None:
            raise ValueError('image size must be 1..%d pixels each way, got %r x %r'
                             % (MAX_SIZE, width, height))
        if rate is None:
            raise ValueError('framerate must be > 0 and <= %g, got %r' % (MAX_FPS, fps))
        if stop_after is not None and (int(stop_after) != stop_after or stop_after < 0):
            raise ValueError('stop_after must be an integer >= 0, got %r' % (stop_after,))
        if unplugged_for is not None and not (0 <= unplugged_for < math.inf):
            raise ValueError('unplugged_for must be a number of seconds >= 0, got %r'
                             % (unplugged_for,))
        if fail_every is not None and (int(fail_every) != fail_every or fail_every < 1):
            raise ValueError('fail_every must be an integer >= 1, got %r' % (fail_every,))
        offered = [_picture_format(name) for name in formats]
        if None in offered or not formats:
            raise ValueError('formats must be one or more of %s, got %s'
                             % (', '.join(_PICTURE_FORMATS), ','.join(formats) or 'none'))
        self.name = name
        self._devices = devices if devices is not None else SyntheticDevices()
        self._clock = self._devices.clock
        self.last_index = None
        self.last_capture_time = None
        self.error = None
        self._width, self._height = max(2, w & ~1), h
        self._offered = list(dict.fromkeys(offered))
        self._format = self._offered[0]
        self._convert_rgb = True
        self._controls = dict(_DEFAULTS)
        self._requested_fps = rate
        self._pacer = FramePacer(self._rate(), clock=self._clock)
        self._stop_after = stop_after
        self._fail_every = fail_every
        self._frames = 0
        self._reads = 0
        self._base = 0
        self._grabbed = None
        self._buf = None
        self._rendered = None
        self._state = self._devices.state((name, stop_after, unplugged_for, fail_every,
                                           tuple(f.fourcc for f in self._offered)))
        self._opened = not fail_open
        if fail_open:
            self.error = 'the device does not open (fail_open)'
        elif self._state.unplugged_at is not None and not self._state.recovered:
            away = self._clock.now() - self._state.unplugged_at
            if unplugged_for is None or away < unplugged_for:
                self._opened = False
                self.error = 'the device is unplugged (stop_after=%d)' % stop_after
                if unplugged_for is not None:
                    self.error += ' and back in %.1f s' % (unplugged_for - away)
            else:
                self._state.recovered = True

    def isOpened(self):  # noqa: N802 (OpenCV's name)
        """Return True while the device is open (also after an unplug, as V4L2 does)."""
        return self._opened

    def release(self):
        """Close the device; reads fail afterwards."""
        self._opened = False
        self._buf = None
        self._rendered = None
        self._grabbed = None

    def interrupt(self):
        """Make the read() waiting for its frame in another thread (or the next) fail now."""
        self._pacer.cancel()

    def _unplugged(self):
        if (self._stop_after is None or self._state.recovered
                or self._frames < self._stop_after):
            return False
        if self._state.unplugged_at is None:
            self._state.unplugged_at = self._clock.now()
        self.error = 'the device was unplugged after %d frames (stop_after)' % self._stop_after
        return True

    def grab(self):
        """Wait for the next frame and capture it; False on a failed read."""
        self._grabbed = None
        if not self._opened or self._unplugged():
            return False
        starting = not self._pacer.running
        if not starting:
            # A sensor's frame exists at its capture time: build the YUYV buffer of the frame
            # expected next before waiting for it, so only the BGR conversion follows the stamp.
            self._render(self._base + self._pacer.next)
        scheduled = self._pacer.wait()
        if scheduled is None:
            return False
        number, due = scheduled
        if starting:
            self._base = self._next_index(due)
        index = self._base + number
        self._state.last_index, self._state.last_time = index, due
        self._reads += 1
        if self._fail_every and self._reads % self._fail_every == 0:
            return False
        self._frames += 1
        self._grabbed = index
        self.last_index, self.last_capture_time = index, due
        return True

    def _next_index(self, start):
        """Index of the first frame of a new schedule: the sequence goes on, gaps included."""
        state = self._state
        if state.last_index is None:
            return 0
        missed = int(round((start - state.last_time) * self._pacer.fps))
        return state.last_index + max(1, missed)

    def retrieve(self, image=None, flag=0):
        """
        Return the grabbed frame.

        A BGR image (a new array each call), or with CAP_PROP_CONVERT_RGB off the buffer as the
        camera sent it, as a 1-D uint8 array (the JPEG's bytes in MJPEG mode): the camera's own
        buffer, valid until the next grab.
        """
        if self._grabbed is None or not self._opened:
            return False, None
        data = self._sent()
        if not self._convert_rgb:
            return True, data
        pixel_format = self._format
        view = pixel_format.view(data, self._width, self._height)
        image = pixel_format.convert(view, 'bgr8')
        return True, image.copy() if image is view else image

    def _sent(self):
        """Return the grabbed frame's bytes as the camera sends them in its format (1-D)."""
        if self._rendered != self._grabbed:
            self._render(self._grabbed)
        yuyv = apply_controls(self._buf, self._controls, _DEFAULTS)
        pixel_format = self._format
        if pixel_format.compressed:
            encoder = mjpeg_encoder(self._width, self._height)
            if yuyv is self._buf:
                jpeg = encoder.encode(self._grabbed, yuyv)
            else:  # controls changed the whole picture: no cached rows apply
                jpeg = encoder.encode_whole(yuyv_to_bgr(yuyv))
            return np.frombuffer(jpeg, np.uint8)
        return np.ascontiguousarray(pixel_format.from_yuyv(yuyv)).reshape(-1).view(np.uint8)

    def _render(self, index):
        layout = frame_layout(self._width, self._height)
        fresh = self._buf is None or self._buf.shape != layout.background.shape
        if fresh:
            self._buf = layout.background.copy()
        layout.render(index, self._buf, fresh)
        self._rendered = index

    def read(self, image=None):
        """Grab and retrieve: (True, BGR image) or (False, None)."""
        if not self.grab():
            return False, None
        return self.retrieve()

    # --- as a FrameSource (what the camera layer uses) ---------------------------------

    def configure(self, pixel_format: PixelFormat, width: int, height: int,
                  fps: float) -> StreamFormat:
        """Ask for a format, size and rate as a driver is asked; return what it gives."""
        self.set(cv2.CAP_PROP_FOURCC, pixel_format.code)
        self.set(cv2.CAP_PROP_FRAME_WIDTH, width)
        self.set(cv2.CAP_PROP_FRAME_HEIGHT, height)
        self.set(cv2.CAP_PROP_FPS, fps)
        self._convert_rgb = False
        return StreamFormat(self._format.fourcc, self._width, self._height, self._pacer.fps,
                            self._format.bytesperline(self._width))

    def start(self) -> None:
        """Stream: frames come from the next next_frame() on."""

    def stop(self) -> None:
        """Stop streaming: the next frame starts a new schedule (the ones between are missed)."""
        self._pacer.restart()

    def capture_into(self, arrays) -> bool:
        """Return False: frames are made in memory of the source's own."""
        return False

    def next_frame(self) -> Optional[Frame]:
        """Wait for the next frame; return it as sent (valid until the next call), or None."""
        if not self.grab():
            return None
        pixel_format = self._format
        return Frame(self.last_index, self.last_capture_time, pixel_format, self._width,
                     self._height, self._sent(), pixel_format.bytesperline(self._width))

    def _rate(self):
        """Return the frame rate the camera gives: a raw format's is limited by the bus."""
        if self._format.compressed:
            return self._requested_fps
        return min(self._requested_fps, bus_max_fps(self._format, self._width, self._height))

    def formats(self) -> List[FrameFormat]:
        """Return the formats it offers at its listed sizes, with the rates each reaches."""
        found = []
        for pixel_format in self._offered:
            offered = _model_format(pixel_format)
            # A scaler: any size; a compressed format at any rate, raw ones at the bus's rates.
            found.append(FrameFormat(pixel_format.fourcc, offered.description,
                                     MODEL.frame_sizes(offered), (2, 1, MAX_SIZE, MAX_SIZE),
                                     (0.1, MAX_FPS) if pixel_format.compressed else None))
        return found

    def controls(self) -> List[ControlInfo]:
        """Return the camera's controls with their values; held ones inactive in auto mode."""
        return [control.info.with_value(self._controls[control.info.cid],
                                        self._held(control))
                for control in MODEL.controls]

    def _held(self, control: camera_model.ModelControl) -> bool:
        """Return whether an automatic mode holds the control now (it is inactive)."""
        if control.held_by is None:
            return False
        mode, free = control.held_by
        return self._controls[mode] != free

    def set_control(self, cid: int, value: int) -> Optional[str]:
        """Set a control as a driver does; return why it was refused, or None."""
        if cid not in _CONTROL_OF:
            return 'the device has no such control'
        control = _CONTROL_OF[cid].info
        if not self._opened:
            return 'the device is not open'
        if not control.minimum <= value <= control.maximum or (
                control.kind == MENU and value not in dict(control.menu)):
            return "out of the device's range"
        self._controls[cid] = int(value)
        return None

    def set(self, prop_id, value):  # noqa: A003 (OpenCV's name)
        """
        Set a property like a V4L2 driver; False for what the camera refuses.

        Width and height (an odd width is rounded down), fps (a raw format is capped by the
        bus), FOURCC (one offered), CONVERT_RGB and the controls within their range.
        """
        if not self._opened:
            return False
        prop_id = int(prop_id)
        if prop_id in _PROPS:
            if not isinstance(value, (int, float, np.integer, np.floating)) or not (
                    math.isfinite(value)):
                return False
            return self.set_control(_PROPS[prop_id], int(round(value))) is None
        if prop_id == cv2.CAP_PROP_CONVERT_RGB:
            self._convert_rgb = bool(value)
            return True
        if prop_id == cv2.CAP_PROP_FOURCC:
            chosen = next((f for f in self._offered if f.code == value), None)
            if chosen is None:
                return False
            changed, self._format = chosen is not self._format, chosen
        elif prop_id in (cv2.CAP_PROP_FRAME_WIDTH, cv2.CAP_PROP_FRAME_HEIGHT):
            size = _check_size(value)
            if size is None:
                return False
            if prop_id == cv2.CAP_PROP_FRAME_WIDTH:
                size = max(2, size & ~1)
                changed, self._width = size != self._width, size
            else:
                changed, self._height = size != self._height, size
        elif prop_id == cv2.CAP_PROP_FPS:
            rate = _check_fps(value)
            if rate is None:
                return False
            changed, self._requested_fps = rate != self._requested_fps, rate
        else:
            return False
        rate = self._rate()
        if changed or rate != self._pacer.fps:
            self._pacer.fps = rate
            self._pacer.restart()
            self._rendered = None
        return True

    def get(self, prop_id):
        """Return the real width, height, fps, next frame index, FOURCC or last capture time."""
        if not self._opened:
            return 0.0
        prop_id = int(prop_id)
        if prop_id == cv2.CAP_PROP_FRAME_WIDTH:
            return float(self._width)
        if prop_id == cv2.CAP_PROP_FRAME_HEIGHT:
            return float(self._height)
        if prop_id == cv2.CAP_PROP_FPS:
            return float(self._pacer.fps)
        if prop_id == cv2.CAP_PROP_FOURCC:
            return float(self._format.code)
        if prop_id == cv2.CAP_PROP_CONVERT_RGB:
            return 1.0 if self._convert_rgb else 0.0
        if prop_id in _PROPS:
            return float(self._controls[_PROPS[prop_id]])
        if prop_id == cv2.CAP_PROP_POS_FRAMES:
            if self._pacer.running:
                return float(self._base + self._pacer.next)
            last = self._state.last_index
            return 0.0 if last is None else float(last + 1)
        if prop_id == cv2.CAP_PROP_POS_MSEC:
            return 0.0 if self.last_capture_time is None else self.last_capture_time * 1000.0
        return 0.0


def _parse_bool(key, text):
    lowered = text.lower()
    if lowered in ('1', 'true'):
        return True
    if lowered in ('0', 'false'):
        return False
    raise ValueError('%s must be 0, 1, true or false, got "%s"' % (key, text))


def _parse_number(key, text, kind, minimum):
    try:
        value = kind(text)
    except ValueError:
        value = None
    if value is None or not math.isfinite(value) or value < minimum:
        raise ValueError('%s must be %s >= %s, got "%s"'
                         % (key, 'an integer' if kind is int else 'a number', minimum, text))
    return value


def parse_synthetic_spec(spec):
    """Return the SyntheticCamera fault options a ``synthetic?key=value&...`` string asks for."""
    base, _, query = spec.partition('?')
    if base != 'synthetic':
        raise ValueError('"%s" is not a synthetic device (synthetic or synthetic?key=value)'
                         % spec)
    options = {}
    for key, value in parse_qsl(query, keep_blank_values=True):
        if key in options:
            raise ValueError('option %s is given twice' % key)
        if key == 'fail_open':
            options[key] = _parse_bool(key, value)
        elif key in ('stop_after', 'fail_every'):
            options[key] = _parse_number(key, value, int, 0 if key == 'stop_after' else 1)
        elif key == 'unplugged_for':
            options[key] = _parse_number(key, value, float, 0)
        elif key == 'formats':
            options[key] = tuple(f.strip() for f in value.split(',') if f.strip())
            if not options[key] or any(_picture_format(f) is None for f in options[key]):
                raise ValueError('formats must be a comma-separated list of %s, got "%s"'
                                 % (', '.join(_PICTURE_FORMATS), value))
        else:
            raise ValueError('unknown option "%s"; use synthetic?key=value&key=value with keys: %s'
                             % (key, _OPTIONS))
    if query and not options:
        raise ValueError('cannot read options "%s"; use key=value&key=value with keys: %s'
                         % (query, _OPTIONS))
    return options


def is_synthetic_spec(video_device):
    """Return True if a video_device string names the synthetic source."""
    return video_device == 'synthetic' or video_device.startswith('synthetic?')
