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
A camera described by a data file: the one description the test cameras are made from.

The synthetic camera (`SYNTHETIC`, synthetic_camera.yaml beside this module) and the emulated
UVC cameras of the tests (py_vision/test/uvc_emulator/cameras/) are described in one YAML
format, read here: who the camera is (vendor, product, serial, USB port), its pixel formats
with their sizes and frame rates, its controls as the device reports them (V4L2 id, label,
type, range, default, menu, the automatic mode that holds it, what it does to the picture),
and the isochronous bandwidth it gets on its USB 2.0 bus. `bus_rates` is the bus's rule of
what a camera offers. The format, key by key: docs/emulated_cameras.md.
"""

from dataclasses import dataclass
from pathlib import Path
from typing import Any, Dict, Optional, Tuple

from py_vision.capture.controls import (
    ARRAY, BITMASK, BOOL, BUTTON, COMPOUND, ControlInfo, INT, INT64, INT_MENU, MENU, STRING)
from py_vision.capture.pixel_formats import find, PixelFormat
from py_vision.capture.source import FrameSize
import yaml

__all__ = ['bus_rates', 'CameraModel', 'CONTROL_TYPES', 'EFFECTS', 'load', 'ModelControl',
           'ModelFormat', 'SYNTHETIC', 'USB2_BANDWIDTH']

SYNTHETIC = Path(__file__).with_name('synthetic_camera.yaml')
# Bytes per second of isochronous video a camera gets on a USB 2.0 high-speed bus, unless its
# data file says otherwise (usb_bandwidth).
USB2_BANDWIDTH = 24000000
# A control's type in a data file -> its kind (enum v4l2_ctrl_type; u8, u16 and u32 are arrays).
CONTROL_TYPES = {'integer': INT, 'boolean': BOOL, 'menu': MENU, 'button': BUTTON,
                 'integer64': INT64, 'string': STRING, 'bitmask': BITMASK,
                 'integer_menu': INT_MENU, 'u8': ARRAY, 'u16': ARRAY, 'u32': ARRAY,
                 'area': COMPOUND}
# What a control may do to the picture (`effect`).
EFFECTS = ('brightness', 'contrast', 'saturation', 'gain', 'exposure', 'white_balance')


def bus_rates(pixel_format: PixelFormat, width: int, height: int, rates: Tuple[float, ...],
              bandwidth: float = USB2_BANDWIDTH) -> Tuple[float, ...]:
    """
    Return the rates, highest first, a USB camera offers of a format at a size.

    A raw format's frames must fit the camera's bandwidth: the rates of `rates` at which they
    do, or the lowest when none does (as a UVC camera still lists its slowest interval); a
    compressed format's frames are as small as needed, so every rate.
    """
    ordered = tuple(sorted(rates, reverse=True))
    if pixel_format.compressed:
        return ordered
    fitting = tuple(rate for rate in ordered
                    if width * height * pixel_format.bus_bytes * rate <= bandwidth)
    return fitting or ordered[-1:]


@dataclass(frozen=True)
class ModelFormat:
    """One pixel format of a camera: its sizes and the rates listed for every size."""

    pixel_format: PixelFormat
    description: str
    sizes: Tuple[Tuple[int, int], ...]
    rates: Tuple[float, ...]          # highest first

    def frame_sizes(self, bandwidth: float) -> Tuple[FrameSize, ...]:
        """Return each size with the rates it offers on a bus giving this bandwidth."""
        return tuple(FrameSize(width, height,
                               bus_rates(self.pixel_format, width, height, self.rates, bandwidth))
                     for width, height in self.sizes)


@dataclass(frozen=True)
class ModelControl:
    """
    One control of a camera: what the device reports at power-up, and how it behaves.

    `name` is the control's V4L2 name (what the tests call it); `held_by` is (the V4L2 id of
    the automatic mode that holds it, the value of that mode that frees it) or None; `effect`
    is what it does to the picture (one of EFFECTS) or None; `dims` an array's dimensions.
    """

    name: str
    type: str                          # noqa: A003 (the data file's word, a CONTROL_TYPES key)
    info: ControlInfo
    held_by: Optional[Tuple[int, int]] = None
    effect: Optional[str] = None
    dims: Tuple[int, ...] = ()


@dataclass(frozen=True)
class CameraModel:
    """
    A camera as its data file describes it.

    `name` is the file's stem; `data` the file as read (identity, and what only one of the
    test cameras uses: faults, clips, ...); `default_size` what it opens with.
    """

    name: str
    data: Dict[str, Any]
    formats: Tuple[ModelFormat, ...]
    controls: Tuple[ModelControl, ...]
    bandwidth: float
    default_size: Tuple[int, int]

    def frame_sizes(self, model_format: ModelFormat) -> Tuple[FrameSize, ...]:
        """Return a format's sizes with the rates each offers on this camera's bus."""
        return model_format.frame_sizes(self.bandwidth)


def load(path) -> CameraModel:
    """Read a camera's data file; ValueError naming the file and what is wrong in it."""
    path = Path(path)
    try:
        data = yaml.safe_load(path.read_text())
    except (OSError, yaml.YAMLError) as error:
        raise ValueError('%s: cannot read the camera: %s'
                         % (path, ' '.join(str(error).split()))) from None
    if not isinstance(data, dict) or not data.get('formats'):
        raise ValueError('%s: a camera needs formats' % path)
    formats = tuple(_format(path, entry) for entry in data['formats'])
    controls = data.get('controls') or []
    ids = {entry.get('name'): entry.get('id') for entry in controls}
    first = formats[0].sizes[0]
    return CameraModel(path.stem, data, formats,
                       tuple(_control(path, entry, ids) for entry in controls),
                       float(data.get('usb_bandwidth', USB2_BANDWIDTH)),
                       tuple(data.get('default_size') or first))


