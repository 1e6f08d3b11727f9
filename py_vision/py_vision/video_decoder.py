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
H.264 and HEVC access units to BGR pictures, with the decoder this machine's OpenCV has.

OpenCV decodes video only from a source it opens itself, so the access units are written into
a pipe that a `cv2.VideoCapture` reads: FFmpeg's ``pipe:<fd>`` where OpenCV has FFmpeg (a PC's
opencv-python, 4.x and 5.x alike), else a GStreamer pipeline from ``fdsrc fd=<fd>`` where it has
GStreamer (the boards' OpenCV 4.6.0), else nothing, and `unavailable_reason()` says so. A
writer thread feeds the pipe and a reader thread takes the pictures out, so `decode()` never
waits. Each access unit is followed by an access unit delimiter, which tells FFmpeg's parser
that the picture is whole at once (otherwise it waits for the next one, a frame period), and
FFmpeg decodes on one thread where OpenCV lets it choose (5.x; see `_open_capture`).

Pictures come out in the order of the units (a camera's stream has no B-frames), each with the
tag its unit was given. Decoding starts at a unit a decoder can start at (a keyframe with its
parameter sets, `annexb`); a decoder that falls behind by `max_queue` units (queued, or in the
pipe) drops units up to the next such start: it catches up a group of pictures at a time and
never shows a picture whose references it skipped.
"""

import collections
import os
import re
import threading
from typing import Callable, Optional

import cv2
import numpy as np
from py_vision.annexb import AUD, inspect, leading_delimiter
from py_vision.capture.opencv_env import prepare_opencv

__all__ = ['backend', 'unavailable_reason', 'VideoDecoder']

# FFmpeg reads 32 bytes to tell the stream's format (the default probes 5 MB: seconds of
# video before the first picture); the parameter sets in the first unit do the rest.
_FFMPEG_OPTIONS = 'probesize;32'
_PARSERS = {'h264': 'h264parse', 'hevc': 'h265parse'}
_CAPS = {'h264': 'video/x-h264', 'hevc': 'video/x-h265'}


def _built_with(name: str, build_information: str) -> bool:
    found = re.search(r'^\s*%s:\s*(\S+)' % name, build_information, re.MULTILINE)
    return bool(found) and found.group(1).upper() != 'NO'


def backend(build_information: Optional[str] = None) -> Optional[str]:
    """Return 'ffmpeg', 'gstreamer' or None: how this OpenCV can decode a stream."""
    info = cv2.getBuildInformation() if build_information is None else build_information
    if _built_with('FFMPEG', info):
        return 'ffmpeg'
    if _built_with('GStreamer', info):
        return 'gstreamer'
    return None


def unavailable_reason(build_information: Optional[str] = None) -> Optional[str]:
    """Return why this machine cannot decode H.264 (None: it can try)."""
    if backend(build_information) is None:
        return ('this OpenCV (%s) has neither FFmpeg nor GStreamer to decode video with'
                % cv2.__version__)
    return None


def _source(kind: str, codec: str, fd: int) -> str:
    if kind == 'ffmpeg':
        return 'pipe:%d' % fd
    # decodebin takes the best decoder installed (a hardware one where the board has it).
    return ('fdsrc fd=%d ! %s,stream-format=byte-stream ! %s ! decodebin ! videoconvert ! '
            'video/x-raw,format=BGR ! appsink sync=false' % (fd, _CAPS[codec], _PARSERS[codec]))


def _open_capture(kind: str, source: str):
    if kind == 'ffmpeg':
        # OpenCV reads the options from the environment when the capture opens, and this
        # capture only is meant: they are set for that call.
        previous = os.environ.get('OPENCV_FFMPEG_CAPTURE_OPTIONS')
        os.environ['OPENCV_FFMPEG_CAPTURE_OPTIONS'] = _FFMPEG_OPTIONS
        try:
            # FFmpeg's frame threads each hold a picture back: one thread gives it out at once.
            # OpenCV 4.6 cannot set their number (one per CPU: a picture is late by one frame
            # period per CPU beyond the first).
            threads = getattr(cv2, 'CAP_PROP_N_THREADS', None)
            return cv2.VideoCapture(source, cv2.CAP_FFMPEG, [] if threads is None else [
                threads, 1])
        finally:
            if previous is None:
                del os.environ['OPENCV_FFMPEG_CAPTURE_OPTIONS']
            else:
                os.environ['OPENCV_FFMPEG_CAPTURE_OPTIONS'] = previous
    return cv2.VideoCapture(source, cv2.CAP_GSTREAMER)


class VideoDecoder:
    """
    Decodes a stream of access units; on_picture(bgr, tag) is called for each picture.

    on_picture runs on the decoder's own thread. on_failure(reason), if given, is called once
    when the decoder cannot go on (it did not open, or it stopped), on that thread too.
    """

    def __init__(self, codec: str, on_picture: Callable[[np.ndarray, object], None],
                 on_failure: Optional[Callable[[str], None]] = None, max_queue: int = 30,
                 build_information: Optional[str] = None):
        self.codec = codec
        self.kind = backend(build_information)
        self._on_picture = on_picture
        self._on_failure = on_failure
        self._max_queue = max_queue
        self._lock = threading.Condition()
        self._queue = collections.deque()    # (bytes, tag) not yet written
        self._tags = collections.deque()     # tags of the units written, not yet decoded
        self._started = False                # a unit a decoder can start at was queued
        self._closed = False
        self._failed = unavailable_reason(build_information)
        self.decoded = 0
        self.dropped = 0
        self._threads = []
        self._read_fd = self._write_fd = None
        if self.kind is not None:
            prepare_opencv()
            self._read_fd, self._write_fd = os.pipe()
            for target, name in ((self._write, 'video_writer'), (self._read, 'video_reader')):
                thread = threading.Thread(target=target, name=name, daemon=True)
                thread.start()
                self._threads.append(thread)

    @property
    def failed(self) -> Optional[str]:
        """Return why the decoder cannot decode (none here, or it stopped), or None."""
        return self._failed

    def decode(self, access_unit, tag=None) -> None:
        """Queue one access unit (bytes or 1-D uint8) for decoding; never waits."""
        data = bytes(access_unit)
        with self._lock:
            if self._closed or self._failed is not None:
                return
            if len(self._queue) + len(self._tags) >= self._max_queue:
                # Behind (units waiting, in the queue or in the pipe): drop the queued ones
                # and wait for the next unit a decoder can start at, so no picture is
                # decoded without its references.
                self.dropped += len(self._queue) + 1
                self._queue.clear()
                self._started = False
                return
            if not self._started:
                if not inspect(data, self.codec).decodable_start:
                    self.dropped += 1
                    return
                self._started = True
            self._queue.append((data, tag))
            self._lock.notify_all()

    def _write(self):
        delimiter = AUD[self.codec]
        first = True
        try:
            while True:
                with self._lock:
                    self._lock.wait_for(lambda: self._queue or self._closed)
                    if self._closed:
                        return
                    data, tag = self._queue.popleft()
                    self._tags.append(tag)
                # A delimiter was written after the previous unit already: a second one in a
                # row would be an empty access unit.
                if not first:
                    data = data[leading_delimiter(data, self.codec):]
                first = False
                view = memoryview(data + delimiter)
                while view:
                    view = view[os.write(self._write_fd, view):]
        except OSError:
            pass   # the reader is gone (closed, or failed): nothing more to write
        finally:
            self._close_fd('_write_fd')

    def _read(self):
        capture = _open_capture(self.kind, _source(self.kind, self.codec, self._read_fd))
        try:
            if not capture.isOpened():
                self._fail('OpenCV %s could not open the stream with %s' % (
                    cv2.__version__, 'FFmpeg' if self.kind == 'ffmpeg' else
                    'GStreamer (it needs %s and an H.264 decoder: gstreamer1.0-plugins-bad '
                    'and -libav)' % _PARSERS[self.codec]))
                return
            while True:
                ok, picture = capture.read()
                if not ok or picture is None:
                    if not self._closed:
                        self._fail('the decoder stopped')
                    return
                with self._lock:
                    if self._closed:  # a picture read after close() goes nowhere
                        return
                    tag = self._tags.popleft() if self._tags else None
                self.decoded += 1
                self._on_picture(picture, tag)
        finally:
            capture.release()
            self._close_fd('_read_fd')

    def _fail(self, reason):
        with self._lock:
            if self._failed is not None or self._closed:
                return
            self._failed = reason
            self._lock.notify_all()
        if self._on_failure is not None:
            self._on_failure(reason)

    def _close_fd(self, name):
        with self._lock:
            fd = getattr(self, name)
            setattr(self, name, None)
        if fd is not None:
            try:
                os.close(fd)
            except OSError:
                pass

    def close(self, timeout: float = 2.0) -> None:
        """Stop decoding; the pictures on their way are dropped."""
        with self._lock:
            self._closed = True
            self._lock.notify_all()
        for thread in self._threads:
            thread.join(timeout)
