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
Open what the `video_device` parameter names: a camera, a video file or the synthetic source.

`open_capture` returns a `CaptureSource`: OpenCV's VideoCapture interface (isOpened, read, set,
get, release) plus what a driver needs from every source alike: the capture time and source
index of the last frame, the camera's controls with their ranges, and interrupt() to end a
read that waits for its frame. V4L2 cameras are OpenCV captures wrapped in `V4L2Source`, which
reads the driver's buffer timestamps and asks the device itself for its controls' ranges
(OpenCV has no call for that); the synthetic camera and video files implement it directly.
"""

import contextlib
import fcntl
import os
import re
import stat
import struct
import sys
import time
from typing import Dict, Optional, Protocol, Tuple

import cv2
import numpy as np

from py_vision.synthetic_camera import (
    Control, CONTROLS, FramePacer, is_synthetic_spec, open_synthetic)


class CaptureSource(Protocol):
    """What usbcam_publisher's camera layer uses from a frame source."""

    last_index: Optional[int]          # source frame number of the last frame read, if known
    last_capture_time: Optional[float]  # its capture time, time.monotonic(), if known

    def isOpened(self) -> bool: ...  # noqa: N802, D102 (OpenCV's interface)

    def read(self) -> Tuple[bool, Optional[np.ndarray]]: ...  # noqa: D102

    def set(self, prop_id: int, value: float) -> bool: ...  # noqa: A003, D102

    def get(self, prop_id: int) -> float: ...  # noqa: D102

    def release(self) -> None: ...  # noqa: D102

    def interrupt(self) -> None: ...  # noqa: D102

    def controls(self) -> Dict[str, Control]: ...  # noqa: D102


_DEFAULT_FILE_FPS = 30.0


class SourceError(Exception):
    """A video_device that cannot be opened; the message is one line naming it."""


@contextlib.contextmanager
def _quiet_opencv():
    """Silence OpenCV's own log lines (e.g. cap_v4l.cpp warnings) while opening a device."""
    # OpenCV 4.5+ and 5.x: cv2.utils.logging; some 4.x builds only have cv2.setLogLevel.
    logging = getattr(getattr(cv2, 'utils', None), 'logging', None)
    get_level = getattr(logging, 'getLogLevel', None) or getattr(cv2, 'getLogLevel', None)
    set_level = getattr(logging, 'setLogLevel', None) or getattr(cv2, 'setLogLevel', None)
    silent = getattr(logging, 'LOG_LEVEL_SILENT', 0)
    if get_level is None or set_level is None:
        yield
        return
    previous = get_level()
    set_level(silent)
    try:
        yield
    finally:
        set_level(previous)


def _request(cap, width, height, fps):
    cap.set(cv2.CAP_PROP_FRAME_WIDTH, width)
    cap.set(cv2.CAP_PROP_FRAME_HEIGHT, height)
    if fps > 0:
        cap.set(cv2.CAP_PROP_FPS, fps)


def _open_camera(video_device, target, node, width, height, fps):
    """Open a V4L2 device (a path or an index) through OpenCV."""
    backend = cv2.CAP_V4L2 if sys.platform.startswith('linux') else cv2.CAP_ANY
    with _quiet_opencv():
        cap = cv2.VideoCapture(target, backend)
        opened = cap.isOpened()
        if opened:
            _request(cap, width, height, fps)
    if not opened:
        cap.release()
        raise SourceError('cannot open video_device "%s": the device exists but does not open '
                          '(busy in another program, or not a video capture device)'
                          % video_device)
    return V4L2Source(cap, node)


