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
rcl's C API where py_vision calls it directly: the libraries rclpy loaded, a message's layout.

A serialized message is rcl_serialized_message_t, whose C layout Humble and Jazzy share.

serialized_take (a subscription's messages taken into memory of our own) and
serialized_publisher (messages published from it) bind their functions from here.
"""

import ctypes
from typing import Optional

__all__ = ['Allocator', 'loaded_library', 'SerializedMessage']


class Allocator(ctypes.Structure):
    """rcutils_allocator_t: four functions and a state pointer."""

    _fields_ = [('allocate', ctypes.c_void_p), ('deallocate', ctypes.c_void_p),
                ('reallocate', ctypes.c_void_p), ('zero_allocate', ctypes.c_void_p),
                ('state', ctypes.c_void_p)]


class SerializedMessage(ctypes.Structure):
    """rcl_serialized_message_t (rcutils_uint8_array_t): the bytes, their length, capacity."""

    _fields_ = [('buffer', ctypes.c_void_p), ('buffer_length', ctypes.c_size_t),
                ('buffer_capacity', ctypes.c_size_t), ('allocator', Allocator)]


def loaded_library(name: str) -> Optional[ctypes.CDLL]:
    """Return the shared library of that file name (librcl.so) the process has loaded, or None."""
    try:
        with open('/proc/self/maps') as maps:
            for line in maps:
                fields = line.rstrip('\n').split(None, 5)
                if len(fields) == 6 and fields[5].rsplit('/', 1)[-1] == name:
                    return ctypes.CDLL(fields[5])
    except OSError:
        pass
    return None
