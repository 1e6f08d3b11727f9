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
What a `video_device` names: the synthetic camera, a V4L2 camera, or a video file.

`classify()` is the one place that reads a `video_device` string; opening a camera and
`--list-formats` both start from its answer. A by-id or by-path link is followed at each call,
so a camera plugged in elsewhere is found again at the next reopen.
"""

from dataclasses import dataclass
import os
import stat

from py_vision.capture.source import SourceError
from py_vision.capture.synthetic_device import is_synthetic_spec

__all__ = ['CAMERA', 'classify', 'FILE', 'SYNTHETIC', 'Target']

SYNTHETIC, CAMERA, FILE = 'synthetic', 'camera', 'file'


@dataclass(frozen=True)
class Target:
    """What a video_device string names: its kind and the path (the link followed now)."""

    kind: str          # SYNTHETIC, CAMERA or FILE
    path: str          # the device node or file; the synthetic spec itself
    device: str        # the video_device string, as the user gave it


def _index_node(video_device: str):
    """Return /dev/video<N> when video_device is a camera index (ASCII digits), else None."""
    index = video_device.strip()
    return '/dev/video%d' % int(index) if index.isascii() and index.isdigit() else None


def classify(video_device) -> Target:
    """
    Return what `video_device` names; SourceError (one line naming it) when it is nothing.

    - ``synthetic`` or ``synthetic?key=value&...``: the synthetic camera;
    - an integer (``0``): the V4L2 camera /dev/video<N>;
    - a character device (``/dev/video0``, ``/dev/v4l/by-id/...``): that V4L2 camera;
    - a regular file: a video file.
    """
    device = str(video_device)
    if is_synthetic_spec(device):
        return Target(SYNTHETIC, device, device)
    node = _index_node(device)
    if node is not None:
        if not os.path.exists(node):
            raise SourceError('cannot open video_device "%s": no camera %s (%s does not '
                              'exist)' % (device, device.strip(), node))
        return Target(CAMERA, node, device)
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
        return Target(CAMERA, path, device)
    if stat.S_ISREG(mode):
        return Target(FILE, path, device)
    if stat.S_ISDIR(mode):
        raise SourceError('cannot open video_device "%s": is a directory' % device)
    raise SourceError('cannot open video_device "%s": neither a video device nor a regular file'
                      % device)
