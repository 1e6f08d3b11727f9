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
so a camera plugged in elsewhere is found again at the next reopen, and so is ``auto``: the
first USB camera (driver uvcvideo) of `video_devices()`, which lists every /dev/videoN with
what it is (`VideoDevice`: what `--list-devices` prints). A board's own capture pipelines
(MIPI, the video IP's DMA) register /dev/video nodes of other drivers, often before the USB
camera's: ``auto`` passes them by.
"""

from dataclasses import dataclass
import os
import re
import stat
from typing import List, Optional, Tuple

from py_vision.capture.source import SourceError
from py_vision.capture.synthetic_device import is_synthetic_spec
from py_vision.capture.v4l2 import V4L2Device, V4L2Error

__all__ = ['AUTO', 'CAMERA', 'classify', 'FILE', 'SYNTHETIC', 'Target', 'UVC_DRIVER',
           'VideoDevice', 'video_devices']

SYNTHETIC, CAMERA, FILE = 'synthetic', 'camera', 'file'
AUTO = 'auto'
UVC_DRIVER = 'uvcvideo'
_LINK_FOLDERS = ('/dev/v4l/by-id', '/dev/v4l/by-path')


@dataclass(frozen=True)
class VideoDevice:
    """One /dev/videoN: what its driver says it is, its udev links, the formats it offers."""

    path: str
    driver: str = ''
    card: str = ''
    bus: str = ''
    capture: bool = False         # a video capture node (a UVC camera's second node is not)
    links: Tuple[str, ...] = ()   # /dev/v4l/by-id/... and by-path/... names of it
    formats: Tuple[str, ...] = ()  # FourCCs, for a capture node
    problem: str = ''             # why it could not be asked (permission denied...)

    @property
    def usb_camera(self) -> bool:
        """Return True for a USB camera's capture node (what video_device:=auto opens)."""
        return self.capture and self.driver == UVC_DRIVER


def _node_number(name: str) -> Optional[int]:
    found = re.fullmatch(r'video(\d+)', name)
    return int(found.group(1)) if found else None


def _links() -> dict:
    """Return node path -> its by-id and by-path links."""
    found = {}
    for folder in _LINK_FOLDERS:
        try:
            names = sorted(os.listdir(folder))
        except OSError:
            continue
        for name in names:
            link = os.path.join(folder, name)
            found.setdefault(os.path.realpath(link), []).append(link)
    return found


def video_devices(formats: bool = True) -> List[VideoDevice]:
    """Return every /dev/videoN in number order, asked what it is (formats: and what it sends)."""
    try:
        names = os.listdir('/dev')
    except OSError:
        names = []
    numbers = sorted(n for n in map(_node_number, names) if n is not None)
    links = _links()
    found = []
    for number in numbers:
        path = '/dev/video%d' % number
        named = tuple(links.get(os.path.realpath(path), ()))
        try:
            with V4L2Device(path, capture_only=False) as device:
                offered = tuple(listed.fourcc for listed in device.formats()) \
                    if formats and device.capture else ()
                found.append(VideoDevice(path, device.driver, device.card, device.bus_info,
                                         device.capture, named, offered))
        except V4L2Error as error:
            found.append(VideoDevice(path, links=named, problem=error.reason))
    return found


def _first_usb_camera(device: str) -> str:
    """Return the node video_device:=auto opens; SourceError saying what there is if none."""
    found = video_devices(formats=False)
    for candidate in found:
        if candidate.usb_camera:
            return candidate.path
    others = ', '.join('%s (%s)' % (d.path, d.driver or d.problem) for d in found)
    raise SourceError('cannot open video_device "%s": no USB camera (driver %s) is plugged in%s'
                      % (device, UVC_DRIVER, '; the video devices here: ' + others if others
                         else ' (there is no /dev/video device at all)'))


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
    - ``auto``: the first USB camera (driver uvcvideo), whatever its number;
    - an integer (``0``): the V4L2 camera /dev/video<N>;
    - a character device (``/dev/video0``, ``/dev/v4l/by-id/...``): that V4L2 camera;
    - a regular file: a video file.
    """
    device = str(video_device)
    if is_synthetic_spec(device):
        return Target(SYNTHETIC, device, device)
    if device.strip().lower() == AUTO:
        return Target(CAMERA, _first_usb_camera(device), device)
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
