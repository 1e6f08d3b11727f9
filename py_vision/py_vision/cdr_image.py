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
A serialized sensor_msgs/Image (CDR, as the middleware carries it) read into an Image message.

The pixels are not copied: the message's data is a view of the serialized buffer (writable
when the buffer is), so a frame taken serialized (serialized_take) is copied once on its way
from the middleware to a numpy image. The rest (header, size, encoding) is read as
rmw_fastrtps writes it on Humble and Jazzy alike: plain CDR (XCDR1), little- or big-endian,
after a 4-byte encapsulation header, each field aligned to its size from there.

A buffer that is not such a message (truncated, a length that runs past its end, a string
without its terminating NUL, another encapsulation) raises CdrError, which says what is
wrong; it never gives a wrong image.
"""

import struct

import numpy as np
from sensor_msgs.msg import Image

__all__ = ['CdrError', 'image_message']

_HEADER = 4  # encapsulation: 2 bytes of kind, 2 of options
_KINDS = {b'\x00\x01': '<', b'\x00\x00': '>'}  # CDR_LE, CDR_BE
_U32 = {order: struct.Struct(order + 'I') for order in '<>'}
_STAMP = {order: struct.Struct(order + 'iI') for order in '<>'}
_SIZE = {order: struct.Struct(order + 'II') for order in '<>'}


class CdrError(ValueError):
    """A buffer is not a serialized sensor_msgs/Image; the message says why."""


class _Reader:
    """Reads CDR fields one after the other, each checked against the buffer's end."""

    def __init__(self, view, order):
        self.view = view
        self.order = order
        self.pos = _HEADER

    def _align(self, size):
        self.pos += -(self.pos - _HEADER) % size

    def _need(self, size, what):
        if self.pos + size > len(self.view):
            raise CdrError('truncated: %s needs %d bytes at offset %d, the message has %d' % (
                what, size, self.pos, len(self.view)))

    def fixed(self, layout, what):
        self._align(4)
        self._need(layout.size, what)
        values = layout.unpack_from(self.view, self.pos)
        self.pos += layout.size
        return values

    def string(self, what):
        (length,) = self.fixed(_U32[self.order], what)
        self._need(length, what)
        raw = bytes(self.view[self.pos:self.pos + length])
        self.pos += length
        if not length:
            return ''
        if raw[-1] != 0:
            raise CdrError('%s of %d bytes does not end with NUL: not a CDR string' % (
                what, length))
        return raw[:-1].decode('utf-8', 'replace')

    def byte(self, what):
        self._need(1, what)
        value = self.view[self.pos]
        self.pos += 1
        return value


def image_message(buffer) -> Image:
    """
    Return the sensor_msgs/Image serialized in buffer (a 1-D uint8 array, bytes, a memoryview).

    Its data is a view of buffer's pixels, which it keeps alive; writable where buffer is.
    Raises CdrError when buffer is not a serialized Image.
    """
    array = np.frombuffer(buffer, np.uint8) if not isinstance(buffer, np.ndarray) else buffer
    if array.ndim != 1 or array.dtype != np.uint8:
        raise CdrError('a serialized message is a 1-D array of bytes, not %s %s' % (
            array.dtype, array.shape))
    view = memoryview(array)
    if len(view) < _HEADER:
        raise CdrError('truncated: %d bytes, fewer than the encapsulation header' % len(view))
    order = _KINDS.get(bytes(view[:2]))
    if order is None:
        raise CdrError('encapsulation %s is not plain CDR (00 00 or 00 01)' % (
            bytes(view[:2]).hex(' ')))
    reader = _Reader(view, order)
    sec, nanosec = reader.fixed(_STAMP[order], 'header.stamp')
    frame_id = reader.string('header.frame_id')
    height, width = reader.fixed(_SIZE[order], 'height and width')
    encoding = reader.string('encoding')
    is_bigendian = reader.byte('is_bigendian')
    step, length = reader.fixed(_SIZE[order], 'step and the data length')
    reader._need(length, 'data')
    msg = Image(height=height, width=width, encoding=encoding, is_bigendian=is_bigendian,
                step=step)
    msg.header.stamp.sec = sec
    msg.header.stamp.nanosec = nanosec
    msg.header.frame_id = frame_id
    # As cv_bridge.share_message_data sets it: the generated code reads any buffer there.
    msg._data = array[reader.pos:reader.pos + length]
    return msg
