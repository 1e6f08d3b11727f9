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
The V4L2 ioctls the emulated-camera tests use, with fcntl.ioctl and struct (64-bit Linux).

A test-side client of the V4L2 API, independent of the emulator it checks: every structure is
laid out here from include/uapi/linux/videodev2.h. `Stream` streams from a device with mmap
buffers, as a capture program does.
"""

import ctypes
import errno
import fcntl
import mmap
import os
import select
import struct
import time


def _ioc(direction, number, size):
    return (direction << 30) | (size << 16) | (ord('V') << 8) | number


_R, _W, _RW = 2, 1, 3
VIDIOC_QUERYCAP = _ioc(_R, 0, 104)
VIDIOC_ENUM_FMT = _ioc(_RW, 2, 64)
VIDIOC_G_FMT = _ioc(_RW, 4, 208)
VIDIOC_S_FMT = _ioc(_RW, 5, 208)
VIDIOC_REQBUFS = _ioc(_RW, 8, 20)
VIDIOC_QUERYBUF = _ioc(_RW, 9, 88)
VIDIOC_QBUF = _ioc(_RW, 15, 88)
VIDIOC_DQBUF = _ioc(_RW, 17, 88)
VIDIOC_STREAMON = _ioc(_W, 18, 4)
VIDIOC_STREAMOFF = _ioc(_W, 19, 4)
VIDIOC_G_PARM = _ioc(_RW, 21, 204)
VIDIOC_S_PARM = _ioc(_RW, 22, 204)
VIDIOC_G_CTRL = _ioc(_RW, 27, 8)
VIDIOC_S_CTRL = _ioc(_RW, 28, 8)
VIDIOC_QUERYCTRL = _ioc(_RW, 36, 68)
VIDIOC_QUERYMENU = _ioc(_RW, 37, 44)
VIDIOC_G_EXT_CTRLS = _ioc(_RW, 71, 32)
VIDIOC_S_EXT_CTRLS = _ioc(_RW, 72, 32)
VIDIOC_ENUM_FRAMESIZES = _ioc(_RW, 74, 44)
VIDIOC_ENUM_FRAMEINTERVALS = _ioc(_RW, 75, 52)
VIDIOC_QUERY_EXT_CTRL = _ioc(_RW, 103, 232)

BUF_TYPE_VIDEO_CAPTURE = 1
MEMORY_MMAP = 1
CAP_VIDEO_CAPTURE = 0x1
CAP_STREAMING = 0x04000000
FMT_FLAG_COMPRESSED = 0x1
CTRL_FLAG_READ_ONLY = 0x4
CTRL_FLAG_INACTIVE = 0x10
CTRL_FLAG_WRITE_ONLY = 0x40
CTRL_FLAG_HAS_PAYLOAD = 0x100
CTRL_FLAG_EXECUTE_ON_WRITE = 0x200
CTRL_FLAG_DYNAMIC_ARRAY = 0x800
CTRL_FLAG_NEXT_CTRL = 0x80000000
CTRL_FLAG_NEXT_COMPOUND = 0x40000000
CTRL_TYPE_INTEGER, CTRL_TYPE_BOOLEAN, CTRL_TYPE_MENU, CTRL_TYPE_CTRL_CLASS = 1, 2, 3, 6
CTRL_TYPE_BUTTON, CTRL_TYPE_INTEGER64, CTRL_TYPE_STRING = 4, 5, 7
CTRL_TYPE_BITMASK, CTRL_TYPE_INTEGER_MENU, CTRL_TYPE_U32, CTRL_TYPE_AREA = 8, 9, 0x102, 0x106
BUF_FLAG_TIMESTAMP_MONOTONIC = 0x2000


def fourcc(code):
    """Return the V4L2 pixel format number of a four-character code."""
    return struct.unpack('<I', code.encode('latin-1'))[0]


def fourcc_text(number):
    r"""
    Return the four-character code of a V4L2 pixel format number.

    Decoded as latin-1: a big-endian variant has bit 31 set ('Y16 ' | 1 << 31 is 'Y16\xa0').
    """
    return struct.pack('<I', number).decode('latin-1')


def _text(raw):
    return raw.split(b'\0', 1)[0].decode()


def _ioctl(fd, request, buf):
    buf = bytearray(buf)
    fcntl.ioctl(fd, request, buf)
    return buf


def querycap(fd):
    """Return (driver, card, bus_info, capabilities, device_caps)."""
    buf = _ioctl(fd, VIDIOC_QUERYCAP, bytes(104))
    driver, card, bus, _, caps, device_caps = struct.unpack_from('16s32s32sIII', buf)
    return _text(driver), _text(card), _text(bus), caps, device_caps


def enum_formats(fd):
    """Return [(fourcc text, flags, description)] as VIDIOC_ENUM_FMT lists them."""
    formats = []
    for index in range(64):
        try:
            buf = _ioctl(fd, VIDIOC_ENUM_FMT, struct.pack('II', index, BUF_TYPE_VIDEO_CAPTURE)
                         + bytes(56))
        except OSError as error:
            if error.errno != errno.EINVAL:
                raise
            return formats
        _, _, flags, description, pixelformat = struct.unpack_from('III32sI', buf)
        formats.append((fourcc_text(pixelformat), flags, _text(description)))
    return formats


def enum_sizes(fd, code):
    """Return the discrete [(width, height)] a format offers."""
    sizes = []
    for index in range(256):
        try:
            buf = _ioctl(fd, VIDIOC_ENUM_FRAMESIZES, struct.pack('II', index, fourcc(code))
                         + bytes(36))
        except OSError as error:
            if error.errno != errno.EINVAL:
                raise
            return sizes
        _, _, kind, width, height = struct.unpack_from('IIIII', buf)
        assert kind == 1, 'not a discrete size'
        sizes.append((width, height))
    return sizes


def enum_intervals(fd, code, width, height):
    """Return the discrete frame intervals [(numerator, denominator)] of a format and size."""
    intervals = []
    for index in range(64):
        try:
            buf = _ioctl(fd, VIDIOC_ENUM_FRAMEINTERVALS,
                         struct.pack('IIII', index, fourcc(code), width, height) + bytes(36))
        except OSError as error:
            if error.errno != errno.EINVAL:
                raise
            return intervals
        kind, numerator, denominator = struct.unpack_from('III', buf, 16)
        assert kind == 1, 'not a discrete interval'
        intervals.append((numerator, denominator))
    return intervals


def get_format(fd):
    """Return (fourcc text, width, height, bytesperline, sizeimage)."""
    buf = _ioctl(fd, VIDIOC_G_FMT, struct.pack('I', BUF_TYPE_VIDEO_CAPTURE) + bytes(204))
    width, height, pixelformat, _, bytesperline, sizeimage = struct.unpack_from('6I', buf, 8)
    return fourcc_text(pixelformat), width, height, bytesperline, sizeimage


def set_format(fd, code, width, height):
    """VIDIOC_S_FMT; return what the driver chose, as get_format does."""
    buf = bytearray(208)
    struct.pack_into('I', buf, 0, BUF_TYPE_VIDEO_CAPTURE)
    struct.pack_into('IIII', buf, 8, width, height, fourcc(code), 0)
    buf = _ioctl(fd, VIDIOC_S_FMT, buf)
    width, height, pixelformat, _, bytesperline, sizeimage = struct.unpack_from('6I', buf, 8)
    return fourcc_text(pixelformat), width, height, bytesperline, sizeimage


def get_interval(fd):
    """Return the frame interval (numerator, denominator) of VIDIOC_G_PARM."""
    buf = _ioctl(fd, VIDIOC_G_PARM, struct.pack('I', BUF_TYPE_VIDEO_CAPTURE) + bytes(200))
    return struct.unpack_from('II', buf, 12)


def set_interval(fd, numerator, denominator):
    """VIDIOC_S_PARM; return the interval the driver chose."""
    buf = bytearray(204)
    struct.pack_into('I', buf, 0, BUF_TYPE_VIDEO_CAPTURE)
    struct.pack_into('II', buf, 12, numerator, denominator)
    buf = _ioctl(fd, VIDIOC_S_PARM, buf)
    return struct.unpack_from('II', buf, 12)


def query_control(fd, control_id):
    """Return VIDIOC_QUERYCTRL's answer as a dict (id, type, name, min, max, step, ...)."""
    buf = _ioctl(fd, VIDIOC_QUERYCTRL, struct.pack('I', control_id) + bytes(64))
    cid, kind, name, minimum, maximum, step, default, flags = struct.unpack_from(
        'II32siiiiI', buf)
    return {'id': cid, 'type': kind, 'name': _text(name), 'min': minimum, 'max': maximum,
            'step': step, 'default': default, 'flags': flags}


