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
A subscription's next message, taken serialized into memory of its own (rcl, through ctypes).

rclpy takes a sensor_msgs/Image in three copies of its pixels: the middleware deserialises it
into a C message (into memory it first zeroes), rclpy's generated code makes `bytes` of the
data, then copies those into the message's array. Its own serialized take
(`raw=True`) makes three copies too (the middleware's buffer, rcl's, `bytes`). Here rcl's
`rcl_take_serialized_message` copies the message into a buffer this process allocated, which
becomes a writable numpy array that frees it when the last view of it goes: two copies in
all (the middleware's own buffer, then this one), and no Python objects but the array.
cdr_image reads the Image out of it.

The C functions are those of the librcl and librcutils rclpy has loaded (found in
/proc/self/maps), with the C layout of rcl_serialized_message_t, which Humble and Jazzy share.
Where they cannot be found, `SerializedTake.usable()` is False and the caller takes as rclpy
does.
"""

import ctypes
from typing import Optional

import numpy as np
from py_vision.rcl_c import Allocator, error_text, function, SerializedMessage

__all__ = ['SerializedTake', 'TakeError']

_TAKE_FAILED = 401   # RCL_RET_SUBSCRIPTION_TAKE_FAILED: nothing to take
_MARGIN = 4096       # room over the last message's size, so a slightly larger one fits


class TakeError(RuntimeError):
    """rcl could not take a message (a status other than "nothing to take")."""


class _C:
    """The C functions, bound once."""

    libc = take = allocator = None
    failed = None  # why they cannot be used

    @classmethod
    def bind(cls) -> bool:
        if cls.take is not None or cls.failed is not None:
            return cls.failed is None
        get_allocator = function('librcutils.so', 'rcutils_get_default_allocator', None,
                                 Allocator)
        take = function('librcl.so', 'rcl_take_serialized_message',
                        [ctypes.c_void_p, ctypes.POINTER(SerializedMessage), ctypes.c_void_p,
                         ctypes.c_void_p], ctypes.c_int)
        if get_allocator is None or take is None:
            cls.failed = "librcl.so's or librcutils.so's functions are not loaded"
            return False
        try:
            libc = ctypes.CDLL(None)
            libc.malloc.restype = ctypes.c_void_p
            libc.malloc.argtypes = [ctypes.c_size_t]
            libc.free.restype = None
            libc.free.argtypes = [ctypes.c_void_p]
        except (OSError, AttributeError) as error:
            cls.failed = str(error)
            return False
        cls.libc, cls.allocator, cls.take = libc, get_allocator(), take
        return True


class _Owned:
    """A block of malloc'd bytes, freed with the last numpy array that views it."""

    __slots__ = ('address', '__array_interface__')

    def __init__(self, address: int, length: int):
        self.address = address
        self.__array_interface__ = {'data': (address, False), 'shape': (length,),
                                    'typestr': '|u1', 'version': 3}

    def __del__(self):
        free = _C.libc.free if _C.libc is not None else None
        if free is not None and self.address:
            free(self.address)
            self.address = 0


class SerializedTake:
    """Takes a subscription's messages serialized, each into a numpy array of its own."""

    def __init__(self):
        self._capacity = 64 * 1024

    @staticmethod
    def usable() -> bool:
        """Return True where rcl's functions are found (else take as rclpy does)."""
        return _C.bind()

    def take(self, handle) -> Optional[np.ndarray]:
        """
        Return the next message of a subscription (its rclpy handle, held) as 1-D uint8 bytes.

        None when there is none; TakeError when rcl fails.
        """
        address = _C.libc.malloc(self._capacity)
        if not address:
            raise MemoryError('no memory for a message of %d bytes' % self._capacity)
        message = SerializedMessage(address, 0, self._capacity, _C.allocator)
        status = _C.take(handle.pointer, ctypes.byref(message), None, None)
        # rcl may have grown the buffer (realloc through the same allocator): it is this one.
        owned = _Owned(message.buffer, message.buffer_length)
        if status != 0:
            if status == _TAKE_FAILED:
                return None
            raise TakeError('rcl_take_serialized_message returned %d: %s' % (
                status, error_text()))
        self._capacity = message.buffer_length + _MARGIN
        return np.asarray(owned)
