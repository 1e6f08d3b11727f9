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

"""frame_memory: freed frames are reused, not given back and faulted in again every frame."""

import platform
import subprocess
import sys

from py_vision import frame_memory
import pytest
import ros_harness

VGA = 640 * 480 * 3
PAGE = 4096
# A process that takes frames as a subscription does: three blocks of a frame's size written
# and freed (the middleware's copy, rclpy's bytes, the message's array), frame after frame;
# it prints the minor page faults a frame costs once the first frames are done.
FRAMES = """
import ctypes, resource, sys
from py_vision import frame_memory
size = int(sys.argv[1])
if sys.argv[2] == 'keep':
    assert frame_memory.keep_buffers(size)
libc = ctypes.CDLL(None)
libc.malloc.restype = ctypes.c_void_p
libc.malloc.argtypes = [ctypes.c_size_t]
libc.free.argtypes = [ctypes.c_void_p]
libc.memset.argtypes = [ctypes.c_void_p, ctypes.c_int, ctypes.c_size_t]

def frame():
    blocks = [libc.malloc(size) for _ in range(3)]
    for block in blocks:
        libc.memset(block, 1, size)
    for block in blocks:
        libc.free(block)

for _ in range(3):
    frame()
before = resource.getrusage(resource.RUSAGE_SELF).ru_minflt
for _ in range(20):
    frame()
print((resource.getrusage(resource.RUSAGE_SELF).ru_minflt - before) / 20.0)
"""

glibc = pytest.mark.skipif(platform.libc_ver()[0] != 'glibc',
                           reason='the setting is mallopt, which only glibc has')


def faults_a_frame(size, how):
    done = subprocess.run([sys.executable, '-c', FRAMES, str(size), how], capture_output=True,
                          text=True, timeout=60, env=ros_harness.installed_env())
    assert done.returncode == 0, done.stderr
    return float(done.stdout)


@glibc
@pytest.mark.parametrize('size', [VGA, 1280 * 720 * 3, 1920 * 1080 * 3])
def test_kept_frames_are_not_faulted_in_again(size):
    # What glibc does alone: the freed frames go back to the system, every page faults again.
    assert faults_a_frame(size, 'default') > size / PAGE
    assert faults_a_frame(size, 'keep') < 0.05 * size / PAGE


@pytest.fixture
def kept(monkeypatch):
    """Record what FrameStream asks to keep, without changing this process' allocator."""
    asked = []

    def keep(size):
        asked.append(size)
        monkeypatch.setitem(frame_memory._state, 'kept', size)
        return True
    monkeypatch.setitem(frame_memory._state, 'kept', 0)
    monkeypatch.setattr(frame_memory, 'keep_buffers', keep)
    return asked


def test_a_stream_is_kept_once_two_frames_in_a_row_are_that_large(kept):
    stream = frame_memory.FrameStream()
    stream.frame(VGA)
    assert kept == []
    for _ in range(5):
        stream.frame(VGA)
    assert kept == [VGA]


def test_a_single_large_image_is_not_kept(kept):
    stream = frame_memory.FrameStream()
    for size in (VGA, VGA, 50 * VGA, VGA, VGA):
        stream.frame(size)
    assert kept == [VGA]
    assert frame_memory.kept_bytes() == VGA


def test_a_larger_stream_raises_what_is_kept_and_a_smaller_one_leaves_it(kept):
    stream = frame_memory.FrameStream()
    for size in (VGA, VGA, 4 * VGA, 4 * VGA, 4 * VGA, VGA, VGA):
        stream.frame(size)
    assert kept == [VGA, 4 * VGA]
    assert frame_memory.kept_bytes() == 4 * VGA


def test_keep_frame_buffers_counts_bgr_bytes(monkeypatch):
    asked = []
    monkeypatch.setattr(frame_memory, 'keep_buffers', lambda size: asked.append(size) or True)
    assert frame_memory.keep_frame_buffers(640, 480)
    assert asked == [VGA]
