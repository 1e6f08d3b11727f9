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
OpenCV as the camera layer needs it: quiet.

OpenCV prints warnings of its own on stderr (a video file its reader trips over, libjpeg's
complaints about a corrupt JPEG being decoded): py_vision says what happened in its own words
instead, so OpenCV is silenced for the life of the process before the first source opens.
"""

import os

import cv2

__all__ = ['prepare_opencv']


def prepare_opencv() -> None:
    """Silence OpenCV's log (idempotent)."""
    os.environ.setdefault('OPENCV_LOG_LEVEL', 'SILENT')
    # FFmpeg's own messages (a stream it decodes ending mid-picture) too: AV_LOG_QUIET.
    os.environ.setdefault('OPENCV_FFMPEG_LOGLEVEL', '-8')
    # OpenCV 4.5+ and 5.x: cv2.utils.logging; some 4.x builds only have cv2.setLogLevel.
    logging = getattr(getattr(cv2, 'utils', None), 'logging', None)
    set_level = getattr(logging, 'setLogLevel', None) or getattr(cv2, 'setLogLevel', None)
    if set_level is not None:
        set_level(getattr(logging, 'LOG_LEVEL_SILENT', 0))
