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

"""VideoDecoder: the clip's access units become its pictures, in order, each with its tag."""

import threading

from py_vision.capture.synthetic_picture import read_frame_index
from py_vision.video_decoder import backend, unavailable_reason, VideoDecoder
import pytest
from ros_harness import wait_until
from video_clip import access_units, FRAMES, HEIGHT, KEYINT, WIDTH

TIMEOUT = 20.0   # generous: only reached when something is broken

pytestmark = pytest.mark.skipif(
    backend() is None, reason='this OpenCV cannot decode video: %s' % unavailable_reason())


class Pictures:
    """What a decoder gave: (index read from the picture, tag), in order."""

    def __init__(self):
        self.got = []
        self.started = threading.Event()
        self.hold = threading.Event()
        self.hold.set()

    def __call__(self, picture, tag):
        self.started.set()
        assert self.hold.wait(TIMEOUT)
        assert picture.shape == (HEIGHT, WIDTH, 3)
        self.got.append((read_frame_index(picture), tag))


@pytest.fixture
def decoders():
    """Close every decoder a test makes, also when the test fails."""
    made = []

    def make(*args, **kwargs):
        decoder = VideoDecoder(*args, **kwargs)
        made.append(decoder)
        return decoder
    yield make
    for decoder in made:
        decoder.close()


def test_every_frame_comes_out_in_order_with_its_own_tag(decoders):
    pictures = Pictures()
    decoder = decoders('h264', pictures, max_queue=FRAMES + 1)   # the whole clip at once
    units = access_units()
    for index, unit in enumerate(units):
        decoder.decode(unit, tag=index)
    # OpenCV 4.6's FFmpeg holds the newest picture back until the next unit comes.
    decoder.decode(units[0], tag='again')
    wait_until(lambda: len(pictures.got) >= FRAMES, TIMEOUT, what='all %d frames' % FRAMES)
    assert pictures.got[:FRAMES] == [(index, index) for index in range(FRAMES)]
    assert decoder.failed is None


def test_a_late_joiner_starts_at_the_next_keyframe(decoders):
    pictures = Pictures()
    decoder = decoders('h264', pictures, max_queue=FRAMES)
    for index, unit in enumerate(access_units()[KEYINT // 2:], start=KEYINT // 2):
        decoder.decode(unit, tag=index)
    decoder.decode(access_units()[0], tag='again')
    expected = list(range(KEYINT, FRAMES))
    wait_until(lambda: len(pictures.got) >= len(expected), TIMEOUT,
               what='the frames from the first keyframe on')
    assert pictures.got[:len(expected)] == [(index, index) for index in expected]
    assert decoder.dropped == KEYINT - KEYINT // 2


def test_a_decoder_that_falls_behind_skips_to_a_keyframe_and_never_shows_a_broken_frame(
        decoders):
    pictures = Pictures()
    pictures.hold.clear()            # the first picture's callback waits: the decoder is behind
    decoder = decoders('h264', pictures, max_queue=4)
    units = access_units()

    def feed(first, last, keeping_up=False):
        for index in range(first, last):
            decoder.decode(units[index], tag=index)
            # Units reach the pipe one by one, as a camera's do; keeping_up: a camera slow
            # enough for the decoder (OpenCV 4.6's holds one picture back).
            wait_until(lambda: not decoder._queue and (
                not keeping_up or len(decoder._tags) <= 1), TIMEOUT,
                what='unit %d written' % index)
    feed(0, 2)                       # (OpenCV 4.6 gives picture 0 out when unit 1 comes)
    wait_until(lambda: pictures.started.is_set(), TIMEOUT, what='the first picture')
    feed(2, KEYINT + 2)              # 4 wait in the pipe; the rest, to the next keyframe too
    assert decoder.dropped == KEYINT + 2 - 1 - 4
    pictures.hold.set()
    wait_until(lambda: len(pictures.got) >= 4, TIMEOUT, what='the pictures that waited')
    feed(KEYINT + 2, FRAMES, keeping_up=True)
    decoder.decode(units[0], tag='again')   # OpenCV 4.6 holds the newest picture back
    wait_until(lambda: any(tag == FRAMES - 1 for _, tag in pictures.got), TIMEOUT,
               what='the last frame')
    tags = [tag for _, tag in pictures.got if tag != 'again']
    assert tags == [0, 1, 2, 3, 4] + list(range(2 * KEYINT, FRAMES))
    assert all(index == tag for index, tag in pictures.got if tag != 'again')


def test_without_a_decoder_it_says_why_and_takes_nothing():
    decoder = VideoDecoder('h264', lambda picture, tag: None,
                           build_information='  Video I/O:\n    FFMPEG: NO\n    GStreamer: NO\n')
    assert decoder.kind is None
    decoder.decode(access_units()[0])
    assert 'neither FFmpeg nor GStreamer' in decoder.failed
    decoder.close()


def test_the_gstreamer_pipeline_is_chosen_where_opencv_has_no_ffmpeg():
    assert backend('    FFMPEG:                      NO\n'
                   '    GStreamer:                   YES (1.22.0)\n') == 'gstreamer'
    assert backend('    FFMPEG:                      YES\n') == 'ffmpeg'


def test_closing_a_decoder_that_never_got_a_frame_returns_at_once(decoders):
    decoder = VideoDecoder('h264', lambda picture, tag: None)
    decoder.close(timeout=TIMEOUT)
    assert not any(thread.is_alive() for thread in decoder._threads)


def test_no_picture_is_handed_out_after_close_returns(decoders):
    # The reader thread busy with a picture while close() gives up waiting for it: the
    # pictures it reads afterwards (already in the pipe) go nowhere, as close() promises.
    pictures, closed, late = Pictures(), threading.Event(), []

    def on_picture(picture, tag):
        if closed.is_set():
            late.append(tag)
        pictures(picture, tag)
    decoder = decoders('h264', on_picture, max_queue=FRAMES + 1)
    units = access_units()
    pictures.hold.clear()            # the first picture waits in on_picture
    for index, unit in enumerate(units):
        decoder.decode(unit, tag=index)
    assert pictures.started.wait(TIMEOUT), 'no picture came'
    decoder.close(timeout=0.5)       # returns with the reader still inside on_picture
    closed.set()
    pictures.hold.set()
    wait_until(lambda: not any(t.is_alive() for t in decoder._threads), TIMEOUT,
               what="the decoder's threads ended")
    assert late == [], 'pictures handed out after close(): %s' % late
