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

"""VideoStore: what a browser reading GET /video gets, from wherever it is in the stream."""

from py_vision.viewer import video
from py_vision.viewer.video import frame, VideoStore


def units(store, number):
    return store.since(number, 0)


def test_a_new_reader_starts_at_the_newest_keyframe_and_then_gets_every_unit():
    store = VideoStore()
    assert units(store, 0) == (0, [])             # nothing yet
    store.submit(b'P0', False)                    # before any keyframe: nobody can use it
    assert units(store, 0) == (1, [])
    store.submit(b'I1', True, 'avc1.42c01e')
    store.submit(b'P2', False)
    assert units(store, 0) == (3, [(b'I1', True), (b'P2', False)])
    assert store.codec == 'avc1.42c01e'
    store.submit(b'P3', False)
    assert units(store, 3) == (4, [(b'P3', False)])
    assert units(store, 4) == (4, [])


def test_a_reader_left_behind_by_a_new_keyframe_resumes_there():
    store = VideoStore()
    for unit, start in ((b'I1', True), (b'P2', False), (b'P3', False), (b'I4', True),
                        (b'P5', False)):
        store.submit(unit, start)
    # The reader had unit 2; units 3 and 4 follow it, but only from 4 on are they kept.
    assert units(store, 2) == (5, [(b'I4', True), (b'P5', False)])
    assert units(store, 3) == (5, [(b'I4', True), (b'P5', False)])
    assert units(store, 4) == (5, [(b'P5', False)])


def test_a_group_too_long_to_keep_makes_readers_wait_for_the_next_keyframe(monkeypatch):
    monkeypatch.setattr(video, 'MAX_UNITS', 3)
    store = VideoStore()
    store.submit(b'I1', True)
    store.submit(b'P2', False)
    store.submit(b'P3', False)
    assert units(store, 1) == (3, [(b'P2', False), (b'P3', False)])
    store.submit(b'P4', False)                    # the fourth: the group is dropped
    assert units(store, 3) == (4, [])
    store.submit(b'P5', False)
    assert units(store, 4) == (5, [])
    store.submit(b'I6', True)
    assert units(store, 5) == (6, [(b'I6', True)])


def test_a_unit_is_framed_with_its_length_and_start_flag():
    assert frame(b'\x00\x00\x00\x01\x09\xf0', True) == b'\x00\x00\x00\x06\x01' + \
        b'\x00\x00\x00\x01\x09\xf0'
    assert frame(b'ab', False) == b'\x00\x00\x00\x02\x00ab'


def test_closing_wakes_a_waiting_reader():
    store = VideoStore()
    store.close()
    assert store.since(0, 5.0) is None
