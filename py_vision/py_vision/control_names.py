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
The names users give a camera's controls and pixel formats: v4l2_camera's, and usb_cam's.

The camera layer knows controls by V4L2 id and pixel formats by FourCC only; this module names
them, and is the one place usb_cam's names are written. `param_name` is v4l2_camera's name for
a control (the V4L2 name in lower case, other characters `_`). `USB_CAM_ALIASES` maps usb_cam's
eleven parameter names onto V4L2 ids, with its three switches as booleans. `ControlNames` is
one camera's controls by name: each control's own name and each usb_cam name whose control the
camera has, and a user's values by name turned into device values by id.
`USB_CAM_PIXEL_FORMATS` maps usb_cam's pixel format names onto the FourCCs that mean the same
(`pixel_format_fourcc`).
"""

from dataclasses import dataclass
import re
from typing import Any, Collection, Dict, Mapping, Optional, Sequence, Tuple

from py_vision.capture.controls import (
    CID, ControlInfo, EXPOSURE_APERTURE_PRIORITY, EXPOSURE_AUTO, EXPOSURE_MANUAL, MENU, Refusal)

__all__ = ['Alias', 'ControlNames', 'param_name', 'pixel_format_fourcc', 'Target',
           'USB_CAM_ALIASES', 'USB_CAM_PIXEL_FORMATS']


def param_name(label: str) -> str:
    """Return a V4L2 control name as a parameter name: 'Exposure Time, Absolute' -> ..."""
    return re.sub(r'[^a-z0-9]+', '_', label.lower()).strip('_')


@dataclass(frozen=True)
class Alias:
    """One of usb_cam's control names, and how its values map onto a V4L2 control."""

    name: str
    cid: int
    switch: Optional[Tuple[int, ...]] = None   # a boolean to users: device values (off, on...)
    description: str = ''

    def to_device(self, value, control: ControlInfo) -> int:
        """Return the device value for a user's value of this alias."""
        if self.switch is None:
            return int(value)
        if not value:
            return self.switch[0]
        offered = dict(control.menu) if control.kind == MENU else None
        for candidate in self.switch[1:]:
            if offered is None or candidate in offered:
                return candidate
        return self.switch[1]

    def from_device(self, raw: int):
        """Return the alias's value for a device value."""
        if self.switch is None:
            return raw
        return raw != self.switch[0]


# usb_cam's names; the switches are booleans to its users.
USB_CAM_ALIASES: Dict[str, Alias] = {alias.name: alias for alias in (
    Alias('brightness', CID.BRIGHTNESS, description='camera brightness'),
    Alias('contrast', CID.CONTRAST, description='camera contrast'),
    Alias('saturation', CID.SATURATION, description='camera colour saturation'),
    Alias('sharpness', CID.SHARPNESS, description='camera sharpness'),
    Alias('gain', CID.GAIN, description='camera gain'),
    Alias('auto_white_balance', CID.AUTO_WHITE_BALANCE, (0, 1),
          'automatic white balance'),
    Alias('white_balance', CID.WHITE_BALANCE_TEMPERATURE,
          description='white balance temperature in kelvin, with auto_white_balance off'),
    Alias('autoexposure', CID.EXPOSURE_AUTO,
          (EXPOSURE_MANUAL, EXPOSURE_APERTURE_PRIORITY, EXPOSURE_AUTO), 'automatic exposure'),
    Alias('exposure', CID.EXPOSURE_ABSOLUTE,
          description='exposure time in 100 us units, with autoexposure off'),
    Alias('autofocus', CID.FOCUS_AUTO, (0, 1), 'automatic focus'),
    Alias('focus', CID.FOCUS_ABSOLUTE, description='focus position, with autofocus off'),
)}


@dataclass(frozen=True)
class Target:
    """What a name stands for: a control (by V4L2 id), through one of usb_cam's names or not."""

    name: str
    cid: int
    alias: Optional[Alias] = None

    def to_device(self, value: Any, control: ControlInfo) -> int:
        """Return the device value for a user's value of this name."""
        return self.alias.to_device(value, control) if self.alias else int(value)

    def from_device(self, raw: int) -> Any:
        """Return this name's value for a device value."""
        return self.alias.from_device(raw) if self.alias else raw


class ControlNames:
    """
    One camera's controls by name: each control's own name, and usb_cam's where it has them.

    `reserved` are names taken already (the node's own parameters): a control named like one
    of them has no name here. A usb_cam name that is also a control's own (`brightness`) is
    that control's name.
    """

    def __init__(self, controls: Sequence[ControlInfo], reserved: Collection[str] = ()):
        self.targets: Dict[str, Target] = {}
        self._own: Dict[int, str] = {}
        for control in controls:
            name = param_name(control.label)
            if name in reserved or name in self.targets:
                continue
            self.targets[name] = Target(name, control.cid)
            self._own[control.cid] = name
        for alias in USB_CAM_ALIASES.values():
            if alias.cid in self._own and alias.name not in self.targets and (
                    alias.name not in reserved):
                self.targets[alias.name] = Target(alias.name, alias.cid, alias)

    def name_of(self, cid: int) -> str:
        """Return a control's own name (its V4L2 id in hex when it has none)."""
        return self._own.get(cid, 'control 0x%08x' % cid)

    def to_device(self, values: Mapping[str, Any], controls: Mapping[int, ControlInfo]
                  ) -> Dict[int, Tuple[str, int]]:
        """Return values by name as device values by id, with the name each came by."""
        found = {}
        for name, value in values.items():
            target = self.targets[name]
            if target.cid in controls:
                found[target.cid] = (name, target.to_device(value, controls[target.cid]))
        return found

    def words(self, refusal: Refusal, used: Optional[Mapping[int, str]] = None) -> str:
        """
        Return a refusal in words: the control by the name used for it (used: id -> name).

        The control holding it is named by its own name, as its value is the device's.
        """
        name = (used or {}).get(refusal.cid) or self.name_of(refusal.cid)
        return refusal.words(lambda cid: name if cid == refusal.cid else self.name_of(cid))


# usb_cam's pixel_format names where they mean what a V4L2 FourCC means (its yuyv and uyvy are
# the FourCCs themselves).
USB_CAM_PIXEL_FORMATS: Dict[str, str] = {
    'mjpeg': 'MJPG', 'mono8': 'GREY', 'mono16': 'Y16', 'rgb24': 'RGB3', 'bgr24': 'BGR3'}


def pixel_format_fourcc(value: str) -> str:
    """Return the FourCC (or auto) a pixel_format value means: usb_cam's names turned into it."""
    return USB_CAM_PIXEL_FORMATS.get(str(value).strip().lower(), str(value).strip())
