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
serialized_publisher (messages published from it) bind their functions here (`function`), and
read the error rcl left when a call failed (`error_text`), as rclpy does after its own calls.
"""

import ctypes
from typing import Any, Dict, Optional, Sequence, Tuple

__all__ = ['Allocator', 'error_text', 'function', 'loaded_library', 'SerializedMessage']

# rcutils' error_handling.h: RCUTILS_ERROR_MESSAGE_MAX_LENGTH (Humble and Jazzy).
_ERROR_LENGTH = 1024


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


_bound: Dict[Tuple[str, str], Any] = {}


def function(library: str, name: str, argtypes: Optional[Sequence[Any]], restype: Any):
    """
    Return the C function `name` of the loaded library (librcl.so), typed, or None.

    None where the process has not loaded the library or it has no such function (another
    middleware layer, an older rcl): the caller then does as rclpy does. Bound once.
    """
    key = (library, name)
    if key not in _bound:
        found = None
        try:
            loaded = loaded_library(library)
            found = getattr(loaded, name) if loaded is not None else None
        except (OSError, AttributeError):
            found = None
        if found is not None:
            if argtypes is not None:
                found.argtypes = list(argtypes)
            found.restype = restype
        _bound[key] = found
    return _bound[key]


class _ErrorString(ctypes.Structure):
    """rcutils_error_string_t: the message, NUL-terminated."""

    _fields_ = [('str', ctypes.c_char * _ERROR_LENGTH)]


def error_text() -> str:
    """Return the error rcl set on this thread by a call that failed, and clear it."""
    is_set = function('librcutils.so', 'rcutils_error_is_set', [], ctypes.c_bool)
    get = function('librcutils.so', 'rcutils_get_error_string', [], _ErrorString)
    reset = function('librcutils.so', 'rcutils_reset_error', [], None)
    if is_set is None or get is None or reset is None or not is_set():
        return 'no error text'
    text = get().str.decode('utf-8', 'replace').strip()
    reset()
    return text or 'no error text'
