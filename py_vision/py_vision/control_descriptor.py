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
How a parameter says it is a camera control or a step's: by words in its descriptor.

control_params and vision_step write them, camera_panel reads them.

A camera control's descriptor has `additional_constraints` beginning with ``camera control``,
then its V4L2 id, type, step and default (``camera control 0x00980900 (integer, step 1,
default 0)``; a button's ``(button)``), ``; inactive while ...`` when the camera ignores it
now and ``; read-only``; one of usb_cam's names has ``camera control: usb_cam name for
<control>``. A menu control's description ends with its entries: ``Auto Exposure; menu:
1=Manual Mode; 3=Aperture Priority Mode`` (an integer menu's labels are its values).

A processing step's own parameter (vision_step declares it beside the node's) has
``step parameter of <step>``, then ``; one of: a | b`` when it takes one of a few strings and
``; accepts <words>`` when a further condition says what it takes. Only strings here: neither
side's layer is imported.
"""

from dataclasses import dataclass
import re
from typing import Any, Dict, List, Optional, Sequence, Tuple

__all__ = ['CONTROL_MARK', 'ControlWords', 'alias_constraints', 'control_constraints',
           'describe', 'is_control', 'parse_constraints', 'parse_menu', 'parse_step',
           'STEP_MARK', 'step_constraints', 'StepWords']

CONTROL_MARK = 'camera control'
STEP_MARK = 'step parameter of '
_CHOICES_MARK = 'one of: '
_CHOICE_SEPARATOR = ' | '
_MENU_MARK = 'menu: '
_ALIAS = re.compile(r'\bname for ([A-Za-z0-9_]+)')
_INACTIVE = re.compile(r'\binactive (while [^;]*)')
_DEFAULT_INACTIVE = "the camera's current mode holds it"


def describe(label: str, menu: Sequence[Tuple[int, str]] = ()) -> str:
    """Return a control's description: its label, and its menu entries when it has some."""
    if not menu:
        return label
    return '%s; %s%s' % (label, _MENU_MARK, '; '.join('%d=%s' % entry for entry in menu))


def control_constraints(cid: int, kind: str, step: int, default: int,
                        inactive: Optional[str] = None, read_only: bool = False) -> str:
    """Return a control's additional_constraints; inactive: why it is (None: active)."""
    if kind == 'button':
        words = '%s 0x%08x (button)' % (CONTROL_MARK, cid)
    else:
        words = '%s 0x%08x (%s, step %d, default %d)' % (
            CONTROL_MARK, cid, kind, step, default)
    if inactive is not None:
        words += '; inactive while %s' % (inactive or _DEFAULT_INACTIVE)
    if read_only:
        words += '; read-only'
    return words


def alias_constraints(control_name: str) -> str:
    """Return the additional_constraints of one of usb_cam's names for control_name."""
    return '%s: usb_cam name for %s' % (CONTROL_MARK, control_name)


def is_control(constraints: str) -> bool:
    """Return True when additional_constraints mark a camera control."""
    return constraints.startswith(CONTROL_MARK)


@dataclass(frozen=True)
class ControlWords:
    """What a camera control's additional_constraints say."""

    kind: Optional[str]        # the type named after the mark, when it names one
    alias_of: Optional[str]    # the control a usb_cam name stands for
    inactive: Optional[str]    # 'while ...': why the camera ignores it now; None: active


def parse_constraints(constraints: str, kinds: Sequence[str] = ()) -> Optional[ControlWords]:
    """Return what a camera control's constraints say, or None when they are not one's."""
    if not is_control(constraints):
        return None
    words = re.sub(r'[,()]', ' ', constraints[len(CONTROL_MARK):].split(';')[0])
    kind = next((word for word in words.split() if word in kinds), None)
    alias = _ALIAS.search(constraints)
    inactive = _INACTIVE.search(constraints)
    return ControlWords(kind, alias.group(1) if alias else None,
                        inactive.group(1).strip() if inactive else None)


def parse_menu(description: str) -> Optional[List[Dict[str, Any]]]:
    """Return the entries of 'menu: 1=Manual; 3=Auto' in a description, or None."""
    at = description.find(_MENU_MARK)
    if at < 0:
        return None
    entries = []
    for item in description[at + len(_MENU_MARK):].split('; '):
        value, equals, label = item.partition('=')
        try:
            number = int(value.strip())
        except ValueError:
            break
        if not equals:
            break
        entries.append({'value': number, 'label': label.strip()})
    return entries or None


def step_constraints(step: str, choices: Sequence[str] = (), accepted: str = '') -> str:
    """Return the additional_constraints of a parameter of step: its mark, choices, words."""
    words = STEP_MARK + step
    if choices:
        words += '; %s%s' % (_CHOICES_MARK, _CHOICE_SEPARATOR.join(choices))
    if accepted:
        words += '; accepts %s' % accepted
    return words


@dataclass(frozen=True)
class StepWords:
    """What a step parameter's additional_constraints say."""

    step: str                      # the step's name, as the node's `step` gives it
    choices: Tuple[str, ...]       # the strings it takes, when it takes one of a few


def parse_step(constraints: str) -> Optional[StepWords]:
    """Return what a step parameter's constraints say, or None when they are not one's."""
    if not constraints.startswith(STEP_MARK):
        return None
    parts = constraints[len(STEP_MARK):].split('; ')
    choices: Tuple[str, ...] = ()
    for part in parts[1:]:
        if part.startswith(_CHOICES_MARK):
            choices = tuple(part[len(_CHOICES_MARK):].split(_CHOICE_SEPARATOR))
    return StepWords(parts[0].strip(), choices)