def _format(path, entry) -> ModelFormat:
    pixel_format = find(str(entry.get('fourcc')))
    if pixel_format is None:
        raise ValueError('%s: py_vision has no pixel format %s' % (path, entry.get('fourcc')))
    sizes = tuple((int(width), int(height)) for width, height in entry.get('sizes') or ())
    rates = tuple(sorted((float(rate) for rate in entry.get('rates') or ()), reverse=True))
    if not sizes or not rates or min(min(size) for size in sizes) < 1 or rates[-1] <= 0:
        raise ValueError('%s: %s needs sizes and rates above 0' % (path, pixel_format.fourcc))
    return ModelFormat(pixel_format, entry.get('description', pixel_format.description),
                       sizes, rates)


def _control(path, entry, ids) -> ModelControl:
    name, kind = entry.get('name'), CONTROL_TYPES.get(entry.get('type'))
    if kind is None:
        raise ValueError('%s: %s has type %r, not one of %s'
                         % (path, name, entry.get('type'), ', '.join(CONTROL_TYPES)))
    if entry.get('effect') not in (None,) + EFFECTS:
        raise ValueError('%s: %s has effect %r, not one of %s'
                         % (path, name, entry['effect'], ', '.join(EFFECTS)))
    held_by = None
    for master, value in (entry.get('inactive_unless') or {}).items():
        if master not in ids:
            raise ValueError('%s: %s depends on unknown control %s' % (path, name, master))
        held_by = (ids[master], int(value))
    menu = tuple((int(index), str(label)) for index, label in sorted(
        (entry.get('menu') or {}).items()))
    settable = kind not in (BUTTON, STRING, ARRAY, COMPOUND)
    info = ControlInfo(int(entry['id']), str(entry['label']), kind, int(entry.get('min', 0)),
                       int(entry.get('max', 0)), int(entry.get('step', 0)),
                       int(entry.get('default', 0)),
                       int(entry.get('default', 0)) if settable else None, menu,
                       bool(entry.get('read_only')))
    return ModelControl(name, entry['type'], info, held_by, entry.get('effect'),
                        tuple(entry.get('dims') or ()))