# struct v4l2_queryctrl: id, type, name[32], minimum, maximum, step, default_value, flags,
# reserved[2]; VIDIOC_QUERYCTRL = _IOWR('V', 36, struct v4l2_queryctrl).
_QUERYCTRL = struct.Struct('=II32siiiiI8x')
_VIDIOC_QUERYCTRL = (3 << 30) | (_QUERYCTRL.size << 16) | (ord('V') << 8) | 36
_CTRL_FLAG_DISABLED = 0x0001
_USER, _CAMERA = 0x00980900, 0x009A0900
_V4L2_CONTROL_IDS = {
    'brightness': _USER + 0, 'contrast': _USER + 1, 'saturation': _USER + 2,
    'auto_white_balance': _USER + 12, 'gain': _USER + 19, 'white_balance': _USER + 26,
    'sharpness': _USER + 27, 'auto_exposure': _CAMERA + 1, 'exposure': _CAMERA + 2,
    'focus': _CAMERA + 10, 'autofocus': _CAMERA + 12,
}


def query_v4l2_controls(path):
    """Return the controls a V4L2 device has, with their ranges (VIDIOC_QUERYCTRL)."""
    found = {}
    try:
        fd = os.open(path, os.O_RDWR | os.O_NONBLOCK)
    except OSError:
        return found
    try:
        for name, cid in _V4L2_CONTROL_IDS.items():
            query = bytearray(_QUERYCTRL.pack(cid, 0, b'', 0, 0, 0, 0, 0))
            try:
                fcntl.ioctl(fd, _VIDIOC_QUERYCTRL, query)
            except OSError:
                continue  # the device has no such control
            _, _, _, low, high, _, default, flags = _QUERYCTRL.unpack(query)
            if not flags & _CTRL_FLAG_DISABLED:
                found[name] = Control(CONTROLS[name].prop, low, high, default)
    finally:
        os.close(fd)
    return found


class V4L2Source:
    """A V4L2 camera opened by OpenCV, with the driver's capture times and its controls."""

    def __init__(self, cap, node):
        self._cap = cap
        self._node = node
        self._controls = None
        self.last_index = None
        self.last_capture_time = None

    def isOpened(self):  # noqa: N802 (OpenCV's name)
        """Return True while the device is open."""
        return self._cap.isOpened()

    def read(self):
        """Read a frame; its capture time is the driver's buffer timestamp when plausible."""
        ok, frame = self._cap.read()
        self.last_capture_time = None
        if ok:
            # OpenCV's V4L2 backend gives the buffer's CLOCK_MONOTONIC time in ms here.
            captured = self._cap.get(cv2.CAP_PROP_POS_MSEC) / 1e3
            if 0 <= time.monotonic() - captured < 1.0:
                self.last_capture_time = captured
        return ok, frame

    def set(self, prop_id, value):  # noqa: A003 (OpenCV's name)
        """Set an OpenCV capture property; False when the driver refuses."""
        return bool(self._cap.set(prop_id, value))

    def get(self, prop_id):
        """Return an OpenCV capture property."""
        return float(self._cap.get(prop_id))

    def release(self):
        """Close the device."""
        self._cap.release()

    def interrupt(self):
        """Nothing to do: a V4L2 read returns within one frame period."""

    def controls(self):
        """Return the device's controls and their ranges, asked once from the driver."""
        if self._controls is None:
            self._controls = query_v4l2_controls(self._node) if self._node else {}
        return dict(self._controls)


def _device_problem(path):
    """Return why a device node cannot be used, or None."""
    if not os.access(path, os.R_OK | os.W_OK):
        return 'permission denied (is the user in the "video" group?)'
    return None


def video_file_support(build_information):
    """
    Return '' or why this OpenCV reads few video files, from cv2.getBuildInformation().

    OpenCV reads video files through FFmpeg, else through GStreamer (whose plugins decide
    which formats open), else only MJPEG .avi files with its own reader. The boards' OpenCV
    has no FFmpeg.
    """
    def built_with(backend):
        found = re.search(r'^\s*%s:\s*(\S+)' % backend, build_information, re.MULTILINE)
        return bool(found) and found.group(1).upper() != 'NO'
    if built_with('FFMPEG'):
        return ''
    if built_with('GStreamer'):
        return (' (this OpenCV has no FFmpeg: it reads files through GStreamer, which could not '
                'open this one; install the GStreamer plugins for its format, e.g. '
                'gstreamer1.0-plugins-good, -bad or -libav)')
    return ' (this OpenCV has neither FFmpeg nor GStreamer: it reads only MJPEG .avi files)'


