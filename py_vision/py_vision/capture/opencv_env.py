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
OpenCV as the camera layer needs it: quiet, and quick to give up on a camera that sends nothing.

OpenCV's V4L2 backend prints warnings of its own (``[ WARN:0@7.4] global cap_v4l.cpp:804
requestBuffers ... errno=19`` at an unplug) on stderr: py_vision says what happened in its own
words instead, so OpenCV is silenced for the life of the process before the first capture
opens. The backend also waits up to 10 s (its default select() timeout) for a frame of a camera
that stalled; it reads OPENCV_VIDEOIO_V4L_SELECT_TIMEOUT once, at its first wait, so the
timeout is set here, before then, to a few frame periods.
"""

import math
import os

import cv2

__all__ = ['prepare_opencv']


def prepare_opencv(fps: float = 30.0) -> None:
    """Silence OpenCV's log and bound its V4L2 read wait for a camera at fps (idempotent)."""
    os.environ.setdefault('OPENCV_LOG_LEVEL', 'SILENT')
    # FFmpeg's own messages (a stream it decodes ending mid-picture) too: AV_LOG_QUIET.
    os.environ.setdefault('OPENCV_FFMPEG_LOGLEVEL', '-8')
    # Whole seconds: at least 1, and at least three frame periods of a slow camera.
    seconds = max(1, math.ceil(3.0 / fps)) if fps > 0 else 10
    os.environ.setdefault('OPENCV_VIDEOIO_V4L_SELECT_TIMEOUT', str(seconds))
    # OpenCV 4.5+ and 5.x: cv2.utils.logging; some 4.x builds only have cv2.setLogLevel.
    logging = getattr(getattr(cv2, 'utils', None), 'logging', None)
    set_level = getattr(logging, 'setLogLevel', None) or getattr(cv2, 'setLogLevel', None)
    if set_level is not None:
        set_level(getattr(logging, 'LOG_LEVEL_SILENT', 0))
