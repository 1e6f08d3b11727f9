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
A device's controls by V4L2 id: what the device says about each, and what a change can do.

A `ControlInfo` is what a device says about one of its controls (VIDIOC_QUERY_EXT_CTRL and
VIDIOC_QUERYMENU on a V4L2 camera, the model's table on the synthetic one): its V4L2 id, the
device's own label, its type, range, step, default, menu, flags and current value. Every
control type V4L2 defines has a kind here; `SETTABLE` are those a single number sets.

`GOVERNORS` is the V4L2 specification's automatic modes: the controls an automatic mode holds
while it is on (auto gain holds the gain, auto exposure the exposure time and the iris, auto
white balance the temperature and the red and blue balance, ...). A device flags a held control
inactive; `holder` says which control holds it. `check` takes a batch of changes and returns
the order to make them in (automatic modes first) and why the device cannot take the others.
Names are not known here: a `Refusal` is put in words with the names its reader uses
(control_names).
"""

from dataclasses import dataclass, replace
from typing import Callable, Dict, List, Mapping, Optional, Sequence, Tuple

__all__ = ['ARRAY', 'BITMASK', 'BOOL', 'BUTTON', 'check', 'CID', 'COMPOUND', 'ControlInfo',
           'governed', 'GOVERNORS', 'holder', 'INT', 'INT64', 'INT_MENU', 'MENU', 'Refusal',
           'SETTABLE', 'STRING']

# The kinds of control (enum v4l2_ctrl_type; an array is any type with dimensions).
INT, BOOL, MENU, BUTTON, INT64 = 'integer', 'boolean', 'menu', 'button', 'integer64'
STRING, BITMASK, INT_MENU, ARRAY, COMPOUND = (
    'string', 'bitmask', 'integer menu', 'array', 'compound')
# Set by one number (a button by any: it is pressed); the rest carry a payload.
SETTABLE = (INT, BOOL, MENU, BUTTON, INT64, BITMASK, INT_MENU)


class CID:
    """The V4L2 control ids py_vision knows (include/uapi/linux/v4l2-controls.h)."""

    USER = 0x00980900
    CAMERA = 0x009A0900
    BRIGHTNESS = USER + 0
    CONTRAST = USER + 1
    SATURATION = USER + 2
    HUE = USER + 3
    AUTO_WHITE_BALANCE = USER + 12
    DO_WHITE_BALANCE = USER + 13
    RED_BALANCE = USER + 14
    BLUE_BALANCE = USER + 15
    EXPOSURE = USER + 17
    AUTOGAIN = USER + 18
    GAIN = USER + 19
    POWER_LINE_FREQUENCY = USER + 24
    HUE_AUTO = USER + 25
    WHITE_BALANCE_TEMPERATURE = USER + 26
    SHARPNESS = USER + 27
    BACKLIGHT_COMPENSATION = USER + 28
    CHROMA_AGC = USER + 29
    AUTOBRIGHTNESS = USER + 32
    CHROMA_GAIN = USER + 36
    EXPOSURE_AUTO = CAMERA + 1
    EXPOSURE_ABSOLUTE = CAMERA + 2
    EXPOSURE_AUTO_PRIORITY = CAMERA + 3
    FOCUS_ABSOLUTE = CAMERA + 10
    FOCUS_RELATIVE = CAMERA + 11
    FOCUS_AUTO = CAMERA + 12
    ZOOM_ABSOLUTE = CAMERA + 13
    IRIS_ABSOLUTE = CAMERA + 17
    IRIS_RELATIVE = CAMERA + 18
    ISO_SENSITIVITY = CAMERA + 23
    ISO_SENSITIVITY_AUTO = CAMERA + 24


# V4L2's auto exposure menu: 0 auto, 1 manual, 2 shutter priority, 3 aperture priority
# (what UVC cameras call automatic).
EXPOSURE_AUTO, EXPOSURE_MANUAL = 0, 1
EXPOSURE_SHUTTER_PRIORITY, EXPOSURE_APERTURE_PRIORITY = 2, 3
_OFF = (0,)   # a boolean automatic mode, or the manual entry of an auto/manual menu
_TIME_FREE = (EXPOSURE_MANUAL, EXPOSURE_SHUTTER_PRIORITY)
_IRIS_FREE = (EXPOSURE_MANUAL, EXPOSURE_APERTURE_PRIORITY)

# The automatic modes of the V4L2 specification ("User Controls", "Camera Control Reference"):
# control -> ((the control whose automatic mode may hold it, its values that free it), ...).
GOVERNORS: Dict[int, Tuple[Tuple[int, Tuple[int, ...]], ...]] = {
    CID.GAIN: ((CID.AUTOGAIN, _OFF),),
    CID.EXPOSURE: ((CID.EXPOSURE_AUTO, _TIME_FREE), (CID.AUTOGAIN, _OFF)),
    CID.EXPOSURE_ABSOLUTE: ((CID.EXPOSURE_AUTO, _TIME_FREE),),
    CID.IRIS_ABSOLUTE: ((CID.EXPOSURE_AUTO, _IRIS_FREE),),
    CID.IRIS_RELATIVE: ((CID.EXPOSURE_AUTO, _IRIS_FREE),),
    CID.WHITE_BALANCE_TEMPERATURE: ((CID.AUTO_WHITE_BALANCE, _OFF),),
    CID.RED_BALANCE: ((CID.AUTO_WHITE_BALANCE, _OFF),),
    CID.BLUE_BALANCE: ((CID.AUTO_WHITE_BALANCE, _OFF),),
    CID.DO_WHITE_BALANCE: ((CID.AUTO_WHITE_BALANCE, _OFF),),
    CID.FOCUS_ABSOLUTE: ((CID.FOCUS_AUTO, _OFF),),
    CID.FOCUS_RELATIVE: ((CID.FOCUS_AUTO, _OFF),),
    CID.HUE: ((CID.HUE_AUTO, _OFF),),
    CID.BRIGHTNESS: ((CID.AUTOBRIGHTNESS, _OFF),),
    CID.ISO_SENSITIVITY: ((CID.ISO_SENSITIVITY_AUTO, _OFF),),
    CID.CHROMA_GAIN: ((CID.CHROMA_AGC, _OFF),),
}
_AUTOMATIC_MODES = frozenset(governor for entries in GOVERNORS.values()
                             for governor, _ in entries)


def holder(cid: int, values: Mapping[int, Optional[int]]) -> Optional[int]:
    """Return the control whose automatic mode holds cid at these values (by id), or None."""
    for governor, frees in GOVERNORS.get(cid, ()):
        if values.get(governor) is not None and values[governor] not in frees:
            return governor
    return None


@dataclass(frozen=True)
class ControlInfo:
    """
    One control of one device, as the device reports it.

    `kind` is one of INT, BOOL, MENU, BUTTON, INT64, STRING, BITMASK, INT_MENU, ARRAY or
    COMPOUND. `menu` lists (index, label) for a menu, (index, its value as text) for an integer
    menu; a bitmask's `maximum` is its mask; a string's range is its length. `value` is None
    where the device does not say (a button, a payload). `read_only` controls can never be set;
    `inactive` ones cannot be set now, and `governor` is the control holding them, when known.
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
    governor: Optional[int] = None

    def with_value(self, value: Optional[int], inactive: Optional[bool] = None) -> 'ControlInfo':
        """Return a copy with the device's current value (and activity)."""
        return replace(self, value=value,
                       inactive=self.inactive if inactive is None else inactive)

    def value_problem(self, value: int) -> Optional[str]:
        """Return what is wrong with value for this control, as words after its name, or None."""
        kind = self.kind
        if kind not in SETTABLE:
            return ' is a %s control: it has no value to set here' % kind
        if kind == BUTTON:
            return None
        if kind in (MENU, INT_MENU):
            if value not in dict(self.menu):
                return ': %s is not one of its menu entries (%s)' % (value, self.menu_text())
            return None
        if kind == BITMASK:
            if value < 0 or value & ~self.maximum:
                return ': 0x%x has bits outside its mask 0x%x' % (value, self.maximum)
            return None
        if not self.minimum <= value <= self.maximum:
            return ": %s is out of the camera's range %d..%d" % (
                value, self.minimum, self.maximum)
        if self.step > 1 and (value - self.minimum) % self.step:
            return ': %s is not on its step of %d from %d' % (value, self.step, self.minimum)
        return None

    def menu_text(self) -> str:
        """Return the menu entries as 'VALUE=Label; VALUE=Label'."""
        return '; '.join('%d=%s' % entry for entry in self.menu)

    def summary(self) -> str:
        """Return what the control is, for --list-formats (after its name)."""
        kind = self.kind
        if kind in (MENU, INT_MENU):
            what = '%s %s' % (kind, self.menu_text())
        elif kind == BOOL:
            what = 'bool'
        elif kind == BITMASK:
            what = 'bitmask 0x%x' % self.maximum
        elif kind in (INT, INT64):
            what = '%s %d..%d' % ('int' if kind == INT else 'int64', self.minimum, self.maximum)
            if self.step != 1:
                what += ' step %d' % self.step
        elif kind == BUTTON:
            what = 'button'
        else:
            what = '%s, not a parameter' % kind
        if kind in SETTABLE and kind != BUTTON:
            number = '0x%x' if kind == BITMASK else '%d'
            what += (', default ' + number + ', value %s') % (
                self.default, '?' if self.value is None else number % self.value)
        flags = ''.join((', read-only' if self.read_only else '',
                         ', inactive' if self.inactive else ''))
        return '(0x%08x): %s%s' % (self.cid, what, flags)


@dataclass(frozen=True)
class Refusal:
    """Why a device control does not take a value; `words` says it with the reader's names."""

    cid: int
    why: str                              # after the control's name: ' is read-only ...'
    governor: Optional[ControlInfo] = None  # the control holding it, with its value

    def words(self, name_of: Callable[[int], str]) -> str:
        """Return the refusal in words, controls named by name_of(V4L2 id)."""
        text = name_of(self.cid) + self.why
        if self.governor is not None:
            text += ' while %s is %s' % (name_of(self.governor.cid), self.governor.value)
        return text


def governed(controls: Sequence[ControlInfo]) -> List[ControlInfo]:
    """Return the controls with `governor` set on each inactive one an automatic mode holds."""
    values = {control.cid: control.value for control in controls}
    found = []
    for control in controls:
        if control.inactive and control.governor is None:
            control = replace(control, governor=holder(control.cid, values))
        found.append(control)
    return found


def check(controls: Sequence[ControlInfo], values: Mapping[int, int]
          ) -> Tuple[List[Tuple[int, int]], Dict[int, Refusal]]:
    """
    Return the changes (V4L2 id -> value) in the order to make them, and why the others fail.

    Automatic modes go first, so that the controls they free can be set after them. Where the
    changes set an automatic mode, whether it holds its controls is the V4L2 specification's
    (GOVERNORS): a control inactive now counts as active when the same changes switch the mode
    holding it off, and as inactive when they switch one on; elsewhere the device's inactive
    flag decides. A control the device does not have is refused.
    """
    by_id = {control.cid: control for control in governed(controls)}
    ordered, refused = [], {}
    for cid in sorted(values, key=lambda cid: cid not in _AUTOMATIC_MODES):
        found = _refusal(by_id.get(cid), cid, values, by_id)
        if found is None:
            ordered.append((cid, values[cid]))
        else:
            refused[cid] = found
    return ordered, refused


def _refusal(control, cid, values, by_id) -> Optional[Refusal]:
    if control is None:
        return Refusal(cid, ': the camera has no such control')
    if control.read_only:
        return Refusal(cid, ' is read-only on this camera')
    held, governor = _held(control, values, by_id)
    if held:
        if governor is not None:
            return Refusal(cid, ' is inactive', governor)
        return Refusal(cid, " is inactive while the camera's current mode holds it")
    problem = control.value_problem(values[cid])
    return Refusal(cid, problem) if problem else None


def _held(control, values, by_id) -> Tuple[bool, Optional[ControlInfo]]:
    """Return whether control is held once values are set, and what holds it (when known)."""
    entries = GOVERNORS.get(control.cid, ())
    if not any(governor in values for governor, _ in entries):
        return control.inactive, by_id.get(control.governor)
    after = {cid: known.value for cid, known in by_id.items()}
    after.update(values)
    governor = holder(control.cid, after)
    if governor not in by_id:
        return False, None
    return True, replace(by_id[governor], value=after[governor])
