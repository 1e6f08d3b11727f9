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
OpenCV's own log lines, kept off the console for the life of the process.

OpenCV's V4L2 backend prints warnings of its own (``[ WARN:0@7.4] global cap_v4l.cpp:804
requestBuffers ... errno=19`` at an unplug) on stderr. py_vision says what happened in its own
words instead, so the camera layer silences OpenCV once, before its first capture opens.
"""

import os

import cv2

__all__ = ['silence_opencv']


def silence_opencv() -> None:
    """Set OpenCV's log level to silent for this process (idempotent)."""
    # Child processes and OpenCV code that reads the environment late see it too.
    os.environ.setdefault('OPENCV_LOG_LEVEL', 'SILENT')
    os.environ.setdefault('OPENCV_VIDEOIO_DEBUG', '0')
    # OpenCV 4.5+ and 5.x: cv2.utils.logging; some 4.x builds only have cv2.setLogLevel.
    logging = getattr(getattr(cv2, 'utils', None), 'logging', None)
    set_level = getattr(logging, 'setLogLevel', None) or getattr(cv2, 'setLogLevel', None)
    if set_level is not None:
        set_level(getattr(logging, 'LOG_LEVEL_SILENT', 0))
