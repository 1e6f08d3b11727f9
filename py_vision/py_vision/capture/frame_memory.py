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

Every frame the capture thread may allocate and free buffers of a frame's size (a decoded
JPEG; where the image cannot go out serialized, a converted image and the C message rclpy
fills). glibc serves blocks that large from mmap, or trims its thread arena's heap once they
are freed, so each new frame starts on memory the system has to fault in again, page by page:
about 0.4 ms of CPU for each 640x480 BGR image decoded (bench/bench_capture.py). With
the mmap threshold above a frame and the trim threshold above a few frames, freed frames are
reused. Process-wide and harmless elsewhere; nothing is done where the C library is not glibc.
"""

import ctypes
import platform

__all__ = ['keep_frame_buffers']

_M_TRIM_THRESHOLD, _M_MMAP_THRESHOLD = -1, -3
_MMAP_THRESHOLD_MAX = 32 * 1024 * 1024   # glibc's largest on 64-bit machines
_kept = [0]


def keep_frame_buffers(width: int, height: int) -> bool:
    """Keep freed buffers of BGR frames of this size (or smaller) for reuse; True if done."""
    frame = width * height * 3
    if frame <= _kept[0] or platform.libc_ver()[0] != 'glibc':
        return frame <= _kept[0]
    try:
        libc = ctypes.CDLL(None)
        done = libc.mallopt(_M_MMAP_THRESHOLD, min(2 * frame, _MMAP_THRESHOLD_MAX)) == 1
        done = libc.mallopt(_M_TRIM_THRESHOLD, 4 * frame) == 1 and done
    except (OSError, AttributeError):
        return False
    if done:
        _kept[0] = frame
    return done
