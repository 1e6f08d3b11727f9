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
Frame-sized buffers kept by the C allocator instead of given back to the system every frame.

Every frame, a node allocates and frees buffers of a frame's size: the capture thread a decoded
image and a message's data; a subscriber, for each message it takes, the middleware's copy,
the bytes rclpy converts it through and the message's own array. glibc serves blocks that large
from mmap, or trims its heap once they are freed, so each new frame starts on memory the system
has to fault in again, page by page: about 0.4 ms of CPU for each 640x480 BGR image decoded
(bench/bench_capture.py), and half of what a subscriber spends on a 640x480 frame
(bench/bench_receive.py). With the mmap threshold above a frame and the trim threshold above a
few frames, freed frames are reused instead.

The setting is the process' (glibc's mallopt), so it is made in one place: `keep_buffers`,
which only ever raises it, called where frames come in (the capture loop when a camera opens,
`FrameStream` for every frame a subscription takes). What it costs is the memory of the few
frames the heap then keeps. Nothing is done where the C library is not glibc.
"""

import ctypes
import platform

__all__ = ['FrameStream', 'kept_bytes', 'keep_buffers', 'keep_frame_buffers']

_M_TRIM_THRESHOLD, _M_MMAP_THRESHOLD = -1, -3
_MMAP_THRESHOLD_MAX = 32 * 1024 * 1024   # glibc's largest on 64-bit machines
# Blocks of up to this many frames are served from the heap; this many frames of free memory
# at its top are kept. A message taken by a subscription is, for a moment, three blocks of
# its size (the middleware's, rclpy's bytes and the message's array), all freed at the top.
MMAP_FRAMES, TRIM_FRAMES = 2, 4
# glibc's own thresholds to begin with (which it raises itself as blocks are freed): frames
# too small to need more are left to it.
_DEFAULT_THRESHOLD = 128 * 1024
_state = {'kept': 0, 'libc': None}


def kept_bytes() -> int:
    """Return the largest frame, in bytes, whose freed buffers the process keeps (0: none)."""
    return _state['kept']


def _libc():
    if _state['libc'] is None:
        _state['libc'] = (ctypes.CDLL(None) if platform.libc_ver()[0] == 'glibc' else False)
    return _state['libc']


def keep_buffers(frame: int) -> bool:
    """Keep freed buffers of `frame` bytes (or fewer) for reuse; True if they are kept."""
    if frame <= _state['kept'] or MMAP_FRAMES * frame <= _DEFAULT_THRESHOLD:
        return True  # kept already, or small enough for glibc's own thresholds
    try:
        libc = _libc()
        if not libc:
            return False
        done = libc.mallopt(_M_MMAP_THRESHOLD,
                            min(MMAP_FRAMES * frame, _MMAP_THRESHOLD_MAX)) == 1
        done = libc.mallopt(_M_TRIM_THRESHOLD, TRIM_FRAMES * frame) == 1 and done
    except (OSError, AttributeError):
        return False
    if done:
        _state['kept'] = frame
    return done


def keep_frame_buffers(width: int, height: int) -> bool:
    """Keep freed buffers of BGR frames of this size (or smaller) for reuse; True if done."""
    return keep_buffers(width * height * 3)


class FrameStream:
    """
    The frames one subscription takes: their buffers are kept once two in a row are that large.

    A single large message (an image sent once) leaves the process' setting as it was, so the
    memory it took is given back as before; a stream of them is kept.
    """

    def __init__(self):
        self._previous = 0

    def frame(self, size: int) -> None:
        """Count one frame of `size` bytes (O(1) unless the kept size grows)."""
        smaller = size if size < self._previous else self._previous
        self._previous = size
        if smaller > _state['kept']:
            keep_buffers(smaller)
