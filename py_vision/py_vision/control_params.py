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
A camera's controls as ROS parameters: every control the device reports, and usb_cam's names.

Each control the camera reports (`ControlInfo`) that one number sets becomes a parameter, named
as v4l2_camera names them (control_names: `white_balance_temperature`, `auto_exposure`),
declared once the camera is open with the value read from the device and a descriptor derived
from the control (control_descriptor):

- integer, 64-bit integer, menu, integer menu and bitmask controls are integers with the
  device's range and step in `integer_range`; a menu's entries (an integer menu's values) and a
  bitmask's mask are in the description (``Auto Exposure; menu: 1=Manual Mode; 3=Aperture
  Priority Mode``);
- a boolean is a boolean; a button is a boolean that presses it when set true and reads back
  false (a press is not repeated after a reconnect);
- `additional_constraints` begins with ``camera control``: the V4L2 id, type, step and default,
  and, while the control is inactive, the control holding it (``inactive while gain_automatic
  is 1``); `read_only` for a control the device will not let anyone set.

String, array and compound controls are not parameters: they are named once in the log.
usb_cam's names are parameters too wherever the camera has the control they stand for, with the
same range. Changes made together are checked whole against the device (read-only, inactive
unless the same changes switch its automatic mode off, range, step, menu, mask): any refusal
refuses them all, with the reason; else they go to the camera as one batch (`set_controls`:
automatic modes first), which the capture loop applies again after a reconnect. The parameters
follow the device's values (an automatic mode switched off, a reconnect, a volatile control).
"""

from dataclasses import replace
from typing import Any, Dict, List, Mapping, Optional, Protocol, Tuple

from py_vision.capture.controls import (
    BITMASK, BOOL, BUTTON, check, ControlInfo, INT_MENU, MENU, Refusal, SETTABLE)
from py_vision.control_descriptor import alias_constraints, control_constraints, describe
from py_vision.control_names import Alias, ControlNames, USB_CAM_ALIASES
from py_vision.params import Parameters, Spec

__all__ = ['ALIAS_HELP', 'CameraControls', 'ControlParameters', 'alias_spec', 'control_spec']

_PRESS = 'a button: set it true to press it (it reads back false)'


class CameraControls(Protocol):
    """The camera's controls as ControlParameters uses them (the capture loop has them)."""

    def controls(self) -> List[ControlInfo]: ...  # noqa: D102 (empty while the camera is lost)

    def set_controls(self, values: Mapping[int, int],  # noqa: D102
                     keep: bool = True) -> Dict[int, Refusal]: ...


def _kind(control: ControlInfo) -> type:
    return bool if control.kind in (BOOL, BUTTON) else int


def _value(control: ControlInfo, alias: Optional[Alias] = None) -> Any:
    if control.kind == BUTTON:
        return False
    raw = control.value if control.value is not None else control.default
    if alias is not None:
        return alias.from_device(raw)
    return bool(raw) if control.kind == BOOL else int(raw)


def control_spec(control: ControlInfo, name: str, held_by: Optional[str] = None) -> Spec:
    """
    Return the parameter of one device control, described by the device.

    held_by: while the control is inactive, what holds it ('gain_automatic is 1'; '' when not
    known); None while it is active.
    """
    constraints = control_constraints(control.cid, control.kind, control.step, control.default,
                                      held_by if control.inactive else None, control.read_only)
    value_range = None if _kind(control) is bool else (control.minimum, control.maximum)
    description = describe(control.label,
                           control.menu if control.kind in (MENU, INT_MENU) else ())
    if control.kind == BITMASK:
        description += '; bitmask 0x%x' % control.maximum
    elif control.kind == BUTTON:
        description += '; ' + _PRESS
    return Spec(name, _value(control), description, value_range,
                live=not control.read_only, step=control.step, constraints=constraints)


def alias_spec(alias: Alias, control: ControlInfo, control_name: str) -> Spec:
    """Return the parameter of one of usb_cam's names, with the device's range."""
    value_range = None
    if alias.switch is None and control.kind != BOOL:
        value_range = (control.minimum, control.maximum)
    return Spec(alias.name, _value(control, alias),
                "%s (usb_cam's name for %s)" % (alias.description, control_name), value_range,
                live=not control.read_only, step=control.step if value_range else 1,
                constraints=alias_constraints(control_name))


# For --help, before any camera is open: usb_cam's names, not set unless given.
ALIAS_HELP: Tuple[Spec, ...] = tuple(
    Spec(alias.name, bool if alias.switch else int, "%s (usb_cam's name)" % alias.description,
         accepted='true or false' if alias.switch else "the camera's own range", live=True)
    for alias in USB_CAM_ALIASES.values())


