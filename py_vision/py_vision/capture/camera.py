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
A camera as usbcam_publisher sees it, without ROS: open with a pixel format, read, control.

`Camera.open()` opens what `video_device` names (`open_source`), negotiates the pixel format
the camera sends over USB, and says what it really got: size, rate, format, and any request the
camera refused. In MJPEG mode the camera's own JPEG bytes are kept as they are (OpenCV's
CAP_PROP_CONVERT_RGB off), so a compressed stream never decodes and re-encodes; `Frame.bgr()`
decodes only when someone needs the pixels. Controls are the device's own (`ControlInfo`),
addressed by V4L2 id, and checked against what the device reports before they reach it.
"""

import os
import stat
import sys
from typing import Dict, List, Mapping, Optional, Tuple

import cv2
import numpy as np
from py_vision.capture.controls import check, ControlInfo, governed, Refusal
from py_vision.capture.opencv_env import prepare_opencv
from py_vision.capture.source import (
    Clock, Frame, FrameFormat, FrameSource, MONOTONIC, SourceError)
from py_vision.capture.synthetic_device import is_synthetic_spec, SyntheticDevices
from py_vision.capture.v4l2 import open_v4l2, V4L2Error, V4L2Source
from py_vision.capture.video_file import video_file_support, VideoFileSource

__all__ = ['Camera', 'index_node', 'open_source', 'PIXEL_FORMATS']

PIXEL_FORMATS = ('auto', 'mjpeg', 'yuyv')
_V4L2_NAMES = {'yuyv': 'YUYV', 'mjpeg': 'MJPG'}
_FOURCCS = {name: float(cv2.VideoWriter_fourcc(*code)) for name, code in _V4L2_NAMES.items()}
_FORMAT_NAMES = {value: name for name, value in _FOURCCS.items()}
# Rates within this fraction of the request count as reached (drivers report 29.97 for 30).
_RATE_TOLERANCE = 0.02


def _request(cap, width, height, fps):
    cap.set(cv2.CAP_PROP_FRAME_WIDTH, width)
    cap.set(cv2.CAP_PROP_FRAME_HEIGHT, height)
    if fps > 0:
        cap.set(cv2.CAP_PROP_FPS, fps)


def _open_camera(video_device, path, target, width, height, fps):
    """Open a V4L2 device (a path or an index): our own handle, then OpenCV's capture."""
    backend = cv2.CAP_V4L2 if sys.platform.startswith('linux') else cv2.CAP_ANY
    try:
        device, cap = open_v4l2(path, target, lambda what: cv2.VideoCapture(what, backend))
    except V4L2Error as error:
        raise SourceError('cannot open video_device "%s": %s' % (video_device, error.reason)) \
            from None
    _request(cap, width, height, fps)
    return V4L2Source(cap, device)


def index_node(video_device: str) -> Optional[str]:
    """Return /dev/video<N> when video_device is a camera index (ASCII digits), else None."""
    index = video_device.strip()
    return '/dev/video%d' % int(index) if index.isascii() and index.isdigit() else None


def open_source(video_device, width, height, fps, *, synthetic: Optional[SyntheticDevices] = None,
                clock: Clock = MONOTONIC) -> FrameSource:
    """
    Open what `video_device` names and return its FrameSource.

    - ``synthetic`` or ``synthetic?key=value&...``: the synthetic camera (of `synthetic`, the
      process's synthetic devices; a new set when None);
    - an integer (``0``): that V4L2 camera, /dev/video<N>;
    - a character device (``/dev/video0``, ``/dev/v4l/by-id/...``): that V4L2 camera, the
      link followed now;
    - a regular file: a VideoFileSource playing it in a loop, in real time (by `clock`).

    Cameras are asked for width, height and fps; read the size they really give with get().
    Raises SourceError (one line naming the device and the reason) when it does not open.
    """
    prepare_opencv(fps)
    device = str(video_device)
    if is_synthetic_spec(device):
        devices = synthetic if synthetic is not None else SyntheticDevices(clock)
        try:
            cap = devices.open(device, width, height, fps)
        except ValueError as error:
            raise SourceError('cannot open video_device "%s": %s' % (device, error)) from None
        if not cap.isOpened():
            raise SourceError('cannot open video_device "%s": %s' % (device, cap.error))
        return cap
    node = index_node(device)
    if node is not None:
        if not os.path.exists(node):
            raise SourceError('cannot open video_device "%s": no camera %s (%s does not '
                              'exist)' % (device, device.strip(), node))
        return _open_camera(device, node, node, width, height, fps)
    # A by-id or by-path link names the camera wherever it is plugged: follow it each time.
    path = os.path.realpath(device)
    try:
        mode = os.stat(path).st_mode
    except FileNotFoundError:
        raise SourceError('cannot open video_device "%s": no such device or file'
                          % device) from None
    except OSError as error:
        raise SourceError('cannot open video_device "%s": %s'
                          % (device, error.strerror or error)) from None
    if stat.S_ISCHR(mode):
        return _open_camera(device, path, path, width, height, fps)
    if stat.S_ISREG(mode):
        if not os.access(path, os.R_OK):
            raise SourceError('cannot open video_device "%s": permission denied' % device)
        source = VideoFileSource(path, fps, clock)
        if not source.isOpened():
            raise SourceError('cannot open video_device "%s": not a video file OpenCV can read%s'
                              % (device, video_file_support(cv2.getBuildInformation())))
        return source
    if stat.S_ISDIR(mode):
        raise SourceError('cannot open video_device "%s": is a directory' % device)
    raise SourceError('cannot open video_device "%s": neither a video device nor a regular file'
                      % device)


