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

Each control the camera reports (`ControlInfo`) becomes a parameter named as v4l2_camera names
them (`white_balance_temperature`, `exposure_time_absolute`, `auto_exposure`), declared once the
camera is open, with the value read from the device and a descriptor derived from the control:
`integer_range` with the device's range and step, the device's name and any menu entries in
the description (``Auto Exposure; menu: 1=Manual Mode; 3=Aperture Priority Mode``),
`additional_constraints` beginning with ``camera control`` (its V4L2 id, type, step and default,
and why it is inactive), `read_only` for a control the device will not let anyone set.
usb_cam's eleven names are parameters too wherever the camera has the control they stand for,
with the same range. A change is applied to the device at once and refused with the reason when
the device cannot take it (read-only, inactive, out of range, off its step, not in its menu);
the parameters follow the device's values (an automatic mode switched off, a reconnect).
"""

from dataclasses import replace
from typing import Any, Callable, Dict, List, Optional, Tuple

from py_vision.capture.controls import (
    Alias, BOOL, ControlInfo, MENU, OWNED_BY, USB_CAM_ALIASES)
from py_vision.control_descriptor import alias_constraints, control_constraints, describe
from py_vision.params import Parameters, Spec

__all__ = ['ALIAS_HELP', 'ControlParameters', 'alias_spec', 'control_spec']


def _kind(control: ControlInfo) -> type:
    return bool if control.kind == BOOL else int


def _value(control: ControlInfo, alias: Optional[Alias] = None) -> Any:
    raw = control.value if control.value is not None else control.default
    if alias is not None:
        return alias.from_device(raw)
    return bool(raw) if control.kind == BOOL else int(raw)


def control_spec(control: ControlInfo) -> Spec:
    """Return the parameter of one device control, described by the device."""
    inactive = None
    if control.inactive:
        inactive = control.inactive_reason
    constraints = control_constraints(control.cid, control.kind, control.step, control.default,
                                      inactive, control.read_only)
    value_range = None if control.kind == BOOL else (control.minimum, control.maximum)
    description = describe(control.label, control.menu if control.kind == MENU else ())
    return Spec(control.name, _value(control), description, value_range,
                live=not control.read_only, step=control.step, constraints=constraints)


def alias_spec(alias: Alias, control: ControlInfo) -> Spec:
    """Return the parameter of one of usb_cam's names, with the device's range."""
    value_range = None
    if alias.switch is None and control.kind != BOOL:
        value_range = (control.minimum, control.maximum)
    return Spec(alias.name, _value(control, alias),
                "%s (usb_cam's name for %s)" % (alias.description, control.name), value_range,
                live=not control.read_only, step=control.step if value_range else 1,
                constraints=alias_constraints(control.name))


# For --help, before any camera is open: usb_cam's names, not set unless given.
ALIAS_HELP: Tuple[Spec, ...] = tuple(
    Spec(alias.name, bool if alias.switch else int, "%s (usb_cam's name)" % alias.description,
         accepted='true or false' if alias.switch else "the camera's own range", live=True)
    for alias in USB_CAM_ALIASES.values())


class ControlParameters:
    """
    The parameters of one camera's controls.

    `set_control(name, value) -> reason or None` applies a change (the capture loop's);
    `read_controls()` returns the device's controls now (empty while it is lost). `log` has
    info and warning; `device` names the camera in them.
    """

    def __init__(self, parameters: Parameters, set_control: Callable[[str, Any], Optional[str]],
                 read_controls: Callable[[], List[ControlInfo]], log, device: str = 'the camera'):
        self._parameters = parameters
        self._device = device
        self._set_control = set_control
        self._read_controls = read_controls
        self._log = log
        self._specs: Dict[str, Spec] = {}
        self._targets: Dict[str, Tuple[int, Optional[Alias]]] = {}  # name -> (cid, alias)
        parameters.add_check(self.refusal)

    @property
    def names(self) -> List[str]:
        """Return the names of the control parameters declared."""
        return list(self._specs)

    def declare(self, static_names) -> None:
        """
        Declare a parameter for each control of the open camera and each usb_cam name it has.

        What the user gave (command line, params file, launch) is applied to the device first,
        automatic modes before the controls they own; a value the device refuses is one warning
        and the device's own value is kept. static_names: the node's other parameters.
        """
        controls = self._read_controls()
        by_id = {control.cid: control for control in controls}
        wanted = []
        for control in controls:
            if control.name in static_names:
                continue  # a device naming a control like one of the node's own parameters
            self._targets[control.name] = (control.cid, None)
            wanted.append(control.name)
        for alias in USB_CAM_ALIASES.values():
            control = by_id.get(alias.cid)
            if control is None or alias.name in self._targets:
                if control is None and self._parameters.given(alias.name) is not None:
                    self._log.warning('%s: %s has no such control; the value is not used' % (
                        alias.name, self._device))
                continue
            self._targets[alias.name] = (alias.cid, alias)
            wanted.append(alias.name)
        given = {name: self._parameters.given(name) for name in wanted}
        owners = {owner for owner, _ in OWNED_BY.values()}
        for name in sorted(wanted, key=lambda n: self._targets[n][0] not in owners):
            if given[name] is None:
                continue
            spec = self._spec(name, by_id)
            # A value of the wrong type is an error; one the device refuses, a warning.
            value = replace(spec, value_range=None, step=1).coerce(given[name])
            if value == spec.default:
                continue
            reason = self._set_control(name, value)
            if reason:
                self._log.warning("%s; left at the camera's own value" % reason)
        # The values now; a control the device no longer answers for (it was unplugged
        # meanwhile) keeps what the first read said, and sync() catches up once it is back.
        by_id.update((control.cid, control) for control in self._read_controls())
        for name in wanted:
            spec = self._spec(name, by_id)
            self._specs[name] = spec
            self._parameters.declare_shown(spec, self._setter(name) if spec.live else None,
                                           first=self._targets[name][0] in owners)

    def refusal(self, changes: Dict[str, Any]) -> Optional[str]:
        """
        Return why the camera would refuse one of changes (name -> value) made together.

        None when it takes them all. A control inactive now counts as active when the same
        changes switch off the automatic mode that owns it. A camera that is lost answers
        nothing here: applying the changes reports it.
        """
        by_id = {control.cid: control for control in self._read_controls()}
        wanted = []  # (name, alias, control, device value)
        for name, value in changes.items():
            if name not in self._targets or self._targets[name][0] not in by_id:
                continue
            cid, alias = self._targets[name]
            control = by_id[cid]
            wanted.append((name, alias, control,
                           alias.to_device(value, control) if alias else int(value)))
        raw = {control.cid: device_value for _, _, control, device_value in wanted}
        for name, alias, control, device_value in wanted:
            owner, frees = OWNED_BY.get(control.cid, (None, ()))
            if control.inactive and raw.get(owner) in frees:
                control = replace(control, inactive=False)
            reason = control.refusal(device_value)
            if reason:
                return reason.replace(control.name, name, 1) if alias else reason
        return None

    def _spec(self, name, by_id) -> Spec:
        cid, alias = self._targets[name]
        return alias_spec(alias, by_id[cid]) if alias else control_spec(by_id[cid])

    def _setter(self, name):
        def apply(value):
            return self._set_control(name, value)
        return apply

    def sync(self) -> None:
        """Show the device's current values and activity in the parameters."""
        controls = self._read_controls()
        if not controls:
            return  # the camera is lost: the parameters keep the last values
        by_id = {control.cid: control for control in controls}
        values, changed = {}, []
        for name in self._specs:
            cid = self._targets[name][0]
            if cid not in by_id:
                continue
            spec = self._spec(name, by_id)
            values[name] = spec.default
            if spec.constraints != self._specs[name].constraints:
                changed.append(spec)
                self._specs[name] = spec
        self._parameters.show(values, changed)