def query_ext_control(fd, control_id):
    """Return VIDIOC_QUERY_EXT_CTRL's answer as a dict (64-bit range fields)."""
    buf = _ioctl(fd, VIDIOC_QUERY_EXT_CTRL, struct.pack('I', control_id) + bytes(228))
    cid, kind, name = struct.unpack_from('II32s', buf)
    minimum, maximum, step, default, flags, elem_size, elems, dims = struct.unpack_from(
        'qqQqIIII', buf, 40)
    return {'id': cid, 'type': kind, 'name': _text(name), 'min': minimum, 'max': maximum,
            'step': step, 'default': default, 'flags': flags, 'elem_size': elem_size,
            'elems': elems, 'dims': dims, 'sizes': list(struct.unpack_from('4I', buf, 80))}


def list_ext_controls(fd, which=CTRL_FLAG_NEXT_CTRL):
    """Return every control VIDIOC_QUERY_EXT_CTRL walks with these NEXT flags, classes too."""
    controls, last = [], 0
    while True:
        try:
            control = query_ext_control(fd, last | which)
        except OSError as error:
            if error.errno != errno.EINVAL:
                raise
            return controls
        controls.append(control)
        last = control['id']


def list_controls(fd):
    """Return every control by VIDIOC_QUERYCTRL with V4L2_CTRL_FLAG_NEXT_CTRL, classes too."""
    controls, last = [], 0
    while True:
        try:
            control = query_control(fd, last | CTRL_FLAG_NEXT_CTRL)
        except OSError as error:
            if error.errno != errno.EINVAL:
                raise
            return controls
        controls.append(control)
        last = control['id']