def _header_length(view, end: int) -> int:
    """
    Return where the scan starts when view[:end] begins with a JPEG header that holds together.

    SOI, then marker segments whose lengths chain up to the start of scan (SOS): a header
    overwritten with noise fails here. 0 when it does not hold together.
    """
    if end < 8 or view[0] != 0xFF or view[1] != 0xD8:
        return 0
    position = 2
    for _ in range(64):   # a JPEG header has a dozen segments or so
        if position + 4 > end or view[position] != 0xFF:
            return 0
        marker = view[position + 1]
        if marker == 0xDA:    # start of scan: the header holds together
            return position
        if marker == 0xFF:    # fill byte
            position += 1
        else:
            position += 2 + (view[position + 2] << 8 | view[position + 3])
    return 0


class _JpegCheck:
    """
    Tell whether a camera's JPEG is shaped like a whole one, without decoding it.

    A whole JPEG has a header that holds together (`_header_length`) and EOI at its end (a UVC
    payload may be padded after it): a transfer cut short, noise in the header or a missing end
    fail here. Damage inside the scan itself shows when it is decoded. A camera sends the same
    header (its tables) frame after frame, so a header byte-for-byte the same as the last one
    that held together is not walked again: one comparison in C instead of a dozen segments in
    Python, every frame.
    """

    def __init__(self):
        self._header = None   # bytes of the last header that held together

    def __call__(self, data: np.ndarray) -> bool:
        """Return True when data (1-D uint8) is shaped like a whole JPEG."""
        view = data.data     # indexing a memoryview gives ints, many times faster than numpy's
        end = len(view)
        while end > 2 and view[end - 1] == 0:
            end -= 1
        if end < 8 or view[end - 2] != 0xFF or view[end - 1] != 0xD9:
            return False
        header = self._header
        if header is not None and data[:len(header)].tobytes() == header:
            return True
        length = _header_length(view, end)
        if length:
            self._header = data[:length].tobytes()
        return length > 0


