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
Messages kept in the form the middleware sends (CDR), reused message after message.

rclpy publishes a message by copying it field by field into a C message (the pixels of an
Image into a new buffer of their size), which the middleware then serializes (copying the
pixels again). A publisher that keeps its messages serialized instead writes each one's bytes
once, where they stay, and hands the middleware the finished bytes:

- `SerializedImage`: a sensor_msgs/Image laid out once per layout (frame_id, size,
  encoding, step) in a buffer of its own, whose pixel bytes (`data()`) a conversion writes
  into, and whose stamp is written per message; made with a `capacity`, its pixel bytes
  stay at one place whatever the layout (`pixels()`), for a camera to capture into;
- `SerializedStamped`: any message whose first field is a std_msgs/Header (CameraInfo),
  serialized once by rclpy while it stays the same object with the same frame_id, only its
  stamp written per message.

The bytes are ROS 2's serialized form, as rclpy.serialization.serialize_message gives them:
a 4-byte encapsulation (CDR, little-endian) and the fields in order, each aligned to its size
counted from after the encapsulation, strings as a 32-bit length (with the NUL) then UTF-8 and
a NUL, sequences as a 32-bit count then the elements; padding is zeroes. Each message starts
where its pixel bytes land on a 64-byte boundary, so that conversions write whole cache lines.
"""

import struct
from typing import Optional, Tuple

import numpy as np

__all__ = ['SerializedImage', 'SerializedStamped', 'STAMP_OFFSET']

# CDR, little-endian, no options: what rmw_fastrtps writes on the machines ROS runs on.
ENCAPSULATION = b'\x00\x01\x00\x00'
# A std_msgs/Header first: builtin_interfaces/Time (int32 sec, uint32 nanosec) right after the
# encapsulation.
STAMP_OFFSET = len(ENCAPSULATION)
_STAMP = struct.Struct('<iI')
_UINT32 = struct.Struct('<I')
_DATA_ALIGNMENT = 64
# A message whose pixels stay at one place: the room its fields have before them, and the
# pixels' alignment (a page: what a driver's DMA would ask of user memory).
HEAD_ROOM = 4096
_PAGE = 4096


def _align(offset: int, size: int) -> int:
    """Return offset (counted from after the encapsulation) rounded up to a multiple of size."""
    return offset + (-(offset - STAMP_OFFSET)) % size


class _Writer:
    """Fields written one after another into a bytearray, aligned as CDR aligns them."""

    def __init__(self):
        self.out = bytearray(ENCAPSULATION)

    def _pad(self, size):
        self.out += bytes(_align(len(self.out), size) - len(self.out))

    def uint32(self, value):
        self._pad(4)
        self.out += _UINT32.pack(value)

    def uint8(self, value):
        self.out.append(value)

    def string(self, text):
        encoded = text.encode('utf-8')
        self.uint32(len(encoded) + 1)
        self.out += encoded + b'\0'


def _stamp_values(stamp) -> Tuple[int, int]:
    """Return (sec, nanosec) of a builtin_interfaces/Time, checked as rclpy checks them."""
    sec, nanosec = stamp.sec, stamp.nanosec
    if not -2 ** 31 <= sec < 2 ** 31 or not 0 <= nanosec < 2 ** 32:
        raise ValueError('stamp out of range: sec %r, nanosec %r' % (sec, nanosec))
    return sec, nanosec


class _Buffer:
    """One message's bytes in a buffer reused as long as it is large enough."""

    def __init__(self):
        self._memory = np.empty(0, np.uint8)
        self.message = self._memory    # the message's bytes: a view of _memory
        self.address = self.size = 0   # where they are, and how many

    def place(self, size: int, aligned_at: int) -> np.ndarray:
        """Make room for a message of size bytes whose byte aligned_at falls on a boundary."""
        if self._memory.size < size + _DATA_ALIGNMENT:
            self._memory = np.zeros(size + _DATA_ALIGNMENT, np.uint8)
        base = self._memory.ctypes.data
        start = -(base + aligned_at) % _DATA_ALIGNMENT
        self.message = self._memory[start:start + size]
        self.address, self.size = base + start, size
        return self.message


