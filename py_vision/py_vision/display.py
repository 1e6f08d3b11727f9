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

"""Where the subscriber shows frames: an OpenCV window when this machine can open one."""

import os
import sys

import cv2

WINDOW_TITLE = 'Video Stream'


def window_unavailable_reason():
    """Return why no OpenCV window can be opened here, or None when one can."""
    if sys.platform.startswith('linux') and not (
            os.environ.get('DISPLAY') or os.environ.get('WAYLAND_DISPLAY')):
        return 'no DISPLAY is set (no screen, or ssh without X forwarding)'
    try:
        cv2.namedWindow(WINDOW_TITLE, cv2.WINDOW_AUTOSIZE)
    except cv2.error:
        return 'this OpenCV has no GUI support (opencv-python-headless)'
    return None


class WindowDisplay:
    """The tutorial's cv2.imshow window; call only after window_unavailable_reason() is None."""

    def __init__(self, title=WINDOW_TITLE):
        self.title = title
        cv2.namedWindow(title, cv2.WINDOW_AUTOSIZE)

    def show(self, image):
        cv2.imshow(self.title, image)
        cv2.waitKey(1)

    def close(self):
        try:
            cv2.destroyWindow(self.title)
        except cv2.error:
            pass
