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
What a device offers, as text: `usbcam_publisher --list-formats` (and `--list-devices`).

Asks the device itself (V4L2 ioctls, or the synthetic camera's model, or the file's own size),
without streaming and without ROS: each pixel format with its frame sizes and rates and what
py_vision makes of it (its sensor_msgs encoding as sent, from the pixel format table), then the
controls with their ranges, menus and values. `devices_listing` is every /dev/videoN in one line
each (devices.video_devices). It stands above the camera layer: it names controls by their
parameter names (control_names), which the camera layer does not know.
"""

from typing import List

import cv2
from py_vision.capture.camera import open_source
from py_vision.capture.controls import ControlInfo
from py_vision.capture.devices import classify, FILE, SYNTHETIC, UVC_DRIVER, video_devices
from py_vision.capture.pixel_formats import find
from py_vision.capture.source import FrameFormat, SourceError
from py_vision.capture.synthetic_device import SyntheticDevices
from py_vision.capture.v4l2 import V4L2Device, V4L2Error
from py_vision.control_names import param_name

__all__ = ['device_listing', 'devices_listing']


def _rates(rates) -> str:
    return ', '.join('%g' % rate for rate in rates) + ' fps'


def _what_it_gives(fourcc: str) -> str:
    pixel_format = find(fourcc)
    if pixel_format is None:
        return 'not a format py_vision converts'
    if pixel_format.jpeg:
        return "compressed: the camera's JPEG is published as it is"
    if pixel_format.video:
        return ("compressed video: the camera's access units are published as they are "
                '(pixel_format:=%s)' % pixel_format.fourcc.lower())
    if pixel_format.encoding is None:
        return 'native: %s (sensor_msgs has no encoding for it)' % pixel_format.native_encoding
    return 'native: %s' % pixel_format.encoding


def _format_lines(listed: FrameFormat) -> List[str]:
    lines = ['%s (%s), %s' % (listed.fourcc, listed.description, _what_it_gives(listed.fourcc))]
    if listed.size_range:
        low_w, low_h, high_w, high_h = listed.size_range
        lines.append('  any size from %dx%d to %dx%d, e.g.:' % (low_w, low_h, high_w, high_h))
    for size in listed.sizes:
        rates = _rates(size.rates) if size.rates else 'rate not listed'
        lines.append('  %dx%d: %s' % (size.width, size.height, rates))
    if listed.rate_range:
        lines.append('  any rate from %g to %g fps' % listed.rate_range)
    return lines


def _control_lines(controls: List[ControlInfo]) -> List[str]:
    if not controls:
        return ['controls: none']
    return ['controls (parameters of usbcam_publisher):'] + [
        '  %s %s' % (param_name(control.label), control.summary()) for control in controls]


def device_listing(video_device: str) -> str:
    """Return what video_device offers, as lines of text; SourceError (one line) if it can't."""
    target = classify(video_device)
    device = target.device
    if target.kind == SYNTHETIC:
        source = open_source(device, 640, 480, 30.0, synthetic=SyntheticDevices())
        try:
            lines = ['%s: the synthetic camera (USB 2.0, a scaler)' % device]
            for listed in source.formats():
                lines += _format_lines(listed)
            lines += _control_lines(source.controls())
        finally:
            source.release()
        return '\n'.join(lines) + '\n'
    if target.kind == FILE:
        source = open_source(device, 0, 0, 0)
        try:
            return '%s: a video file, %dx%d at %g fps (no formats or controls to choose)\n' % (
                device, source.get(cv2.CAP_PROP_FRAME_WIDTH),
                source.get(cv2.CAP_PROP_FRAME_HEIGHT), source.get(cv2.CAP_PROP_FPS))
        finally:
            source.release()
    try:
        with V4L2Device(target.path) as opened:
            where = device if target.path == device else '%s (%s)' % (device, target.path)
            lines = ['%s: %s, driver %s, %s' % (where, opened.card, opened.driver,
                                                opened.bus_info)]
            for listed in opened.formats():
                lines += _format_lines(listed)
            lines += _control_lines(opened.controls())
    except V4L2Error as error:
        raise SourceError('cannot open video_device "%s": %s' % (device, error.reason)) \
            from None
    return '\n'.join(lines) + '\n'


def devices_listing() -> str:
    """Return every video device, one line each: what it is, its links, its formats."""
    found = video_devices()
    if not found:
        return 'no video devices (/dev/video*)\n'
    lines = []
    auto = next((device.path for device in found if device.usb_camera), None)
    for device in found:
        if device.problem:
            words = ['cannot be asked: %s' % device.problem]
        else:
            words = [device.card or '(no name)', 'driver %s' % device.driver,
                     device.bus or 'no bus info']
        words += ['by-id %s' % link if '/by-id/' in link else 'by-path %s' % link
                  for link in device.links]
        if device.capture:
            words.append('formats %s' % (' '.join(device.formats) or 'none listed'))
        elif not device.problem:
            words.append('not a capture device' + (
                " (a USB camera's metadata node)" if device.driver == UVC_DRIVER else ''))
        if device.path == auto:
            words.append('video_device:=auto opens it')
        lines.append('%s: %s' % (device.path, ', '.join(words)))
    return '\n'.join(lines) + '\n'