def open_capture(video_device, width, height, fps):
    """
    Open what `video_device` names and return a VideoCapture-like object.

    - ``synthetic`` or ``synthetic?key=value&...``: the synthetic V4L2 source;
    - an integer (``0``): that OpenCV camera index (V4L2 on Linux);
    - a character device (``/dev/video0``): that V4L2 camera;
    - a regular file: a VideoFileSource playing it in a loop, in real time.

    Cameras are asked for width, height and fps; read the size they really give with get().
    Raises SourceError (one line naming the device and the reason) when it does not open.
    """
    device = str(video_device)
    if is_synthetic_spec(device):
        try:
            cap = open_synthetic(device, width, height, fps)
        except ValueError as error:
            raise SourceError('cannot open video_device "%s": %s' % (device, error)) from None
        if not cap.isOpened():
            raise SourceError('cannot open video_device "%s": %s' % (device, cap.error))
        return cap
    if device.strip().isdigit():
        index = int(device)
        node = '/dev/video%d' % index
        if sys.platform.startswith('linux'):
            if not os.path.exists(node):
                raise SourceError('cannot open video_device "%s": no camera %s (%s does not '
                                  'exist)' % (device, index, node))
            problem = _device_problem(node)
            if problem:
                raise SourceError('cannot open video_device "%s": %s: %s'
                                  % (device, node, problem))
        return _open_camera(device, index, node, width, height, fps)
    try:
        mode = os.stat(device).st_mode
    except FileNotFoundError:
        raise SourceError('cannot open video_device "%s": no such device or file'
                          % device) from None
    except OSError as error:
        raise SourceError('cannot open video_device "%s": %s'
                          % (device, error.strerror or error)) from None
    if stat.S_ISCHR(mode):
        problem = _device_problem(device)
        if problem:
            raise SourceError('cannot open video_device "%s": %s' % (device, problem))
        return _open_camera(device, device, device, width, height, fps)
    if stat.S_ISREG(mode):
        if not os.access(device, os.R_OK):
            raise SourceError('cannot open video_device "%s": permission denied' % device)
        source = VideoFileSource(device, fps)
        if not source.isOpened():
            raise SourceError('cannot open video_device "%s": not a video file OpenCV can read%s'
                              % (device, video_file_support(cv2.getBuildInformation())))
        return source
    if stat.S_ISDIR(mode):
        raise SourceError('cannot open video_device "%s": is a directory' % device)
    raise SourceError('cannot open video_device "%s": neither a video device nor a regular file'
                      % device)


