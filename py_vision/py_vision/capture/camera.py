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
the camera sends (`pixel_format`: a FourCC of the table in pixel_formats, or
`auto`: the format that reaches the requested size and rate with the least work for the
output asked for), and says what it really got: size, rate, format, and any request the camera
refused. Frames are the camera's bytes as sent (`Frame`); a camera's JPEG is checked for being
whole without decoding it, and decoded only when someone needs its pixels. `start()` and
`stop()` start and stop the stream, the device kept open in between. Controls are the device's
own (`ControlInfo`), addressed by V4L2 id, and checked against what the device reports before
they reach it.
"""

import errno
import os
from typing import Dict, List, Mapping, Optional, Sequence, Tuple

import cv2
import numpy as np
from py_vision.capture.controls import check, ControlInfo, governed, Refusal
from py_vision.capture.devices import CAMERA, classify, FILE
from py_vision.capture.opencv_env import prepare_opencv
from py_vision.capture.pixel_formats import COLOUR_OUTPUTS, find, FORMATS, PixelFormat
from py_vision.capture.source import (
    BusFull, Clock, Frame, FrameFormat, FrameSource, MONOTONIC, SourceError, StreamFormat)
from py_vision.capture.synthetic_device import SyntheticDevices
from py_vision.capture.v4l2 import MEMORY_MMAP, MEMORY_USERPTR, V4L2Error
from py_vision.capture.v4l2_stream import BUFFERS, V4L2Source
from py_vision.capture.video_file import video_file_support, VideoFileSource

__all__ = ['Camera', 'open_source', 'pixel_format_accepted']

# V4L2's memory types in usb_cam's words for them (its io_method).
_IO_METHODS = {MEMORY_MMAP: 'mmap', MEMORY_USERPTR: 'userptr'}

# Rates within this fraction of the request count as reached (drivers report 29.97 for 30).
_RATE_TOLERANCE = 0.02


def pixel_format_accepted(value: str) -> bool:
    """Return True for a pixel_format value: auto, or a FourCC of the table."""
    return str(value).strip().lower() == 'auto' or find(value) is not None


def open_source(video_device, width, height, fps, *, synthetic: Optional[SyntheticDevices] = None,
                clock: Clock = MONOTONIC) -> FrameSource:
    """
    Open what `video_device` names (devices.classify) and return its FrameSource.

    The synthetic camera is one of `synthetic`, the process's synthetic devices (a new set when
    None); a video file plays in a loop, in real time (by `clock`); a V4L2 camera is streamed
    by py_vision (v4l2_stream). Raises SourceError (one line naming the device and the reason)
    when it does not open.
    """
    prepare_opencv()
    target = classify(video_device)
    device = target.device
    if target.kind == CAMERA:
        try:
            return V4L2Source(target.path)
        except V4L2Error as error:
            raise SourceError('cannot open video_device "%s": %s' % (device, error.reason)) \
                from None
    if target.kind == FILE:
        if not os.access(target.path, os.R_OK):
            raise SourceError('cannot open video_device "%s": permission denied' % device)
        source = VideoFileSource(target.path, fps, clock)
        if not source.isOpened():
            raise SourceError('cannot open video_device "%s": not a video file OpenCV can read%s'
                              % (device, video_file_support(cv2.getBuildInformation())))
        return source
    devices = synthetic if synthetic is not None else SyntheticDevices(clock)
    try:
        cap = devices.open(device, width, height, fps)
    except ValueError as error:
        raise SourceError('cannot open video_device "%s": %s' % (device, error)) from None
    if not cap.isOpened():
        raise SourceError('cannot open video_device "%s": %s' % (device, cap.error))
    return cap


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
        if header is not None and view[:len(header)] == header:
            return True
        length = _header_length(view, end)
        if length:
            self._header = data[:length].tobytes()
        return length > 0


class Camera:
    """An opened camera, video file or synthetic camera, with what it really gives."""

    def __init__(self, source: FrameSource, device: str, stream: StreamFormat,
                 notes: List[str], requested: Tuple[int, int, float] = (0, 0, 0.0)):
        self.source = source
        self.device = device
        self.stream = stream
        self.pixel_format: PixelFormat = stream.pixel_format
        self.file = isinstance(source, VideoFileSource)
        # The device node a V4L2 camera was found at (video_device:=auto, a by-id link).
        self.node = source.device.path if isinstance(source, V4L2Source) else None
        self.notes = notes                 # requests the camera did not grant, in words
        self.requested = requested         # width, height and rate asked for
        self.width, self.height, self.fps = stream.width, stream.height, stream.fps
        self.streaming = False
        self._whole_jpeg = _JpegCheck()

    @classmethod
    def open(cls, device: str, width: int, height: int, fps: float,  # noqa: A003
             pixel_format: str = 'auto', output: str = 'bgr8', *,
             synthetic: Optional[SyntheticDevices] = None,
             clock: Clock = MONOTONIC) -> 'Camera':
        """
        Open device with the size, rate and pixel format asked for; SourceError if it fails.

        `output` is what its frames will be converted to (bgr8, rgb8, mono8, mono16, native):
        `auto` chooses the format that costs least for it.
        """
        if not pixel_format_accepted(pixel_format):
            raise ValueError('pixel_format must be auto or one of %s' % ', '.join(FORMATS))
        source = open_source(device, width, height, fps, synthetic=synthetic, clock=clock)
        notes = []
        try:
            stream = _negotiate(source, device, width, height, fps, pixel_format, output, notes)
        except Exception:
            source.release()
            raise
        return cls(source, device, stream, notes, (width, height, fps))

    def describe(self) -> str:
        """Return what the camera gives, and what was asked when it differs, in one line."""
        what = 'video file' if self.file else self.pixel_format.fourcc
        line = '%dx%d %s at %.4g fps' % (self.width, self.height, what, self.fps)
        width, height, fps = self.requested
        if self.file:
            if width and (self.width, self.height) != (width, height):
                line += " (the file's own size; %dx%d requested)" % (width, height)
        elif (self.width, self.height) != (width, height) or \
                abs(self.fps - fps) > fps * _RATE_TOLERANCE:
            line += ' (%dx%d at %.4g fps requested: the nearest the camera offers)' % (
                width, height, fps)
        return line

    def start(self) -> None:
        """
        Start streaming (again); SourceError (one line) when the device will not.

        BusFull when the USB bus has no room for the stream now: another camera's stream
        takes it, and trying again later may succeed.
        """
        if self.streaming:
            return
        try:
            self.source.start()
        except V4L2Error as error:
            if error.errno == errno.ENOSPC:
                raise BusFull('cannot stream from video_device "%s": %s; use pixel_format '
                              'mjpg or h264, or a smaller size or rate (retrying)' % (
                                  self.device, error.reason)) from None
            raise SourceError('cannot stream from video_device "%s": %s' % (
                self.device, error.reason)) from None
        self.streaming = True

    def stop(self) -> None:
        """Stop streaming, keeping the device open with its buffers and controls."""
        if self.streaming:
            self.streaming = False
            self.source.stop()

    def read(self) -> Optional[Frame]:
        """
        Wait for the next frame; None when the read failed.

        A frame whose JPEG is not whole (a corrupt USB transfer) comes back with `corrupt` set;
        one the driver flagged as an error with `error` set. Its bytes are valid until the next
        read() or stop().
        """
        frame = self.source.next_frame()
        if frame is not None and frame.pixel_format.jpeg and frame.data is not None \
                and not frame.corrupt:
            frame.corrupt = not self._whole_jpeg(frame.data)
        return frame

    @property
    def buffer_bytes(self) -> int:
        """Return the bytes of an array capture_into() takes (0: a source that takes none)."""
        return self.source.buffer_bytes if isinstance(self.source, V4L2Source) else 0

    @property
    def sends_messages(self) -> bool:
        """
        Return True when native frames are a message's pixels as they are.

        A raw format with a sensor_msgs encoding whose rows have no padding: its bytes are
        the Image's data, with nothing converted or left out.
        """
        pixel_format, stream = self.pixel_format, self.stream
        return (pixel_format is not None and not pixel_format.compressed
                and pixel_format.encoding is not None
                and stream.bytesperline in (0, pixel_format.bytesperline(self.width)))

    @property
    def io_method(self) -> str:
        """Return how frames reach the program: 'mmap', 'userptr' or '' (no V4L2 buffers)."""
        if not isinstance(self.source, V4L2Source):
            return ''
        return _IO_METHODS.get(self.source.memory, '')

    @property
    def buffer_count(self) -> int:
        """Return how many arrays capture_into() takes: one for each buffer the camera has."""
        return BUFFERS

    def capture_into(self, arrays: Optional[Sequence[np.ndarray]]) -> bool:
        """
        Offer the camera memory to write its frames into, before start() (None: its own).

        Each array 1-D, writable uint8 of `buffer_bytes`; a frame written there names its
        array (`Frame.user_buffer`). False where the camera cannot (not a V4L2 device, or the
        arrays do not fit); a driver that refuses them at start() uses its own buffers.
        """
        if self.streaming:
            raise RuntimeError('capture_into() while streaming')
        return self.source.capture_into(arrays)

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
        """Stop streaming and close the device."""
        self.streaming = False
        self.source.release()


def _rank(pixel_format: PixelFormat, listed: Optional[FrameFormat], request, output: str):
    """
    Return how well a format serves a request (lower is better) for `auto`.

    Formats that reach the requested size and rate come first, the least work for `output`
    first among them (a format without colour last for a colour output, and fewer bits last
    for mono16); then the others, nearest size, then highest rate first.
    """
    width, height, fps = request
    got = listed.nearest(width, height, fps) if listed is not None else request
    fits = (pixel_format.mono and output in COLOUR_OUTPUTS,
            -min(pixel_format.bits, 16 if output == 'mono16' else 8))
    if got[:2] == (width, height) and got[2] >= fps * (1 - _RATE_TOLERANCE):
        return (0,) + fits + (pixel_format.cost(output),)
    outside = _outside_overlap(got[0], got[1], width, height)
    return (1, outside, -got[2]) + fits + (pixel_format.cost(output),)


def _outside_overlap(width, height, other_width, other_height):
    overlap = min(width, other_width) * min(height, other_height)
    return width * height + other_width * other_height - 2 * overlap


def _candidates(offered: Dict[str, FrameFormat], request, output: str) -> List[PixelFormat]:
    """Return the formats auto tries, best first: those offered that py_vision converts."""
    # A camera's own video is never chosen for the user: its frames are a stream, not images.
    known = [FORMATS[fourcc] for fourcc in FORMATS if (not offered or fourcc in offered)
             and not FORMATS[fourcc].video]
    return sorted(known, key=lambda pf: _rank(pf, offered.get(pf.fourcc), request, output))


def _negotiate(source, device, width, height, fps, wanted, output, notes) -> StreamFormat:
    """Choose the pixel format; return what the source gives and add what was not granted."""
    offered = {listed.fourcc: listed for listed in source.formats()}
    request = (width, height, fps)
    chosen = find(wanted) if wanted.strip().lower() != 'auto' else None
    candidates = _candidates(offered, request, output)
    if chosen is not None and (not offered or chosen.fourcc in offered):
        candidates = [chosen]
    if not candidates:
        raise SourceError('cannot open video_device "%s": it sends no pixel format py_vision '
                          'can convert (it offers %s)' % (device, ', '.join(offered)))
    for candidate in candidates:
        listed = offered.get(candidate.fourcc)
        asked = listed.nearest(width, height, fps) if listed is not None else request
        try:
            stream = source.configure(candidate, *asked)
        except V4L2Error as error:
            raise SourceError('cannot open video_device "%s": %s' % (device, error.reason)) \
                from None
        if stream.pixel_format is not None:
            break
    else:
        raise SourceError('cannot open video_device "%s": it sends %s, which py_vision cannot '
                          'convert' % (device, stream.fourcc))
    got = stream.pixel_format
    if chosen is not None and got is not chosen and not isinstance(source, VideoFileSource):
        offers = ' (it offers %s)' % ', '.join(offered) if chosen.fourcc not in offered else ''
        notes.append('the camera refuses pixel_format %s%s; it gives %s instead' % (
            wanted, offers, got.fourcc))
    if stream.fps < fps * (1 - _RATE_TOLERANCE) and not isinstance(source, VideoFileSource):
        notes.append('%.4g fps requested, the camera gives %.4g fps in %s%s' % (
            fps, stream.fps, got.fourcc, _faster(offered, got, stream, wanted)))
    return stream


def _faster(offered, got, stream, wanted) -> str:
    """Return a hint naming a compressed format that reaches a higher rate, or ''."""
    if got.compressed:
        return ''
    for fourcc, listed in offered.items():
        pixel_format = find(fourcc)
        if pixel_format is not None and pixel_format.compressed and listed.nearest(
                stream.width, stream.height, 1000.0)[2] > stream.fps:
            hint = 'auto reaches higher rates' if wanted.strip().lower() == 'auto' else \
                'pixel_format:=%s or auto reaches higher rates' % fourcc.lower()
            return ' (%s at this size is limited by the bus; %s)' % (got.fourcc, hint)
    return ''
