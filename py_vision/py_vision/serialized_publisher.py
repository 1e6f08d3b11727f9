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
Publish a message already serialized, from memory of our own: the middleware's copy only.

rclpy's Publisher.publish() takes serialized bytes too (rclpy 3.3 on Humble and 7 on Jazzy),
but only as a `bytes` object, which it copies again into a C++ string: a frame's bytes made
twice more per message. `SerializedPublisher` hands rcl the bytes where they are instead:
rcl_publish_serialized_message() (rcl's C API, the same on Humble and Jazzy) called through
ctypes on the rcl publisher of an rclpy Publisher (its handle's `pointer`), from the librcl
rclpy itself loaded, with the GIL released while the middleware sends. The publisher's handle
is held meanwhile, as rclpy holds it in publish(), so that it cannot be destroyed under the
call. Where this is not possible (no librcl in the process, an rclpy without `pointer`)
`available` is False and the caller publishes messages as rclpy does.
"""

import ctypes

import numpy as np
from py_vision.rcl_c import error_text, function, SerializedMessage
from py_vision.serialized import SerializedStamped

__all__ = ['SerializedPublisher', 'StampedPublisher']

_RCL_RET_OK = 0


def _rcl_publish():
    """Return rcl_publish_serialized_message from the process' librcl, or None."""
    return function('librcl.so', 'rcl_publish_serialized_message',
                    [ctypes.c_void_p, ctypes.POINTER(SerializedMessage), ctypes.c_void_p],
                    ctypes.c_int)


class SerializedPublisher:
    """
    Publishes serialized messages (1-D uint8 arrays) through an rclpy Publisher's rcl one.

    Made after rclpy is imported and the publisher created (librcl is loaded by then).
    """

    def __init__(self, publisher):
        self.publisher = publisher
        self._publish = _rcl_publish()
        self._message = SerializedMessage()
        self._pointer = ctypes.byref(self._message)
        self._where = (0, 0)
        self._handle = getattr(publisher, 'handle', None)
        rcl_publisher = getattr(self._handle, 'pointer', None)
        self.available = self._publish is not None and isinstance(rcl_publisher, int)
        # The rcl publisher stays where it is until it is destroyed, which its handle, held
        # during each call, says first (rclpy's InvalidHandle).
        self._rcl_publisher = ctypes.c_void_p(rcl_publisher) if self.available else None

    def publish(self, serialized: np.ndarray) -> None:
        """
        Publish a message's serialized bytes (contiguous uint8), read while this runs only.

        RuntimeError when rcl refuses (the bytes not a message); the publisher's handle raises
        its own error once it is destroyed.
        """
        if not serialized.flags.c_contiguous or serialized.dtype != np.uint8:
            raise ValueError('a serialized message is contiguous uint8 bytes')
        self.publish_at(serialized.ctypes.data, serialized.size)

    def publish_at(self, address: int, size: int) -> None:
        """Publish the serialized message of size bytes at address (as publish())."""
        if (address, size) != self._where:
            message = self._message
            message.buffer = address
            message.buffer_length = message.buffer_capacity = size
            self._where = (address, size)
        with self._handle:
            status = self._publish(self._rcl_publisher, self._pointer, None)
        if status != _RCL_RET_OK:
            raise RuntimeError('rcl_publish_serialized_message failed (%d) on %s: %s' % (
                status, self.publisher.topic_name, error_text()))


class StampedPublisher:
    """
    Publishes messages that start with a std_msgs/Header through an rclpy Publisher.

    Serialized once per message object and frame_id (SerializedStamped), the stamp written per
    message; through rclpy where SerializedPublisher is not available. From one thread.
    """

    def __init__(self, publisher):
        self.publisher = publisher
        self._out = SerializedPublisher(publisher)
        self._serialized = SerializedStamped()

    def publish(self, msg) -> None:
        """Publish msg (which must not change but for its header's stamp between calls)."""
        if self._out.available:
            self._out.publish_at(*self._serialized.stamp(msg))
        else:
            self.publisher.publish(msg)
