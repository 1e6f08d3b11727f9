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
The camera as usbcam_publisher sees it, without ROS: open with a pixel format, read, control.

`Camera.open()` opens what `video_device` names (frame_source), negotiates the pixel format the
camera sends over USB, and says what it really got: size, rate, format, and any request the
camera refused. In MJPEG mode the camera's own JPEG bytes are kept as they are (OpenCV's
CAP_PROP_CONVERT_RGB off), so a compressed stream never decodes and re-encodes; `Frame.bgr()`
decodes only when someone needs the pixels. Controls use usb_cam's parameter names and are
checked against the ranges the camera itself reports.
"""

from dataclasses import dataclass, field
from typing import Dict, List, Optional, Tuple

import cv2
import numpy as np

from py_vision.frame_source import CaptureSource, open_capture, SourceError, VideoFileSource
from py_vision.synthetic_camera import Control

__all__ = ['Camera', 'CONTROL_NAMES', 'Frame', 'PIXEL_FORMATS', 'SourceError']

PIXEL_FORMATS = ('auto', 'mjpeg', 'yuyv')
_FOURCCS = {'yuyv': float(cv2.VideoWriter_fourcc(*'YUYV')),
            'mjpeg': float(cv2.VideoWriter_fourcc(*'MJPG'))}
_FORMAT_NAMES = {value: name for name, value in _FOURCCS.items()}

# usb_cam's parameter names -> the camera's control; the three switches are booleans to users.
CONTROL_NAMES = ('brightness', 'contrast', 'saturation', 'sharpness', 'gain',
                 'auto_white_balance', 'white_balance', 'autoexposure', 'exposure',
                 'autofocus', 'focus')
_CONTROL_OF = {name: name for name in CONTROL_NAMES}
_CONTROL_OF['autoexposure'] = 'auto_exposure'
# V4L2's exposure menu: 1 is manual, 3 (aperture priority) is what UVC cameras call automatic.
_SWITCHES = {'autoexposure': (1, 3), 'auto_white_balance': (0, 1), 'autofocus': (0, 1)}
# Rates within this fraction of the request count as reached (drivers report 29.97 for 30).
_RATE_TOLERANCE = 0.02


@dataclass
class Frame:
    """One captured frame: BGR pixels, or the camera's JPEG bytes decoded only on demand."""

    index: Optional[int]
    capture_time: Optional[float]
    jpeg: Optional[np.ndarray] = None      # 1-D uint8, the camera's own bytes (MJPEG)
    _bgr: Optional[np.ndarray] = field(default=None, repr=False)
    decoded: bool = False                   # bgr() had to decode the JPEG

    def bgr(self) -> Optional[np.ndarray]:
        """Return the frame as a BGR image (decoding the camera's JPEG once); None if corrupt."""
        if self._bgr is None and self.jpeg is not None and not self.decoded:
            self.decoded = True
            self._bgr = cv2.imdecode(self.jpeg, cv2.IMREAD_COLOR)
        return self._bgr