class ControlParameters:
    """
    The parameters of one camera's controls.

    `camera` reads and sets the controls (the capture loop); `log` has info and warning;
    `device` names the camera in them.
    """

    def __init__(self, parameters: Parameters, camera: CameraControls, log,
                 device: str = 'the camera'):
        self._parameters = parameters
        self._camera = camera
        self._log = log
        self._device = device
        self._names = ControlNames(())
        self._by_id: Dict[int, ControlInfo] = {}   # the controls as last read
        self._specs: Dict[str, Spec] = {}
        # What the device said at the last sync that the parameters show (None: not yet).
        self._shown: Optional[List[ControlInfo]] = None

    @property
    def names(self) -> List[str]:
        """Return the names of the control parameters declared."""
        return list(self._specs)

    def declare(self, static_names) -> None:
        """
        Declare a parameter for each control of the open camera and each usb_cam name it has.

        What the user gave (command line, params file, launch) is applied to the device first,
        as one batch; a value the device refuses is one warning and the device's own value is
        kept. static_names: the node's other parameters. Raises ConfigError for a value of the
        wrong type (nothing is declared then).
        """
        controls = self._camera.controls()
        names = self._names = ControlNames(controls, static_names)
        by_id = {control.cid: control for control in controls}
        wanted = [name for name, target in names.targets.items()
                  if by_id[target.cid].kind in SETTABLE]
        others = ['%s (%s)' % (name, by_id[target.cid].kind)
                  for name, target in names.targets.items() if name not in wanted]
        if others:
            self._log.info('%s: not parameters (no single value to set): %s'
                           % (self._device, ', '.join(others)))
        for alias in USB_CAM_ALIASES.values():
            if alias.name not in names.targets and alias.name not in static_names and (
                    self._parameters.given(alias.name) is not None):
                self._log.warning('%s: %s has no such control; the value is not used' % (
                    alias.name, self._device))
        given = {}
        for name in wanted:
            value = self._parameters.given(name)
            if value is None:
                continue
            spec = self._spec(name, by_id)
            # A value of the wrong type is an error; one the device refuses, a warning.
            value = replace(spec, value_range=None, step=1).coerce(value)
            if value != spec.default:
                given[name] = value
        values = names.to_device(given, by_id)
        self.warn(self._set(values, by_id), {cid: name for cid, (name, _) in values.items()})
        # The values now; a control the device no longer answers for (it was unplugged
        # meanwhile) keeps what the first read said, and sync() catches up once it is back.
        by_id.update((control.cid, control) for control in self._camera.controls())
        self._by_id = by_id
        for name in wanted:
            spec = self._specs[name] = self._spec(name, by_id)
            self._parameters.declare_shown(spec, self._apply if spec.live else None)

    def warn(self, refusals: Mapping[int, Refusal], used: Optional[Mapping[int, str]] = None
             ) -> None:
        """Log each refusal of the camera: its value was not set (used: id -> name given)."""
        for refusal in refusals.values():
            self._log.warning("%s; left at the camera's own value"
                              % self._names.words(refusal, used))

    def _set(self, values: Mapping[int, Tuple[str, int]], by_id) -> Dict[int, Refusal]:
        """Set values (id -> (name, device value)) as one batch, then press the buttons."""
        buttons = {cid for cid in values if by_id[cid].kind == BUTTON}
        settings = {cid: value for cid, (_, value) in values.items() if cid not in buttons}
        refused = self._camera.set_controls(settings) if settings else {}
        pressed = {cid: 1 for cid in buttons if values[cid][1]}
        if pressed:
            refused.update(self._camera.set_controls(pressed, keep=False))
        return refused

    def _apply(self, changes: Dict[str, Any]) -> Optional[str]:
        """
        Apply parameter changes made together (name -> value); None, or why none was applied.

        A camera that is lost answers nothing here: the capture loop keeps the values and
        applies them when it is back (a button's press it refuses: it cannot wait).
        """
        # The parameters may now say what the device does not (a button reads back false):
        # the next sync shows the device's values again, changed or not.
        self._shown = None
        controls = self._camera.controls()
        by_id = {control.cid: control for control in controls} or self._by_id
        values = self._names.to_device(changes, by_id)
        used = {cid: name for cid, (name, _) in values.items()}
        if controls:
            _, refused = check(controls, {cid: value for cid, (_, value) in values.items()
                                          if by_id[cid].kind != BUTTON or value})
            if refused:
                return self._first(refused, values, used)
        refused = self._set(values, by_id)
        if refused:
            # The device refused what passed every check: put back what was applied.
            self._camera.set_controls({
                cid: by_id[cid].value for cid in values
                if cid not in refused and by_id[cid].kind != BUTTON and
                by_id[cid].value is not None})
            return self._first(refused, values, used)
        return None

    def _first(self, refused, values, used) -> str:
        cid = next(cid for cid in values if cid in refused)
        return self._names.words(refused[cid], used)

    def _spec(self, name, by_id) -> Spec:
        target = self._names.targets[name]
        control = by_id[target.cid]
        if target.alias is not None:
            return alias_spec(target.alias, control, self._names.name_of(control.cid))
        held_by = None
        if control.inactive:
            governor = by_id.get(control.governor)
            held_by = '' if governor is None else '%s is %s' % (
                self._names.name_of(governor.cid), governor.value)
        return control_spec(control, name, held_by)

    def sync(self) -> None:
        """Show the device's current values and activity in the parameters."""
        controls = self._camera.controls()
        if not controls:
            return  # the camera is lost: the parameters keep the last values
        if controls == self._shown:
            return  # nothing changed on the device: the parameters show it already
        by_id = self._by_id = {control.cid: control for control in controls}
        values, changed = {}, []
        for name, old in self._specs.items():
            if self._names.targets[name].cid not in by_id:
                continue
            spec = self._spec(name, by_id)
            values[name] = spec.default
            if replace(spec, default=old.default) != old:
                changed.append(spec)
                self._specs[name] = spec
        self._parameters.show(values, changed)
        self._shown = controls