def query_menu(fd, control_id, index):
    """Return the name of a menu entry (OSError EINVAL for an index the menu lacks)."""
    buf = _ioctl(fd, VIDIOC_QUERYMENU, struct.pack('II', control_id, index) + bytes(36))
    return _text(buf[8:40])


def query_int_menu(fd, control_id, index):
    """Return the value of an integer menu's entry (the union's 64-bit member)."""
    buf = _ioctl(fd, VIDIOC_QUERYMENU, struct.pack('II', control_id, index) + bytes(36))
    return struct.unpack_from('q', buf, 8)[0]


def get_control(fd, control_id):
    """VIDIOC_G_CTRL."""
    return struct.unpack_from('Ii', _ioctl(fd, VIDIOC_G_CTRL, struct.pack('Ii', control_id, 0)))[1]


def set_control(fd, control_id, value):
    """VIDIOC_S_CTRL; return the value the driver kept (clamped to the range and step)."""
    buf = _ioctl(fd, VIDIOC_S_CTRL, struct.pack('Ii', control_id, value))
    return struct.unpack_from('Ii', buf)[1]


def _ext_controls(fd, request, values, wide=False):
    """Run an EXT_CTRLS ioctl on [(id, value)]; return the values after it (value64: wide)."""
    layout = '=IIIq' if wide else '=IIIi'
    items = ctypes.create_string_buffer(20 * len(values))
    for i, (cid, value) in enumerate(values):
        struct.pack_into(layout, items, 20 * i, cid, 0, 0, value)
    head = struct.pack('IIIiIIQ', 0, len(values), 0, 0, 0, 0, ctypes.addressof(items))
    _ioctl(fd, request, head)
    return [struct.unpack_from(layout, items.raw, 20 * i)[3] for i in range(len(values))]