class Camera:
    """An opened camera, video file or synthetic camera, with what it really gives."""

    def __init__(self, source: CaptureSource, device: str, pixel_format: str,
                 notes: List[str]):
        self.source = source
        self.device = device
        self.pixel_format = pixel_format   # 'yuyv', 'mjpeg', or 'file'
        self.notes = notes                 # requests the camera did not grant, in words
        self.width = int(source.get(cv2.CAP_PROP_FRAME_WIDTH))
        self.height = int(source.get(cv2.CAP_PROP_FRAME_HEIGHT))
        self.fps = float(source.get(cv2.CAP_PROP_FPS))
        self.frames_decoded = 0

    @classmethod
    def open(cls, device: str, width: int, height: int, fps: float,  # noqa: A003
             pixel_format: str = 'auto') -> 'Camera':
        """Open device with the size, rate and pixel format asked for; SourceError if it fails."""
        if pixel_format not in PIXEL_FORMATS:
            raise ValueError('pixel_format must be one of %s' % ', '.join(PIXEL_FORMATS))
        source = open_capture(device, width, height, fps)
        notes = []
        if isinstance(source, VideoFileSource):
            return cls(source, device, 'file', notes)
        try:
            chosen = _negotiate(source, device, width, height, fps, pixel_format, notes)
        except Exception:
            source.release()
            raise
        return cls(source, device, chosen, notes)

    def describe(self) -> str:
        """Return what the camera gives, for the log line on opening."""
        what = {'yuyv': 'YUYV', 'mjpeg': 'MJPEG', 'file': 'video file'}[self.pixel_format]
        return '%dx%d %s at %.4g fps' % (self.width, self.height, what, self.fps)

    def read(self) -> Optional[Frame]:
        """Wait for the next frame; None when the read failed."""
        ok, data = self.source.read()
        if not ok or data is None:
            return None
        index = self.source.last_index
        captured = self.source.last_capture_time
        if self.pixel_format == 'mjpeg':
            jpeg = np.ascontiguousarray(data).reshape(-1)
            if jpeg.size < 4 or jpeg[0] != 0xFF or jpeg[1] != 0xD8:
                return None  # not a JPEG: a corrupt USB transfer
            return Frame(index, captured, jpeg=jpeg)
        if data.ndim != 3 or data.shape[2] != 3:
            return None
        return Frame(index, captured, _bgr=data)

    @property
    def controls(self) -> Dict[str, Control]:
        """Return the camera's controls under usb_cam's names, with the camera's ranges."""
        own = self.source.controls()
        return {name: own[_CONTROL_OF[name]] for name in CONTROL_NAMES
                if _CONTROL_OF[name] in own}

    def set_control(self, name: str, value) -> Tuple[bool, Optional[object], str]:
        """
        Set a control; return (applied, the value the camera reports, what to tell the user).

        The message is empty when the camera took exactly the value; it says why when the
        control does not exist, the value is out of the camera's range, or the camera refused.
        """
        control = self.controls.get(name)
        if control is None:
            return False, None, '%s has no %s control' % (self.device, name)
        raw = _SWITCHES[name][bool(value)] if name in _SWITCHES else int(value)
        if not control.minimum <= raw <= control.maximum:
            return False, None, "%s: %s is out of the camera's range %d..%d" % (
                name, value, control.minimum, control.maximum)
        if not self.source.set(control.prop, raw):
            return False, None, '%s refused %s=%s' % (self.device, name, value)
        got = int(round(self.source.get(control.prop)))
        reported = (got == _SWITCHES[name][1]) if name in _SWITCHES else got
        if got != raw:
            return True, reported, '%s: the camera took %s instead of %s' % (
                name, reported, value)
        return True, reported, ''

    def interrupt(self) -> None:
        """End a read() waiting in another thread."""
        self.source.interrupt()

    def release(self) -> None:
        """Close the device."""
        self.source.release()


def _try_format(source, name, width, height, fps):
    """Ask for a pixel format at a size and rate; return (format name or None, rate obtained)."""
    source.set(cv2.CAP_PROP_FOURCC, _FOURCCS[name])
    # The camera keeps its JPEG bytes only with OpenCV's conversion off.
    source.set(cv2.CAP_PROP_CONVERT_RGB, 0 if name == 'mjpeg' else 1)
    source.set(cv2.CAP_PROP_FRAME_WIDTH, width)
    source.set(cv2.CAP_PROP_FRAME_HEIGHT, height)
    source.set(cv2.CAP_PROP_FPS, fps)
    got = _FORMAT_NAMES.get(source.get(cv2.CAP_PROP_FOURCC))
    if got is not None:
        source.set(cv2.CAP_PROP_CONVERT_RGB, 0 if got == 'mjpeg' else 1)
    return got, source.get(cv2.CAP_PROP_FPS)


def _negotiate(source, device, width, height, fps, pixel_format, notes):
    """Choose the pixel format; return its name and add what was not granted to notes."""
    wanted = ('yuyv', 'mjpeg') if pixel_format == 'auto' else (pixel_format,)
    got, rate = _try_format(source, wanted[0], width, height, fps)
    if pixel_format == 'auto' and (got != 'yuyv' or rate < fps * (1 - _RATE_TOLERANCE)):
        yuyv_rate = rate if got == 'yuyv' else 0.0
        got, rate = _try_format(source, 'mjpeg', width, height, fps)
        if got != 'mjpeg' or rate <= yuyv_rate:
            got, rate = _try_format(source, 'yuyv', width, height, fps)
    if got is None:
        raise SourceError('cannot open video_device "%s": it sends neither YUYV nor MJPEG'
                          % device)
    if pixel_format != 'auto' and got != pixel_format:
        notes.append('the camera refuses pixel_format %s; it gives %s instead' % (
            pixel_format, got))
    if rate < fps * (1 - _RATE_TOLERANCE):
        why = ''
        if got == 'yuyv':
            why = ' (YUYV at this size is limited by USB 2.0; pixel_format:=mjpeg or auto ' \
                  'reaches higher rates)'
        notes.append('%.4g fps requested, the camera gives %.4g fps in %s%s' % (
            fps, rate, got.upper(), why))
    return got
