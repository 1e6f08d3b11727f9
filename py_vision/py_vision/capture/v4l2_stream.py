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
V4L2 cameras streamed by py_vision itself: mapped or user buffers, one frame at a time.

`V4L2Source` is the FrameSource of a V4L2 capture device. `configure` sets the pixel format
and size (VIDIOC_S_FMT) and the frame interval (VIDIOC_S_PARM) and reads back what the driver
chose; `start` asks for buffers once (VIDIOC_REQBUFS), maps each (VIDIOC_QUERYBUF, mmap),
queues them all (VIDIOC_QBUF) and starts the stream (VIDIOC_STREAMON); `next_frame` waits with
poll() for a filled buffer and takes it (VIDIOC_DQBUF), handing out a view of its bytes: only
`bytesused` of them, stamped with the buffer's time when the driver says it is CLOCK_MONOTONIC
(time.monotonic()'s clock), numbered by its sequence. The buffer goes back to the driver at the
next `next_frame()`, so a frame is converted straight from the driver's memory and never
copied on the way. `stop` ends the stream (VIDIOC_STREAMOFF) and keeps the device, its buffers
and its controls, so that `start` resumes at once and nobody else can take the camera
meanwhile; `release` gives everything back.

`capture_into(arrays)` hands the device memory of the program's own to write frames into
(V4L2_MEMORY_USERPTR): the pixel bytes of the messages that go out, so that a frame published
as the camera sent it is never copied by the program. A driver that does not take user memory
(REQBUFS or QBUF refuse it) streams into its own mapped buffers instead, as without it; a frame
in user memory says which array it is in (`Frame.user_buffer`).

The device is polled only while it has buffers: a poll on a queue without any starts the
read() emulation of a driver that offers read I/O (vivid does; uvcvideo does not), which
allocates buffers of its own and makes S_FMT EBUSY.

Structures are laid out from include/uapi/linux/videodev2.h with the machine's own alignment
(`struct v4l2_buffer` holds a `struct timeval` of two longs and a union with a pointer: 88
bytes on x86-64 and aarch64).
"""

import errno
import fcntl
from fractions import Fraction
import mmap
import os
import select
import struct
from typing import List, Optional, Sequence

import numpy as np
from py_vision.capture.controls import ControlInfo
from py_vision.capture.pixel_formats import fourcc_text, PixelFormat
from py_vision.capture.source import Frame, FrameFormat, StreamFormat
from py_vision.capture.v4l2 import (
    _ioc, _REQBUFS, BUF_TYPE_VIDEO_CAPTURE, CAP_VIDEO_CAPTURE, MEMORY_MMAP, MEMORY_USERPTR,
    open_problem, V4L2Device, V4L2Error, VIDIOC_REQBUFS)

__all__ = ['STREAM_PROBLEMS', 'V4L2Source']

# struct v4l2_format for a single-planar capture: type, then a 200-byte union aligned for its
# pointer members, of which struct v4l2_pix_format: width height pixelformat field
# bytesperline sizeimage colorspace priv flags ycbcr_enc quantization xfer_func.
_FORMAT = struct.Struct('@I0P12I152x')
# struct v4l2_streamparm: type, then struct v4l2_captureparm (capability capturemode
# timeperframe extendedmode readbuffers reserved[4]) in a 200-byte union.
_STREAMPARM = struct.Struct('=I6I16x160x')
# struct v4l2_buffer: index type bytesused flags field, struct timeval, struct v4l2_timecode
# (type flags frames seconds minutes hours userbits[4]), sequence memory, the union m (offset
# or a pointer), length reserved2 request_fd.
_BUFFER = struct.Struct('@5Ill2I8B2IL3I0l')
_WRITE, _READ_WRITE = 1, 3
VIDIOC_G_FMT = _ioc(_READ_WRITE, 4, _FORMAT.size)
VIDIOC_S_FMT = _ioc(_READ_WRITE, 5, _FORMAT.size)
VIDIOC_QUERYBUF = _ioc(_READ_WRITE, 9, _BUFFER.size)
VIDIOC_QBUF = _ioc(_READ_WRITE, 15, _BUFFER.size)
VIDIOC_DQBUF = _ioc(_READ_WRITE, 17, _BUFFER.size)
VIDIOC_STREAMON = _ioc(_WRITE, 18, 4)
VIDIOC_STREAMOFF = _ioc(_WRITE, 19, 4)
VIDIOC_G_PARM = _ioc(_READ_WRITE, 21, _STREAMPARM.size)
VIDIOC_S_PARM = _ioc(_READ_WRITE, 22, _STREAMPARM.size)

CAP_STREAMING = 0x04000000
BUF_FLAG_ERROR = 0x0040
BUF_FLAG_TIMESTAMP_MASK = 0xE000
BUF_FLAG_TIMESTAMP_MONOTONIC = 0x2000
FIELD_ANY = 0
BUFFERS = 4
# Where _BUFFER's values hold a mapped buffer's place, and where `memory` lies in it.
_OFFSET, _LENGTH = 19, 20
_MEMORY_AT = struct.calcsize('@5Ill2I8BI')
# What a dequeued buffer says, the rest skipped: index, bytesused, flags, timestamp, sequence.
_DEQUEUED = struct.Struct('@I4xII4xll16xI')


def _buffer_for(index: int, memory: int = MEMORY_MMAP, address: int = 0,
                length: int = 0) -> bytes:
    """
    Return a struct v4l2_buffer naming buffer `index` of the capture queue.

    mmap'd, or (MEMORY_USERPTR) the program's memory of length bytes at address.
    """
    buffer = bytearray(_BUFFER.size)
    struct.pack_into('=II', buffer, 0, index, BUF_TYPE_VIDEO_CAPTURE)
    struct.pack_into('=I', buffer, _MEMORY_AT, memory)
    if memory == MEMORY_USERPTR:
        struct.pack_into('@LI', buffer, _BUFFER_M_AT, address, length)
    return bytes(buffer)


# Where the union m (then length) lies in struct v4l2_buffer.
_BUFFER_M_AT = struct.calcsize('@5Ill2I8B2I0L')
_BUFFERS = [_buffer_for(index) for index in range(32)]   # VIDEO_MAX_FRAME buffers at most
_STREAM_TYPE = struct.pack('=I', BUF_TYPE_VIDEO_CAPTURE)

# What a driver that cannot use the user memory it is given answers QBUF (an unplugged or
# taken device answers otherwise: that is said as it is).
_USER_MEMORY_REFUSED = (errno.EINVAL, errno.EFAULT, errno.ENOMEM)
# Why a stream does not start, by errno, where open_problem's words would not tell a user.
STREAM_PROBLEMS = {
    errno.ENOMEM: 'the driver has no memory for the buffers',
    # uvcvideo cannot reserve the isochronous bandwidth: other streams hold the bus.
    errno.ENOSPC: "the USB bus is full with another camera's stream",
}


def _stream_error(call: str, error: OSError) -> V4L2Error:
    """Return the one-line reason a call that starts streaming failed."""
    code = error.errno
    words = STREAM_PROBLEMS.get(code) or open_problem(code)
    return V4L2Error('streaming does not start (%s: %s)' % (call, words), code)


class V4L2Source:
    """A V4L2 capture device streamed with mmap buffers (see the module's text)."""

    def __init__(self, path: str):
        self.device = V4L2Device(path)
        if not self.device.caps & CAP_VIDEO_CAPTURE:
            self.device.close()
            raise V4L2Error('a multi-planar capture device (py_vision streams single-planar '
                            'ones)')
        if not self.device.caps & CAP_STREAMING:
            self.device.close()
            raise V4L2Error('it cannot stream (no V4L2 streaming I/O)')
        self._fd = self.device.fd
        self._maps: List[mmap.mmap] = []
        self._arrays: List[np.ndarray] = []     # each buffer's bytes, made once
        self._user: Optional[List[np.ndarray]] = None   # capture_into()'s memory
        self.memory: Optional[int] = None       # the buffers': MEMORY_MMAP, _USERPTR, or none
        self._queue_as: List[bytes] = _BUFFERS  # each buffer's struct v4l2_buffer for QBUF
        self._dequeue_as = _BUFFERS[0]
        self._held: Optional[int] = None        # the buffer the last frame's bytes are in
        self._streaming = False
        self._queued = False    # every buffer is with the driver (a STREAMON that failed)
        self._format: Optional[StreamFormat] = None
        self._pixel_format: Optional[PixelFormat] = None
        self._timeout = 1.0
        self.buffer_bytes = 0    # a frame's buffer, as the driver sizes it (sizeimage)
        self._whole = 0          # the bytes of a whole raw frame (0: compressed)
        self._wake_read, self._wake_write = os.pipe2(os.O_NONBLOCK | os.O_CLOEXEC)
        self._poll = select.epoll()
        self._poll.register(self._wake_read, select.EPOLLIN)
        self._polled = False    # the device is in the epoll set (only while it has buffers)

    # --- formats and controls: the device's own answers ------------------------------------

    def formats(self) -> List[FrameFormat]:
        """Return what the device offers."""
        return self.device.formats()

    def controls(self) -> List[ControlInfo]:
        """Return the device's controls with their current values."""
        return self.device.controls()

    def set_control(self, cid: int, value: int) -> Optional[str]:
        """Set a device control through the driver."""
        return self.device.set_control(cid, value)

    # --- configuring ----------------------------------------------------------------------

    def configure(self, pixel_format: PixelFormat, width: int, height: int,
                  fps: float) -> StreamFormat:
        """Ask for a format, size and rate; return what the driver gives. V4L2Error if none."""
        self._free_buffers()
        request = bytearray(_FORMAT.pack(BUF_TYPE_VIDEO_CAPTURE, width, height,
                                         pixel_format.code, FIELD_ANY, *(0,) * 8))
        try:
            fcntl.ioctl(self._fd, VIDIOC_S_FMT, request)
        except OSError as error:
            raise V4L2Error(open_problem(error.errno), error.errno) from None
        _, width, height, code, _, bytesperline, sizeimage, *_ = _FORMAT.unpack(request)
        self.buffer_bytes = sizeimage
        rate = self._set_rate(fps)
        self.device.forget_controls()  # a driver may change ranges with the format or rate
        self._format = StreamFormat(fourcc_text(code), width, height, rate or fps, bytesperline)
        self._pixel_format = pixel_format = self._format.pixel_format
        if pixel_format is not None and not pixel_format.compressed:
            self._whole = pixel_format.frame_bytes(width, height, bytesperline)
        # A frame comes within a few periods of a slow camera, within a second of any other.
        self._timeout = max(1.0, 3.0 / max(rate or fps, 1e-3))
        return self._format

    def _set_rate(self, fps: float) -> float:
        """Ask for a frame interval of 1/fps; return the rate the driver gives (0: unknown)."""
        interval = Fraction(1.0 / fps).limit_denominator(100000)
        request = bytearray(_STREAMPARM.pack(BUF_TYPE_VIDEO_CAPTURE, 0, 0, interval.numerator,
                                             interval.denominator, 0, 0))
        try:
            fcntl.ioctl(self._fd, VIDIOC_S_PARM, request)
        except OSError:
            request = bytearray(_STREAMPARM.pack(BUF_TYPE_VIDEO_CAPTURE, *(0,) * 6))
            try:   # a driver without a settable interval may still tell its own
                fcntl.ioctl(self._fd, VIDIOC_G_PARM, request)
            except OSError:
                return 0.0
        _, _, _, numerator, denominator, _, _ = _STREAMPARM.unpack(request)
        return denominator / numerator if numerator and denominator else 0.0

    # --- streaming ------------------------------------------------------------------------

    def capture_into(self, arrays: Optional[Sequence[np.ndarray]]) -> bool:
        """
        Have the device write frames into arrays (USERPTR) from the next start() on.

        Each array 1-D, writable, contiguous uint8 of at least `buffer_bytes` (the driver's
        sizeimage, from configure()): one buffer each, two at least. None: the device's own
        mapped buffers again. The buffers of a stopped stream are given back first. True
        when the arrays will be tried (a driver may still refuse them at start(): mapped
        buffers then); False when they do not fit (nothing changes then).
        """
        if self._streaming:
            raise RuntimeError('capture_into() while streaming')
        if arrays is not None:
            arrays = list(arrays)
            if len(arrays) < 2 or len(arrays) > len(_BUFFERS) or not all(
                    isinstance(a, np.ndarray) and a.ndim == 1 and a.dtype == np.uint8
                    and a.flags.c_contiguous and a.flags.writeable
                    and a.size >= max(self.buffer_bytes, 1) for a in arrays):
                return False
        self._free_buffers()
        self._user = arrays
        return True

    def start(self) -> None:
        """Start streaming: buffers asked for and mapped once, all queued; V4L2Error if not."""
        if self._streaming:
            return
        if not self._arrays:
            self._map_buffers(user=self._user is not None)
        # After a STREAMON that failed (no room on the USB bus) the driver keeps the buffers
        # queued: queued again, they would be refused.
        if not self._queued:
            self._queue_all()
            self._queued = True
        if not self._polled:
            # Polled only once it has buffers: polling a queue without any starts the read()
            # emulation of a driver that has read I/O (vivid), which takes the queue.
            self._poll.register(self._fd, select.EPOLLIN)
            self._polled = True
        try:
            fcntl.ioctl(self._fd, VIDIOC_STREAMON, _STREAM_TYPE)
        except OSError as error:
            raise _stream_error('VIDIOC_STREAMON', error) from None
        self._held = None
        self._streaming = True

    def _map_buffers(self, user: bool):
        if user and self._user_buffers():
            return
        self.memory = MEMORY_MMAP
        self._queue_as, self._dequeue_as = _BUFFERS, _BUFFERS[0]
        request = bytearray(_REQBUFS.pack(BUFFERS, BUF_TYPE_VIDEO_CAPTURE, MEMORY_MMAP, 0, 0))
        try:
            fcntl.ioctl(self._fd, VIDIOC_REQBUFS, request)
        except OSError as error:
            raise _stream_error('VIDIOC_REQBUFS', error) from None
        count = _REQBUFS.unpack(request)[0]
        if count < 2:
            raise V4L2Error('cannot stream: the driver gives %d buffer(s), 2 are needed'
                            % count)
        try:
            for index in range(count):
                info = bytearray(_BUFFERS[index])
                fcntl.ioctl(self._fd, VIDIOC_QUERYBUF, info)
                fields = _BUFFER.unpack(info)
                mapped = mmap.mmap(self._fd, fields[_LENGTH], mmap.MAP_SHARED, mmap.PROT_READ,
                                   offset=fields[_OFFSET])
                self._maps.append(mapped)
                self._arrays.append(np.frombuffer(mapped, np.uint8))
        except OSError as error:
            self._free_buffers()
            raise _stream_error('mapping the buffers', error) from None

    def _user_buffers(self) -> bool:
        """Ask for capture_into()'s arrays as the buffers (USERPTR); False if refused."""
        arrays = self._user
        request = bytearray(_REQBUFS.pack(len(arrays), BUF_TYPE_VIDEO_CAPTURE, MEMORY_USERPTR,
                                          0, 0))
        try:
            fcntl.ioctl(self._fd, VIDIOC_REQBUFS, request)
        except OSError:
            return False   # no user memory for this driver (EINVAL): mapped buffers
        count = _REQBUFS.unpack(request)[0]
        if not 2 <= count <= len(arrays):
            self._give_back(MEMORY_USERPTR)
            return False
        self.memory = MEMORY_USERPTR
        self._arrays = arrays[:count]
        self._queue_as = [_buffer_for(index, MEMORY_USERPTR, array.ctypes.data, array.size)
                          for index, array in enumerate(self._arrays)]
        self._dequeue_as = self._queue_as[0]
        return True

    def _queue_all(self) -> None:
        """Give every buffer to the driver; V4L2Error if it refuses them."""
        try:
            for index in range(len(self._arrays)):
                self._queue(index)
        except OSError as error:
            if self.memory != MEMORY_USERPTR or error.errno not in _USER_MEMORY_REFUSED:
                raise _stream_error('VIDIOC_QBUF', error) from None
            # A driver that takes no user memory after all (its buffers must be physically
            # contiguous, say): its own mapped buffers then.
            self._free_buffers()
            self._map_buffers(user=False)
            self._queue_all()

    def _queue(self, index: int) -> None:
        fcntl.ioctl(self._fd, VIDIOC_QBUF, bytearray(self._queue_as[index]))

    def stop(self) -> None:
        """Stop streaming (VIDIOC_STREAMOFF); the device, its buffers and controls are kept."""
        if not self._streaming:
            return
        self._streaming = False
        self._held = None   # STREAMOFF takes every buffer back
        self._queued = False
        try:
            fcntl.ioctl(self._fd, VIDIOC_STREAMOFF, _STREAM_TYPE)
        except OSError:
            pass   # an unplugged device has stopped anyway

    def next_frame(self) -> Optional[Frame]:
        """
        Wait for the next filled buffer and return its frame; None when none came or it failed.

        The previous frame's buffer goes back to the driver first. A buffer the driver flagged
        as an error comes back as a Frame with `error` set (and no data).
        """
        # Per frame, the fewest Python steps: poll(), then DQBUF (a DQBUF that finds nothing
        # ready would raise, and an exception costs more than the poll).
        if not self._streaming:
            return None
        fd = self._fd
        if self._held is not None:
            held, self._held = self._held, None
            try:
                fcntl.ioctl(fd, VIDIOC_QBUF, bytearray(self._queue_as[held]))
            except OSError:
                return None
        timeout, buffer = self._timeout, bytearray(self._dequeue_as)
        for _ in range(100):
            events = self._poll.poll(timeout)
            if not events or any(ready == self._wake_read for ready, _ in events):
                return self._woken(events)   # a timeout, or interrupt()
            try:
                fcntl.ioctl(fd, VIDIOC_DQBUF, buffer)
                return self._frame(*_DEQUEUED.unpack_from(buffer))
            except BlockingIOError:
                timeout = 0.01   # readable, yet nothing to take: ask again, briefly
            except OSError:
                return None      # unplugged, or the stream failed for good
        return None

    def _woken(self, events) -> None:
        """Take interrupt()'s byte, if it woke the wait."""
        if events:
            try:
                os.read(self._wake_read, 64)
            except BlockingIOError:
                pass

    def _frame(self, index, used, flags, seconds, microseconds, sequence) -> Frame:
        captured = None
        if flags & BUF_FLAG_TIMESTAMP_MASK == BUF_FLAG_TIMESTAMP_MONOTONIC:
            captured = seconds + microseconds * 1e-6
        stream = self._format
        if flags & BUF_FLAG_ERROR:
            self._queue_back(index)
            return Frame(sequence, captured, self._pixel_format, stream.width, stream.height,
                         error=True)
        self._held = index
        data = self._arrays[index][:used]    # no more than the buffer, if bytesused says more
        return Frame(sequence, captured, self._pixel_format, stream.width, stream.height,
                     data, stream.bytesperline, corrupt=len(data) < self._whole,
                     user_buffer=index if self.memory == MEMORY_USERPTR else None)

    def _queue_back(self, index: int) -> None:
        try:
            self._queue(index)
        except OSError:
            pass   # the next DQBUF says what is wrong

    def interrupt(self) -> None:
        """End a next_frame() waiting in another thread (or the next one) at once."""
        try:
            os.write(self._wake_write, b'x')
        except (BlockingIOError, OSError):
            pass

    def release(self) -> None:
        """Stop streaming and give the buffers and the device back."""
        if self.device.fd is None:
            return
        self.stop()
        self._free_buffers()
        self.device.close()
        self._poll.close()
        os.close(self._wake_read)
        os.close(self._wake_write)

    def _free_buffers(self) -> None:
        self.stop()
        self._queued = False
        if self._polled:
            self._poll.unregister(self._fd)
            self._polled = False
        if not self._arrays:
            return
        memory = self.memory
        if memory == MEMORY_USERPTR:
            self._give_back(memory)   # the driver lets go of user memory before the arrays go
        self._arrays = []
        for mapped in self._maps:
            try:
                mapped.close()
            except BufferError:
                pass   # a frame still holds a view: unmapped when it goes
        self._maps = []
        if memory != MEMORY_USERPTR:
            # Unmapped first: a kernel before 5.0 refuses to free mapped buffers (EBUSY).
            self._give_back(memory)
        self.memory = None

    def _give_back(self, memory: int) -> None:
        """Free the driver's buffers (REQBUFS with a count of 0)."""
        try:
            fcntl.ioctl(self._fd, VIDIOC_REQBUFS, bytearray(_REQBUFS.pack(
                0, BUF_TYPE_VIDEO_CAPTURE, memory, 0, 0)))
        except OSError:
            pass