class _PixelsInPlace(_Buffer):
    """A message whose pixel bytes stay where they are: capacity of them, a page aligned."""

    def __init__(self, capacity: int):
        super().__init__()
        # Whole pages: no other data shares the pages a device writes the pixels into.
        pages = -(-capacity // _PAGE) * _PAGE
        self._memory = np.zeros(HEAD_ROOM + pages + _PAGE, np.uint8)
        base = self._memory.ctypes.data
        self._pixels_at = HEAD_ROOM + (-(base + HEAD_ROOM) % _PAGE)
        self.pixels = self._memory[self._pixels_at:self._pixels_at + capacity]
        self.pixels_address = base + self._pixels_at

    def place(self, size: int, aligned_at: int) -> np.ndarray:
        """Lay a message of size bytes out so that its byte aligned_at is pixels' first."""
        if aligned_at > HEAD_ROOM or size - aligned_at > self.pixels.size:
            raise ValueError('the message does not fit around its pixels (fields of %d bytes '
                             'of %d, pixels of %d of %d)' % (aligned_at, HEAD_ROOM,
                                                             size - aligned_at,
                                                             self.pixels.size))
        start = self._pixels_at - aligned_at
        self.message = self._memory[start:start + size]
        self.address, self.size = self._memory.ctypes.data + start, size
        return self.message


class SerializedImage:
    """
    A sensor_msgs/Image kept serialized: laid out per layout, its pixels written in place.

    Per message: `prepare(header, height, width, encoding, step, is_bigendian, size)` (a new
    layout only when one of them but the stamp changed, otherwise the stamp alone), then the
    pixels written into `data()` (`size` bytes: step x height unless said), then `message()`
    is published (`where()`: its address and size, for SerializedPublisher.publish_at).

    With a capacity (bytes), the pixel bytes never move: `pixels()` (that many, a page
    aligned) is where every layout puts them, its fields laid out before them; prepare()
    raises ValueError for a layout whose pixels or fields (HEAD_ROOM) do not fit.
    """

    def __init__(self, capacity: Optional[int] = None):
        self._buffer = _Buffer() if capacity is None else _PixelsInPlace(capacity)
        self._layout = None
        self._data: Optional[np.ndarray] = None
        self._data_offset = 0

    def prepare(self, header, height: int, width: int, encoding: str, step: int,
                is_bigendian: bool = False, size: Optional[int] = None) -> None:
        """Lay out a message with header's frame_id and these fields; write header's stamp."""
        layout = (header.frame_id, height, width, encoding, step, bool(is_bigendian),
                  step * height if size is None else size)
        if layout != self._layout:
            self._lay_out(*layout)
        _STAMP.pack_into(self._buffer.message, STAMP_OFFSET, *_stamp_values(header.stamp))

    def _lay_out(self, frame_id, height, width, encoding, step, is_bigendian, size):
        for name, value in (('height', height), ('width', width), ('step', step),
                            ('size', size)):
            if not 0 <= value < 2 ** 32:
                raise ValueError('%s out of range: %r' % (name, value))
        writer = _Writer()
        writer.out += bytes(_STAMP.size)
        writer.string(frame_id)
        writer.uint32(height)
        writer.uint32(width)
        writer.string(encoding)
        writer.uint8(1 if is_bigendian else 0)
        writer.uint32(step)
        writer.uint32(size)
        head = len(writer.out)
        self._layout = None   # until laid out whole
        message = self._buffer.place(head + size, head)
        message[:head] = np.frombuffer(writer.out, np.uint8)
        self._data = message[head:]
        self._data_offset = head
        self._layout = (frame_id, height, width, encoding, step, is_bigendian, size)

    def data(self) -> np.ndarray:
        """Return the message's pixel bytes (1-D uint8, `size` of them) to write into."""
        return self._data

    def pixels(self) -> np.ndarray:
        """Return where the pixel bytes of every layout are (made with a capacity only)."""
        return self._buffer.pixels

    @property
    def pixels_address(self) -> int:
        """Return the address of pixels() (made with a capacity only)."""
        return self._buffer.pixels_address

    def message(self) -> np.ndarray:
        """Return the serialized bytes (1-D uint8) of the whole message, as it is now."""
        return self._buffer.message

    def where(self) -> Tuple[int, int]:
        """Return the address and size of message() (valid until the next layout)."""
        return self._buffer.address, self._buffer.size


class SerializedStamped:
    """
    A message that starts with a std_msgs/Header, serialized once, its stamp written per use.

    `message(msg)` returns msg's serialized bytes with msg.header's stamp: serialized anew only
    when msg is another object than the last time or its frame_id changed. msg must not change
    otherwise between calls (CameraInfoManager replaces its messages, never changes them).
    `stamp(msg)` does the same and returns where the bytes are (address, size).
    """

    def __init__(self):
        self._buffer = _Buffer()
        self._source = None
        self._frame_id = None

    def message(self, msg) -> np.ndarray:
        """Return the bytes of msg serialized (1-D uint8), with its header's current stamp."""
        self.stamp(msg)
        return self._buffer.message

    def stamp(self, msg) -> Tuple[int, int]:
        """Serialize msg (or only write its stamp); return the bytes' address and size."""
        header = msg.header
        buffer = self._buffer
        if msg is not self._source or header.frame_id != self._frame_id:
            from rclpy.serialization import serialize_message
            serialized = serialize_message(msg)
            self._source = None
            message = buffer.place(len(serialized), 0)
            message[:] = np.frombuffer(serialized, np.uint8)
            self._source, self._frame_id = msg, header.frame_id
        _STAMP.pack_into(buffer.message, STAMP_OFFSET, *_stamp_values(header.stamp))
        return buffer.address, buffer.size