class Camera:
    """An opened camera, video file or synthetic camera, with what it really gives."""

    def __init__(self, source: FrameSource, device: str, pixel_format: str,
                 notes: List[str], requested: Tuple[int, int, float] = (0, 0, 0.0)):
        self.source = source
        self.device = device
        self.pixel_format = pixel_format   # 'yuyv', 'mjpeg', or 'file'
        self.notes = notes                 # requests the camera did not grant, in words
        self.requested = requested         # width, height and rate asked for
        self.width = int(source.get(cv2.CAP_PROP_FRAME_WIDTH))
        self.height = int(source.get(cv2.CAP_PROP_FRAME_HEIGHT))
        self.fps = float(source.get(cv2.CAP_PROP_FPS))
        self._whole_jpeg = _JpegCheck()

    @classmethod
    def open(cls, device: str, width: int, height: int, fps: float,  # noqa: A003
             pixel_format: str = 'auto', *, synthetic: Optional[SyntheticDevices] = None,
             clock: Clock = MONOTONIC) -> 'Camera':
        """Open device with the size, rate and pixel format asked for; SourceError if it fails."""
        if pixel_format not in PIXEL_FORMATS:
            raise ValueError('pixel_format must be one of %s' % ', '.join(PIXEL_FORMATS))
        source = open_source(device, width, height, fps, synthetic=synthetic, clock=clock)
        notes = []
        requested = (width, height, fps)
        if isinstance(source, VideoFileSource):
            return cls(source, device, 'file', notes, requested)
        try:
            chosen = _negotiate(source, device, width, height, fps, pixel_format, notes)
        except Exception:
            source.release()
            raise
        return cls(source, device, chosen, notes, requested)

    def describe(self) -> str:
        """Return what the camera gives, and what was asked when it differs, in one line."""
        what = {'yuyv': 'YUYV', 'mjpeg': 'MJPEG', 'file': 'video file'}[self.pixel_format]
        line = '%dx%d %s at %.4g fps' % (self.width, self.height, what, self.fps)
        width, height, fps = self.requested
        if self.pixel_format == 'file':
            if width and (self.width, self.height) != (width, height):
                line += " (the file's own size; %dx%d requested)" % (width, height)
        elif (self.width, self.height) != (width, height) or \
                abs(self.fps - fps) > fps * _RATE_TOLERANCE:
            line += ' (%dx%d at %.4g fps requested: the nearest the camera offers)' % (
                width, height, fps)
        return line

    def read(self) -> Optional[Frame]:
        """
        Wait for the next frame; None when the read failed.

        A frame whose JPEG is not whole (a corrupt USB transfer) comes back with `corrupt` set.
        """
        source = self.source
        ok, data = source.read()
        if not ok or data is None:
            return None
        if self.pixel_format == 'mjpeg':
            jpeg = data.reshape(-1)   # OpenCV's buffer is contiguous: a view
            return Frame(source.last_index, source.last_capture_time, self.width, self.height,
                         jpeg=jpeg, corrupt=not self._whole_jpeg(jpeg))
        whole = data.ndim == 3 and data.shape[2] == 3
        return Frame(source.last_index, source.last_capture_time,
                     data.shape[1] if whole else 0, data.shape[0],
                     _bgr=data if whole else None, corrupt=not whole)

    def formats(self) -> List[FrameFormat]:
        """Return the pixel formats, sizes and rates the device offers (none for a file)."""
        return self.source.formats()

    def controls(self) -> List[ControlInfo]:
        """Return the device's controls with their values, and what holds the inactive ones."""
        return governed(self.source.controls())

    def set_controls(self, values: Mapping[int, int]) -> Dict[int, Refusal]:
        """
        Set controls (V4L2 id -> value; a button: pressed); return why some were not set.

        Automatic modes are set first, so that the controls they free take the values asked
        for (controls.check); what the device reports refusing (read-only, inactive, out of
        its range, step or menu) never reaches it.
        """
        ordered, refused = check(self.controls(), values)
        for cid, value in ordered:
            reason = self.source.set_control(cid, value)
            if reason:
                refused[cid] = Refusal(cid, ': %s refused %s (%s)' % (self.device, value, reason))
        return refused

    def interrupt(self) -> None:
        """End a read() waiting in another thread."""
        self.source.interrupt()

    def release(self) -> None:
        """Close the device."""
        self.source.release()


def _try_format(source, offered, name, width, height, fps):
    """
    Ask for a pixel format at a size and rate; return (format name or None, rate obtained).

    The size and rate asked for are the nearest the device lists for that format (`offered`,
    by V4L2 FOURCC), so what the driver gives is what the device's enumeration says.
    """
    listed = offered.get(_V4L2_NAMES[name])
    if listed is not None:
        width, height, fps = listed.nearest(width, height, fps)
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
    offered = {listed.fourcc: listed for listed in source.formats()}
    wanted = ('yuyv', 'mjpeg') if pixel_format == 'auto' else (pixel_format,)
    got, rate = _try_format(source, offered, wanted[0], width, height, fps)
    if pixel_format == 'auto' and (got != 'yuyv' or rate < fps * (1 - _RATE_TOLERANCE)):
        yuyv_rate = rate if got == 'yuyv' else 0.0
        got, rate = _try_format(source, offered, 'mjpeg', width, height, fps)
        if got != 'mjpeg' or rate <= yuyv_rate:
            got, rate = _try_format(source, offered, 'yuyv', width, height, fps)
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