class VideoFileSource:
    """
    A video file as a camera: VideoCapture's interface, real-time pacing, looping.

    Frames come at `fps` (the file's own rate when fps <= 0) at the file's real size, which
    get() reports; set() cannot change the size. At the end the file is reopened by its path
    and played again; once the file is gone or unreadable, reads fail (as a camera's do when
    it is unplugged). A caller that falls behind gets the next frame at once and the schedule
    restarts from it: file frames are not skipped. `last_index` counts frames from 0 across
    loops; `last_capture_time` is the time.monotonic() at which the frame was due.
    """

    def __init__(self, path, fps=0.0):
        self.path = path
        self.last_index = None
        self.last_capture_time = None
        self._count = 0
        self._pending = None
        self._grabbed = None
        self._cap = None
        self._size = (0, 0)
        self._file_fps = 0.0
        first = self._reopen()
        self._pending = first
        if first is None:
            self.release()
            self._pacer = FramePacer(_DEFAULT_FILE_FPS, drop=False)
            return
        self._size = (first.shape[1], first.shape[0])
        rate = fps if fps and fps > 0 else self._file_fps
        self._pacer = FramePacer(rate if 0 < rate <= 1000 else _DEFAULT_FILE_FPS, drop=False)

    def _reopen(self):
        """(Re)open the file by its path; return its first frame, or None."""
        if self._cap is not None:
            self._cap.release()
            self._cap = None
        if not os.path.isfile(self.path):
            return None
        with _quiet_opencv():
            cap = cv2.VideoCapture(self.path)
            ok, frame = cap.read() if cap.isOpened() else (False, None)
        if not ok or frame is None:
            cap.release()
            return None
        self._cap = cap
        self._file_fps = cap.get(cv2.CAP_PROP_FPS) or 0.0
        return frame

    def _next_frame(self):
        if self._pending is not None:
            frame, self._pending = self._pending, None
            return frame
        if not os.path.isfile(self.path):
            self.release()
            return None
        ok, frame = self._cap.read()
        if not ok or frame is None:
            frame = self._reopen()
        return frame

    def isOpened(self):  # noqa: N802 (OpenCV's name)
        """Return True while the file is open."""
        return self._cap is not None

    def release(self):
        """Close the file; reads fail afterwards."""
        if self._cap is not None:
            self._cap.release()
        self._cap = None
        self._pending = None

    def interrupt(self):
        """Make a read() waiting for its frame in another thread fail at once, and later ones."""
        self._pacer.cancel()

    def controls(self):
        """Return no controls: a file has none."""
        return {}

    def grab(self):
        """Wait until the next frame is due and read it from the file; False on failure."""
        self._grabbed = None
        if self._cap is None:
            return False
        _, due = self._pacer.wait()
        if self._pacer.cancelled.is_set():
            return False
        frame = self._next_frame()
        if frame is None:
            self.release()
            return False
        if frame.ndim == 2:
            frame = cv2.cvtColor(frame, cv2.COLOR_GRAY2BGR)
        if frame.shape[1::-1] != self._size:
            # A file whose size changes mid-stream: keep the advertised size.
            frame = cv2.resize(frame, self._size, interpolation=cv2.INTER_AREA)
        self._grabbed = np.ascontiguousarray(frame)
        self.last_index, self.last_capture_time = self._count, due
        self._count += 1
        return True

    def retrieve(self, image=None, flag=0):
        """Return the grabbed frame (BGR) or (False, None)."""
        if self._grabbed is None:
            return False, None
        frame, self._grabbed = self._grabbed, None
        return True, frame

    def read(self, image=None):
        """Grab and retrieve: (True, BGR image) or (False, None)."""
        if not self.grab():
            return False, None
        return self.retrieve()

    def set(self, prop_id, value):  # noqa: A003 (OpenCV's name)
        """Set the playback rate (CAP_PROP_FPS); the size of a file cannot change."""
        if self._cap is None or int(prop_id) != cv2.CAP_PROP_FPS:
            return False
        try:
            rate = float(value)
        except (TypeError, ValueError):
            return False
        if rate <= 0:
            rate = self._file_fps
        if not 0 < rate <= 1000:
            return False
        if rate != self._pacer.fps:
            self._pacer.fps = rate
            self._pacer.restart()
        return True

    def get(self, prop_id):
        """Return the real size, the playback fps, the frame count or last capture time."""
        if self._cap is None:
            return 0.0
        prop_id = int(prop_id)
        if prop_id == cv2.CAP_PROP_FRAME_WIDTH:
            return float(self._size[0])
        if prop_id == cv2.CAP_PROP_FRAME_HEIGHT:
            return float(self._size[1])
        if prop_id == cv2.CAP_PROP_FPS:
            return float(self._pacer.fps)
        if prop_id == cv2.CAP_PROP_POS_FRAMES:
            return float(self._count)
        if prop_id == cv2.CAP_PROP_POS_MSEC:
            return 0.0 if self.last_capture_time is None else self.last_capture_time * 1000.0
        return float(self._cap.get(prop_id))