def get_ext_controls(fd, ids, wide=False):
    """VIDIOC_G_EXT_CTRLS for these control ids; return their values (value64: wide)."""
    return _ext_controls(fd, VIDIOC_G_EXT_CTRLS, [(cid, 0) for cid in ids], wide)


def set_ext_controls(fd, values, wide=False):
    """VIDIOC_S_EXT_CTRLS with [(id, value)]; return the values the driver kept."""
    return _ext_controls(fd, VIDIOC_S_EXT_CTRLS, values, wide)


class Stream:
    """mmap streaming from an open device: S_FMT, REQBUFS, QUERYBUF+mmap, QBUF, STREAMON."""

    def __init__(self, fd, code=None, width=None, height=None, buffers=4, interval=None):
        self.fd = fd
        if code is not None:
            self.format = set_format(fd, code, width, height)
        else:
            self.format = get_format(fd)
        if interval is not None:
            set_interval(fd, *interval)
        request = struct.pack('IIII', buffers, BUF_TYPE_VIDEO_CAPTURE, MEMORY_MMAP, 0)
        buf = _ioctl(fd, VIDIOC_REQBUFS, request + bytes(4))
        count = struct.unpack_from('I', buf)[0]
        self.maps = []
        for index in range(count):
            info = self._buffer(VIDIOC_QUERYBUF, index)
            self.maps.append(mmap.mmap(fd, info['length'], mmap.MAP_SHARED, mmap.PROT_READ,
                                       offset=info['offset']))
            self._buffer(VIDIOC_QBUF, index)
        fcntl.ioctl(fd, VIDIOC_STREAMON, struct.pack('I', BUF_TYPE_VIDEO_CAPTURE))

    def _buffer(self, request, index=0):
        buf = bytearray(88)
        struct.pack_into('II', buf, 0, index, BUF_TYPE_VIDEO_CAPTURE)
        struct.pack_into('I', buf, 60, MEMORY_MMAP)
        buf = _ioctl(self.fd, request, buf)
        index, _, used, flags, _ = struct.unpack_from('IIIII', buf)
        sec, usec = struct.unpack_from('qq', buf, 24)
        sequence, _, offset, length = struct.unpack_from('IIIxxxxI', buf, 56)
        return {'index': index, 'bytesused': used, 'flags': flags, 'timestamp': sec + usec / 1e6,
                'sequence': sequence, 'offset': offset, 'length': length}

    def wait(self, timeout):
        """Poll the device; return its revents (0 on a timeout)."""
        poller = select.poll()
        poller.register(self.fd, select.POLLIN | select.POLLERR)
        events = poller.poll(int(timeout * 1000))
        return events[0][1] if events else 0

    def dequeue(self, timeout=5.0):
        """Wait for a filled buffer and take it (VIDIOC_DQBUF): its info; queue() gives it back."""
        deadline = time.monotonic() + timeout
        while True:
            try:
                return self._buffer(VIDIOC_DQBUF)
            except BlockingIOError:
                left = deadline - time.monotonic()
                if left <= 0:
                    raise TimeoutError('no frame within %.1f s' % timeout)
                self.wait(left)

    def queue(self, index):
        """Give a buffer back to the driver (VIDIOC_QBUF)."""
        self._buffer(VIDIOC_QBUF, index)

    def read(self, timeout=5.0):
        """Wait for a buffer, dequeue it, copy its bytes and queue it again: (info, bytes)."""
        info = self.dequeue(timeout)
        data = bytes(self.maps[info['index']][:info['bytesused']])
        self.queue(info['index'])
        return info, data

    def close(self):
        """STREAMOFF and unmap the buffers (the descriptor stays open)."""
        try:
            fcntl.ioctl(self.fd, VIDIOC_STREAMOFF, struct.pack('I', BUF_TYPE_VIDEO_CAPTURE))
        except OSError:
            pass
        for m in self.maps:
            m.close()
        self.maps = []


def open_device(path, nonblocking=True):
    """os.open a device read-write, non-blocking as capture programs do."""
    return os.open(path, os.O_RDWR | (os.O_NONBLOCK if nonblocking else 0))
