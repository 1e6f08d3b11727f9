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

`open_capture` returns an object with OpenCV's VideoCapture interface (isOpened, read, set, get,
release). `SyntheticCamera` and `VideoFileSource` also have `last_index` and
`last_capture_time` (time.monotonic() of the capture); a plain ``cv2.VideoCapture`` has not, so
callers use ``getattr(cap, 'last_capture_time', None)`` and fall back to the time read()
returned.
"""

import contextlib
import os
import stat
import sys

import cv2
import numpy as np

from py_vision.synthetic_camera import FramePacer, is_synthetic_spec, open_synthetic

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


def _open_camera(video_device, target, width, height, fps):
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
    return cap


def _device_problem(path):
    """Return why a device node cannot be used, or None."""
    if not os.access(path, os.R_OK | os.W_OK):
        return 'permission denied (is the user in the "video" group?)'
    return None


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
        return _open_camera(device, index, width, height, fps)
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
        return _open_camera(device, device, width, height, fps)
    if stat.S_ISREG(mode):
        if not os.access(device, os.R_OK):
            raise SourceError('cannot open video_device "%s": permission denied' % device)
        source = VideoFileSource(device, fps)
        if not source.isOpened():
            raise SourceError('cannot open video_device "%s": not a video file OpenCV can read'
                              % device)
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
