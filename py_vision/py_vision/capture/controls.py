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
The control table: one device control described once, and the names users give it.

A `ControlInfo` is what a device says about one of its controls (VIDIOC_QUERY_EXT_CTRL and
VIDIOC_QUERYMENU on a V4L2 camera, the model's table on the synthetic one): its V4L2 id, its
parameter name (the V4L2 name as v4l2_camera writes it: lower case, other characters `_`),
type, range, step, default, menu entries, flags and current value. `USB_CAM_ALIASES` maps
usb_cam's eleven parameter names onto V4L2 ids; everything else (descriptors, refusals, the
values the aliases take) is derived from the device's own ControlInfo.
"""

from dataclasses import dataclass, replace
import re
from typing import Dict, Optional, Tuple

__all__ = ['Alias', 'BOOL', 'CID', 'ControlInfo', 'INT', 'MENU', 'OWNED_BY', 'param_name',
           'USB_CAM_ALIASES']

INT, BOOL, MENU = 'integer', 'boolean', 'menu'


class CID:
    """The V4L2 control ids py_vision names (include/uapi/linux/v4l2-controls.h)."""

    USER = 0x00980900
    CAMERA = 0x009A0900
    BRIGHTNESS = USER + 0
    CONTRAST = USER + 1
    SATURATION = USER + 2
    HUE = USER + 3
    AUTO_WHITE_BALANCE = USER + 12
    GAIN = USER + 19
    POWER_LINE_FREQUENCY = USER + 24
    WHITE_BALANCE_TEMPERATURE = USER + 26
    SHARPNESS = USER + 27
    BACKLIGHT_COMPENSATION = USER + 28
    EXPOSURE_AUTO = CAMERA + 1
    EXPOSURE_ABSOLUTE = CAMERA + 2
    EXPOSURE_AUTO_PRIORITY = CAMERA + 3
    FOCUS_ABSOLUTE = CAMERA + 10
    FOCUS_AUTO = CAMERA + 12
    ZOOM_ABSOLUTE = CAMERA + 13


# V4L2's auto exposure menu: 0 auto, 1 manual, 2 shutter priority, 3 aperture priority
# (what UVC cameras call automatic).
EXPOSURE_MANUAL, EXPOSURE_APERTURE_PRIORITY, EXPOSURE_AUTO = 1, 3, 0
EXPOSURE_SHUTTER_PRIORITY = 2

# Controls an automatic mode owns: control -> (its owner, the owner's values that free it).
# A device marks such a control inactive; these say why, and set the owner first.
OWNED_BY = {
    CID.WHITE_BALANCE_TEMPERATURE: (CID.AUTO_WHITE_BALANCE, (0,)),
    CID.EXPOSURE_ABSOLUTE: (CID.EXPOSURE_AUTO, (EXPOSURE_MANUAL, EXPOSURE_SHUTTER_PRIORITY)),
    CID.FOCUS_ABSOLUTE: (CID.FOCUS_AUTO, (0,)),
}


def param_name(v4l2_name: str) -> str:
    """Return a V4L2 control name as a parameter name: 'Exposure Time, Absolute' -> ..."""
    return re.sub(r'[^a-z0-9]+', '_', v4l2_name.lower()).strip('_')


@dataclass(frozen=True)
class ControlInfo:
    """
    One control of one device, as the device reports it.

    `kind` is INT, BOOL or MENU; `menu` lists (value, label) for a menu control. `read_only`
    controls can never be set; `inactive` ones cannot be set now (another control, usually an
    automatic mode, owns them: `inactive_reason` says which when the source knows).
    """

    cid: int
    label: str                      # the device's own name, 'White Balance Temperature'
    kind: str
    minimum: int
    maximum: int
    step: int = 1
    default: int = 0
    value: Optional[int] = None
    menu: Tuple[Tuple[int, str], ...] = ()
    read_only: bool = False
    inactive: bool = False
    inactive_reason: str = ''

    @property
    def name(self) -> str:
        """Return the parameter name, as v4l2_camera derives it from the V4L2 name."""
        return param_name(self.label)

    def with_value(self, value: Optional[int], inactive: Optional[bool] = None,
                   inactive_reason: Optional[str] = None) -> 'ControlInfo':
        """Return a copy with the device's current value (and activity)."""
        return replace(self, value=value,
                       inactive=self.inactive if inactive is None else inactive,
                       inactive_reason=(self.inactive_reason if inactive_reason is None
                                        else inactive_reason))

    def refusal(self, value: int) -> Optional[str]:
        """Return why value cannot be set now, in words, or None when it can."""
        if self.read_only:
            return '%s is read-only on this camera' % self.name
        if self.inactive:
            return '%s is inactive%s' % (
                self.name, (' while ' + self.inactive_reason) if self.inactive_reason
                else ' (an automatic mode controls it)')
        if self.kind == MENU:
            if value not in dict(self.menu):
                return '%s: %s is not one of its menu entries (%s)' % (
                    self.name, value, self.menu_text())
            return None
        if not self.minimum <= value <= self.maximum:
            return "%s: %s is out of the camera's range %d..%d" % (
                self.name, value, self.minimum, self.maximum)
        if self.step > 1 and (value - self.minimum) % self.step:
            return '%s: %s is not on its step of %d from %d' % (
                self.name, value, self.step, self.minimum)
        return None

    def menu_text(self) -> str:
        """Return the menu entries as 'VALUE=Label; VALUE=Label'."""
        return '; '.join('%d=%s' % entry for entry in self.menu)

    def summary(self) -> str:
        """Return the control in one line, for --list-formats and the logs."""
        if self.kind == MENU:
            what = 'menu %s' % self.menu_text()
        elif self.kind == BOOL:
            what = 'bool'
        else:
            what = 'int %d..%d' % (self.minimum, self.maximum)
            if self.step != 1:
                what += ' step %d' % self.step
        flags = ''.join((', read-only' if self.read_only else '',
                         ', inactive' if self.inactive else ''))
        return '%s (0x%08x): %s, default %d, value %s%s' % (
            self.name, self.cid, what, self.default,
            '?' if self.value is None else self.value, flags)


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
