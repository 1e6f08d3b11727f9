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


"""A video file as a camera: VideoCapture's interface, real-time pacing, looping."""

import os
import re
from typing import List, Optional

import cv2
import numpy as np
from py_vision.capture.controls import ControlInfo
from py_vision.capture.opencv_env import prepare_opencv
from py_vision.capture.pacing import FramePacer
from py_vision.capture.pixel_formats import OPENCV_BGR, PixelFormat
from py_vision.capture.source import Clock, Frame, FrameFormat, MONOTONIC, StreamFormat

__all__ = ['video_file_support', 'VideoFileSource']

_DEFAULT_FILE_FPS = 30.0


def video_file_support(build_information: str) -> str:
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

    def __init__(self, path, fps=0.0, clock: Clock = MONOTONIC):
        self.path = path
        self._clock = clock
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
            self._pacer = FramePacer(_DEFAULT_FILE_FPS, drop=False, clock=clock)
            return
        self._size = (first.shape[1], first.shape[0])
        rate = fps if fps and fps > 0 else self._file_fps
        self._pacer = FramePacer(rate if 0 < rate <= 1000 else _DEFAULT_FILE_FPS, drop=False,
                                 clock=clock)

    def _reopen(self):
        """(Re)open the file by its path; return its first frame, or None."""
        if self._cap is not None:
            self._cap.release()
            self._cap = None
        if not os.path.isfile(self.path):
            return None
        prepare_opencv()
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
        """Make the read() waiting for its frame in another thread (or the next) fail now."""
        self._pacer.cancel()

    def configure(self, pixel_format: PixelFormat, width: int, height: int,
                  fps: float) -> StreamFormat:
        """Play at fps (the file's own rate when <= 0); return its own size, in BGR."""
        self.set(cv2.CAP_PROP_FPS, fps)
        width, height = self._size
        return StreamFormat(OPENCV_BGR.fourcc, width, height, self._pacer.fps,
                            OPENCV_BGR.bytesperline(width))

    def start(self) -> None:
        """Play: frames come from the next next_frame() on."""

    def stop(self) -> None:
        """Pause: playing goes on from the same frame."""

    def capture_into(self, arrays) -> bool:
        """Return False: frames are made in memory of the source's own."""
        return False

    def next_frame(self) -> Optional[Frame]:
        """Wait until the next frame is due and return it (BGR), or None when the file fails."""
        if not self.grab():
            return None
        frame, self._grabbed = self._grabbed, None
        width, height = self._size
        return Frame(self.last_index, self.last_capture_time, OPENCV_BGR, width, height,
                     frame.reshape(-1), OPENCV_BGR.bytesperline(width))

    def formats(self) -> List[FrameFormat]:
        """Return nothing: a file has the one size it was recorded at."""
        return []

    def controls(self) -> List[ControlInfo]:
        """Return no controls: a file has none."""
        return []

    def set_control(self, cid: int, value: int) -> Optional[str]:
        """Refuse: a file has no controls."""
        return 'a video file has no controls'

    def grab(self):
        """Wait until the next frame is due and read it from the file; False on failure."""
        self._grabbed = None
        if self._cap is None:
            return False
        scheduled = self._pacer.wait()
        if scheduled is None:
            return False
        due = scheduled[1]
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
