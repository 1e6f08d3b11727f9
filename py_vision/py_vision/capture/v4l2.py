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
V4L2 devices: what they are and offer, and their controls, asked through ioctls.

`V4L2Device` asks the driver directly (fcntl.ioctl, struct layouts of linux/videodev2.h):
what the device is (QUERYCAP), the pixel formats, frame sizes and frame intervals it offers
(ENUM_FMT, ENUM_FRAMESIZES, ENUM_FRAMEINTERVALS), and every control of every type
(QUERY_EXT_CTRL walking V4L2_CTRL_FLAG_NEXT_CTRL and NEXT_COMPOUND, or QUERYCTRL on old
drivers; QUERYMENU; G_CTRL and S_CTRL, G_EXT_CTRLS and S_EXT_CTRLS for 64-bit values).
Streaming the frames is v4l2_stream's.
"""

import ctypes
import errno
import fcntl
import os
import struct
from typing import List, Optional

from py_vision.capture.controls import (
    ARRAY, BITMASK, BOOL, BUTTON, COMPOUND, ControlInfo, INT, INT64, INT_MENU, MENU, SETTABLE,
    STRING)
from py_vision.capture.pixel_formats import fourcc_text
from py_vision.capture.source import FrameFormat, FrameSize

__all__ = ['open_problem', 'V4L2Device', 'V4L2Error']


def _ioc(direction, number, size):
    return (direction << 30) | (size << 16) | (ord('V') << 8) | number


_READ, _READ_WRITE = 2, 3
# struct v4l2_capability: driver[16] card[32] bus_info[32] version capabilities device_caps
# reserved[3].
_CAPABILITY = struct.Struct('=16s32s32sIII12x')
# struct v4l2_fmtdesc: index type flags description[32] pixelformat mbus_code reserved[3].
_FMTDESC = struct.Struct('=III32sII12x')
# struct v4l2_frmsizeenum: index pixel_format type, a union of discrete (width height) or
# stepwise (min_width max_width step_width min_height max_height step_height), reserved[2].
_FRMSIZE = struct.Struct('=III6I8x')
# struct v4l2_frmivalenum: index pixel_format width height type, a union of discrete
# (numerator denominator) or stepwise (min, max, step fractions), reserved[2].
_FRMIVAL = struct.Struct('=IIIII6I8x')
# struct v4l2_query_ext_ctrl: id type name[32] minimum maximum step default_value (64 bit)
# flags elem_size elems nr_of_dims dims[4] reserved[32].
_EXT_CTRL = struct.Struct('=II32sqqQqIIII16x128x')
# struct v4l2_queryctrl: id type name[32] minimum maximum step default_value flags reserved[2].
_QUERYCTRL = struct.Struct('=II32siiiiI8x')
# struct v4l2_querymenu (packed): id index, a union of name[32] or an int64 value, reserved.
_QUERYMENU = struct.Struct('=II32sI')
# struct v4l2_control: id value.
_CONTROL = struct.Struct('=Ii')


class _ExtValue(ctypes.Union):
    _fields_ = [('value', ctypes.c_int32), ('value64', ctypes.c_int64)]


class _ExtControl(ctypes.Structure):
    # struct v4l2_ext_control (packed): id size reserved2[1], then the value's union.
    _pack_ = 1
    _fields_ = [('id', ctypes.c_uint32), ('size', ctypes.c_uint32),
                ('reserved2', ctypes.c_uint32), ('u', _ExtValue)]


class _ExtControls(ctypes.Structure):
    # struct v4l2_ext_controls: which count error_idx request_fd reserved[1] controls.
    _fields_ = [('which', ctypes.c_uint32), ('count', ctypes.c_uint32),
                ('error_idx', ctypes.c_uint32), ('request_fd', ctypes.c_int32),
                ('reserved', ctypes.c_uint32), ('controls', ctypes.POINTER(_ExtControl))]


# struct v4l2_requestbuffers: count type memory capabilities flags reserved[3].
_REQBUFS = struct.Struct('=IIIIB3x')

VIDIOC_QUERYCAP = _ioc(_READ, 0, _CAPABILITY.size)
VIDIOC_ENUM_FMT = _ioc(_READ_WRITE, 2, _FMTDESC.size)
VIDIOC_REQBUFS = _ioc(_READ_WRITE, 8, _REQBUFS.size)
VIDIOC_G_CTRL = _ioc(_READ_WRITE, 27, _CONTROL.size)
VIDIOC_S_CTRL = _ioc(_READ_WRITE, 28, _CONTROL.size)
VIDIOC_QUERYCTRL = _ioc(_READ_WRITE, 36, _QUERYCTRL.size)
VIDIOC_QUERYMENU = _ioc(_READ_WRITE, 37, _QUERYMENU.size)
VIDIOC_G_EXT_CTRLS = _ioc(_READ_WRITE, 71, ctypes.sizeof(_ExtControls))
VIDIOC_S_EXT_CTRLS = _ioc(_READ_WRITE, 72, ctypes.sizeof(_ExtControls))
VIDIOC_ENUM_FRAMESIZES = _ioc(_READ_WRITE, 74, _FRMSIZE.size)
VIDIOC_ENUM_FRAMEINTERVALS = _ioc(_READ_WRITE, 75, _FRMIVAL.size)
VIDIOC_QUERY_EXT_CTRL = _ioc(_READ_WRITE, 103, _EXT_CTRL.size)

CAP_VIDEO_CAPTURE = 0x00000001
CAP_VIDEO_CAPTURE_MPLANE = 0x00001000
CAP_DEVICE_CAPS = 0x80000000
BUF_TYPE_VIDEO_CAPTURE = 1
MEMORY_MMAP, MEMORY_USERPTR = 1, 2
FRMSIZE_DISCRETE, FRMIVAL_DISCRETE = 1, 1
CTRL_FLAG_DISABLED = 0x0001
CTRL_FLAG_READ_ONLY = 0x0004
CTRL_FLAG_INACTIVE = 0x0010
CTRL_FLAG_WRITE_ONLY = 0x0040
CTRL_FLAG_DYNAMIC_ARRAY = 0x0800
CTRL_FLAG_NEXT_CTRL = 0x80000000
CTRL_FLAG_NEXT_COMPOUND = 0x40000000
# enum v4l2_ctrl_type; from 0x100 on the compound types (U8, U16, U32 are arrays' elements).
_CTRL_TYPES = {1: INT, 2: BOOL, 3: MENU, 4: BUTTON, 5: INT64, 7: STRING, 8: BITMASK,
               9: INT_MENU}
_COMPOUND_TYPES, _ELEMENT_TYPES = 0x0100, (0x0100, 0x0101, 0x0102)
_CTRL_CLASS_TYPE = 6
# A stepwise or continuous size range is offered at these common sizes.
_COMMON_SIZES = ((160, 120), (320, 240), (640, 480), (800, 600), (1024, 768), (1280, 720),
                 (1280, 960), (1600, 1200), (1920, 1080), (2560, 1440), (3840, 2160))


def _text(raw: bytes) -> str:
    return raw.split(b'\0', 1)[0].decode('utf-8', 'replace').strip()


def _kind(kind: int, dims: int, flags: int) -> str:
    """Return what a control is, from its V4L2 type, its number of dimensions and flags."""
    if dims or flags & CTRL_FLAG_DYNAMIC_ARRAY or kind in _ELEMENT_TYPES:
        return ARRAY
    # A type newer than this code carries a payload too: not a number to set.
    return _CTRL_TYPES.get(kind, COMPOUND)


class V4L2Error(Exception):
    """A V4L2 device that cannot be used; `reason` says why in words, `errno` is the cause."""

    def __init__(self, reason: str, code: Optional[int] = None):
        super().__init__(reason)
        self.reason = reason
        self.errno = code


def open_problem(code: int) -> str:
    """Return what an errno from opening or using a video device means to a user."""
    if code in (errno.EACCES, errno.EPERM):
        return 'permission denied (add the user to the "video" group: ' \
               'sudo usermod -aG video $USER, then log in again)'
    if code == errno.EBUSY:
        return 'the device is busy (another program is streaming from it)'
    if code in (errno.ENOENT, errno.ENXIO, errno.ENODEV):
        return 'no such device (unplugged?)'
    return os.strerror(code)


class V4L2Device:
    """A V4L2 device opened for its answers (not for streaming): caps, formats, controls."""

    def __init__(self, path: str, capture_only: bool = True):
        self.path = path
        self._kinds = {}   # control id -> kind, as controls() last found them
        # (id, minimum, maximum, kind) -> a menu's entries: a control's menu is the driver's
        # own table, asked for once while the device is open (controls() runs twice a second).
        self._menus = {}
        # What the last walk of the controls found, and a request that reads all their values
        # in one ioctl: while those values stay the same, so do the controls' ranges and flags
        # (an automatic mode makes others inactive by its value).
        # A new format or rate may change ranges and flags without a value (a sensor's
        # exposure range): forget_controls() then has them walked again.
        self._known: Optional[List[ControlInfo]] = None
        self._known_values: Optional[List[int]] = None
        self._values_request = None
        try:
            self.fd = os.open(path, os.O_RDWR | os.O_NONBLOCK)
        except OSError as error:
            raise V4L2Error(open_problem(error.errno), error.errno) from None
        try:
            self.driver, self.card, self.bus_info, caps = self._querycap()
        except V4L2Error:
            self.close()
            raise
        self.caps = caps
        if capture_only and not self.capture:
            self.close()
            raise V4L2Error('not a video capture device (%s has no capture capability)'
                            % (self.card or 'it'))

    @property
    def capture(self) -> bool:
        """Return True for a video capture node (not a UVC camera's metadata node, an output)."""
        return bool(self.caps & (CAP_VIDEO_CAPTURE | CAP_VIDEO_CAPTURE_MPLANE))

    def _ioctl(self, request, buffer):
        fcntl.ioctl(self.fd, request, buffer)
        return buffer

    def _querycap(self):
        try:
            data = self._ioctl(VIDIOC_QUERYCAP, bytearray(_CAPABILITY.size))
        except OSError as error:
            if error.errno in (errno.ENOTTY, errno.EINVAL):
                raise V4L2Error('not a video capture device (it does not answer V4L2)',
                                error.errno) from None
            raise V4L2Error(open_problem(error.errno), error.errno) from None
        driver, card, bus, _, caps, device_caps = _CAPABILITY.unpack(data)
        if caps & CAP_DEVICE_CAPS:
            caps = device_caps
        return _text(driver), _text(card), _text(bus), caps

    def close(self) -> None:
        """Close the device's handle."""
        if self.fd is not None:
            os.close(self.fd)
            self.fd = None

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()

    # --- formats --------------------------------------------------------------------

    def formats(self) -> List[FrameFormat]:
        """Return each pixel format the device offers with its sizes and rates."""
        found = []
        for index in range(64):
            buffer = bytearray(_FMTDESC.pack(index, BUF_TYPE_VIDEO_CAPTURE, 0, b'', 0, 0))
            try:
                self._ioctl(VIDIOC_ENUM_FMT, buffer)
            except OSError:
                break
            _, _, _, description, pixelformat, _ = _FMTDESC.unpack(buffer)
            found.append(self._format(fourcc_text(pixelformat), _text(description),
                                      pixelformat))
        return found

    def _format(self, fourcc, description, pixelformat):
        listed, size_range = self._sizes(pixelformat)
        sizes, rate_range = [], None
        for width, height in listed:
            rates, stepwise = self._rates(pixelformat, width, height)
            sizes.append(FrameSize(width, height, tuple(rates)))
            if stepwise and rates:
                rate_range = (rates[-1], rates[0])
        return FrameFormat(fourcc, description, tuple(sizes), size_range, rate_range)

    def _sizes(self, pixelformat):
        """Return the discrete sizes, and the range of a stepwise or continuous one."""
        sizes = []
        for index in range(256):
            buffer = bytearray(_FRMSIZE.pack(index, pixelformat, 0, 0, 0, 0, 0, 0, 0))
            try:
                self._ioctl(VIDIOC_ENUM_FRAMESIZES, buffer)
            except OSError:
                break
            _, _, kind, *values = _FRMSIZE.unpack(buffer)
            if kind == FRMSIZE_DISCRETE:
                sizes.append((values[0], values[1]))
                continue
            low_w, high_w, step_w, low_h, high_h, step_h = values
            common = [(w, h) for w, h in _COMMON_SIZES
                      if low_w <= w <= high_w and low_h <= h <= high_h
                      and (w - low_w) % max(step_w, 1) == 0
                      and (h - low_h) % max(step_h, 1) == 0]
            return common, (low_w, low_h, high_w, high_h)
        return sizes, None

    def _rates(self, pixelformat, width, height):
        """Return the rates a size offers, highest first, and whether they are a range."""
        rates = []
        for index in range(64):
            buffer = bytearray(_FRMIVAL.pack(index, pixelformat, width, height, 0,
                                             0, 0, 0, 0, 0, 0))
            try:
                self._ioctl(VIDIOC_ENUM_FRAMEINTERVALS, buffer)
            except OSError:
                break
            _, _, _, _, kind, num, den, *stepwise = _FRMIVAL.unpack(buffer)
            if kind == FRMIVAL_DISCRETE:
                if num and den:
                    rates.append(den / num)
                continue
            # A range of intervals: the shortest and longest bound the rates.
            bounds = [den / num for num, den in ((num, den), stepwise[:2]) if num and den]
            return sorted(set(bounds), reverse=True), True
        return sorted(set(rates), reverse=True), False

    # --- controls -------------------------------------------------------------------

    def controls(self) -> List[ControlInfo]:
        """
        Return every control, of every type, with its value where one number holds it.

        Every control is asked for again (VIDIOC_QUERY_EXT_CTRL, VIDIOC_G_CTRL each) only when
        a value changed since the last call: the values themselves are read in one ioctl.
        """
        known = self._known
        if known is not None:
            values = self._read_values()
            if values is not None and values == self._known_values:
                return list(known)
        found = self._walk()
        self._known = found
        self._values_request = None
        self._known_values = self._read_values()
        return list(found)

    def forget_controls(self) -> None:
        """Have the next controls() ask for every control again (the format or rate changed)."""
        self._known = self._known_values = self._values_request = None

    def _read_values(self) -> Optional[List[int]]:
        """Return the values of the controls last walked, read in one ioctl; None if not."""
        request = self._values_request
        if request is None:
            readable = [control for control in self._known if control.value is not None]
            items = (_ExtControl * len(readable))()
            for item, control in zip(items, readable):
                item.id = control.cid
            kinds = [control.kind for control in readable]
            request = self._values_request = (_ExtControls(count=len(readable), controls=items),
                                              items, kinds)
        controls, items, kinds = request
        if not kinds:
            return []
        try:
            self._ioctl(VIDIOC_G_EXT_CTRLS, controls)
        except OSError:
            return None   # a driver that will not read them together: walked every time
        return [item.u.value64 if kind == INT64 else item.u.value & 0xFFFFFFFF
                if kind == BITMASK else item.u.value for item, kind in zip(items, kinds)]

    def _walk(self) -> List[ControlInfo]:
        """Ask the device for every control, its range, flags, menu and value."""
        try:
            queried = list(self._walk_ext())
        except OSError:
            queried = list(self._walk_old())  # a driver without VIDIOC_QUERY_EXT_CTRL
        found = []
        for cid, kind, label, low, high, step, default, flags in queried:
            if flags & CTRL_FLAG_DISABLED:
                continue
            if kind == BITMASK:   # the old ioctl's 32 bits are signed
                high, default = high & 0xFFFFFFFF, default & 0xFFFFFFFF
            self._kinds[cid] = kind
            menu = ()
            if kind in (MENU, INT_MENU):
                key = (cid, low, high, kind)
                menu = self._menus.get(key)
                if menu is None:
                    menu = self._menus[key] = tuple(self._menu(cid, low, high, kind))
            value = None
            if kind in SETTABLE and kind != BUTTON and not flags & CTRL_FLAG_WRITE_ONLY:
                value = self.get_control(cid)
            found.append(ControlInfo(
                cid, label, kind, int(low), int(high), max(int(step), 1), int(default), value,
                menu, read_only=bool(flags & CTRL_FLAG_READ_ONLY),
                inactive=bool(flags & CTRL_FLAG_INACTIVE)))
        return found

    def _walk_ext(self):
        # NEXT_CTRL alone skips arrays and compound types: both flags walk every control.
        walk = CTRL_FLAG_NEXT_CTRL | CTRL_FLAG_NEXT_COMPOUND
        cid = walk
        while True:
            buffer = bytearray(_EXT_CTRL.size)
            struct.pack_into('=I', buffer, 0, cid)
            try:
                self._ioctl(VIDIOC_QUERY_EXT_CTRL, buffer)
            except OSError as error:
                if error.errno == errno.EINVAL and cid != walk:
                    return  # past the last control
                raise
            (found, kind, name, low, high, step, default, flags,
             _, _, dims) = _EXT_CTRL.unpack(buffer)
            if kind != _CTRL_CLASS_TYPE:
                yield (found, _kind(kind, dims, flags), _text(name), low, high, step, default,
                       flags)
            cid = found | walk

    def _walk_old(self):
        cid = CTRL_FLAG_NEXT_CTRL
        while True:
            buffer = bytearray(_QUERYCTRL.pack(cid, 0, b'', 0, 0, 0, 0, 0))
            try:
                self._ioctl(VIDIOC_QUERYCTRL, buffer)
            except OSError:
                return
            found, kind, name, low, high, step, default, flags = _QUERYCTRL.unpack(buffer)
            if kind != _CTRL_CLASS_TYPE:
                yield found, _kind(kind, 0, flags), _text(name), low, high, step, default, flags
            cid = found | CTRL_FLAG_NEXT_CTRL

    def _menu(self, cid, low, high, kind):
        """Yield (index, label) of each entry; an integer menu's label is its value."""
        for index in range(int(low), int(high) + 1):
            buffer = bytearray(_QUERYMENU.pack(cid, index, b'', 0))
            try:
                self._ioctl(VIDIOC_QUERYMENU, buffer)
            except OSError:
                continue  # a value the menu skips
            if kind == INT_MENU:
                yield index, str(struct.unpack_from('=q', buffer, 8)[0])
            else:
                yield index, _text(_QUERYMENU.unpack(buffer)[2])

    def _ext_control(self, request, cid: int, value: int = 0) -> int:
        """Get or set one 64-bit control through the EXT_CTRLS ioctls; return its value."""
        item = _ExtControl(id=cid)
        item.u.value64 = value
        self._ioctl(request, _ExtControls(count=1, controls=ctypes.pointer(item)))
        return item.u.value64

    def get_control(self, cid: int) -> Optional[int]:
        """Return a control's current value, or None when the device does not say."""
        kind = self._kinds.get(cid)
        try:
            if kind == INT64:
                return self._ext_control(VIDIOC_G_EXT_CTRLS, cid)
            buffer = self._ioctl(VIDIOC_G_CTRL, bytearray(_CONTROL.pack(cid, 0)))
        except OSError:
            return None
        value = _CONTROL.unpack(buffer)[1]
        return value & 0xFFFFFFFF if kind == BITMASK else value

    def set_control(self, cid: int, value: int) -> Optional[str]:
        """Set a control (press a button); return None, or why the device refused, in words."""
        value = int(value)
        try:
            if self._kinds.get(cid) == INT64:
                self._ext_control(VIDIOC_S_EXT_CTRLS, cid, value)
            else:
                # A bitmask's top bit is the sign of the ioctl's 32-bit value.
                signed = value - (1 << 32) if value >= 1 << 31 else value
                self._ioctl(VIDIOC_S_CTRL, bytearray(_CONTROL.pack(cid, signed)))
        except OSError as error:
            if error.errno == errno.EACCES:
                return 'the device refuses it now (read-only or inactive)'
            if error.errno == errno.ERANGE:
                return "out of the device's range"
            return 'the device refused it: %s' % os.strerror(error.errno)
        return None
