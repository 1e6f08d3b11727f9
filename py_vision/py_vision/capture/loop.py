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
The capture loop: open, read, notice a loss, reopen with back-off, re-apply controls, close.

`CaptureLoop` owns one camera and the thread that reads it; the node gives it a way to open
the camera and a function to call with each new frame, and drives it through a small
interface that maps onto a lifecycle node:

===============  ============================================================================
``open()``       configure: open and negotiate, apply the controls the user set; no streaming
``start()``      activate: start streaming, read frames on the capture thread and hand them
                 to ``on_frame`` (opening the camera first if it is closed)
``pause()``      deactivate: stop reading and streaming (VIDIOC_STREAMOFF), the device kept
                 open with its buffers and controls, so that start() resumes at once
``close()``      cleanup: stop reading and release the device; start() opens it again
===============  ============================================================================

A device that fails (reads fail, or no frame for `stall_periods` frame periods: a stall) is
lost: it is released and reopened with back-off, and the controls set through the loop are
applied again. A stream the USB bus has no room for (another camera's stream takes it:
`BusFull`) is tried again with the same back-off, the device kept open, and `stats().waiting`
says why nothing streams meanwhile. Frames captured before the loop (re)started reading are
stale and dropped; a frame the driver flagged as an error, or a corrupt one, is counted and
dropped; frames the device's numbering skips are counted as dropped: on_frame sees only new,
whole frames, and a frame found corrupt while on_frame decodes it (`Frame.image()` None) is
counted too (on_frame publishes no part of it). A frame's bytes are valid while on_frame runs.
`stats()` gives the counters diagnostics report.
"""

from dataclasses import dataclass, replace
import threading
from typing import Callable, Dict, List, Mapping, Optional, Sequence

from py_vision.capture.camera import Camera
from py_vision.capture.controls import ControlInfo, Refusal
from py_vision.capture.source import BusFull, Clock, Frame, MONOTONIC, SourceError
from py_vision.frame_memory import keep_frame_buffers

__all__ = ['CaptureLoop', 'CaptureStats', 'LoopTiming']


@dataclass(frozen=True)
class LoopTiming:
    """When a device counts as lost and how soon it is tried again."""

    lost_after_failed_reads: int = 5     # one bad read is noise
    stall_periods: float = 8.0           # no frame for this many frame periods: a stall
    min_stall_s: float = 1.0             # ... and at least this long (OpenCV's read timeout)
    first_frame_s: float = 3.0           # a camera may take this long to send its first frame
    backoff_s: Sequence[float] = (0.25, 0.5, 1.0, 2.0, 4.0)
    log_period_s: float = 5.0            # failed reopen attempts are logged this often


@dataclass(frozen=True)
class CaptureStats:
    """What the loop has seen, for diagnostics."""

    frames: int = 0          # new, whole frames handed to on_frame
    lost: int = 0            # times the device was lost (failed reads, stall, unplug)
    stalls: int = 0          # ... of which stalls: no frame and no error
    stale: int = 0           # frames dropped as captured before reading (re)started
    corrupt: int = 0         # frames dropped as not whole (a corrupt JPEG, a short buffer)
    errors: int = 0          # frames dropped as the driver flagged them (buffer errors)
    dropped: int = 0         # frames the device's numbering shows it never delivered
    reconnects: int = 0      # times the device came back
    present: bool = False    # the device is open
    streaming: bool = False  # the capture thread is reading
    pixel_format: str = ''   # the FourCC, or 'file'
    width: int = 0
    height: int = 0
    fps: float = 0.0         # the rate the device was set to
    measured_fps: float = 0.0  # the rate frames arrived at over the last second or so
    waiting: str = ''        # why the open device does not stream now (BusFull), in one line
    io_method: str = ''      # how the stream's frames reach us: mmap, userptr ('': not V4L2)


class CaptureLoop:
    """
    One camera read on its own thread, reopened when it is lost.

    `open_camera()` returns an opened Camera or raises SourceError; `on_frame(camera, frame)`
    publishes a frame (on the capture thread); `logger` has info/warning/error. `clock` and
    `timing` are for tests. `on_failure(error)` is called when the capture thread fails with
    an unexpected error (on_frame raised): the loop then stops reading. `on_refused(refusals)`
    hears which controls a reopened camera did not take again (V4L2 id -> Refusal); without it
    they are logged by id.
    """

    def __init__(self, open_camera: Callable[[], Camera],
                 on_frame: Callable[[Camera, Frame], None], logger, *, name: str = 'camera',
                 clock: Clock = MONOTONIC, timing: LoopTiming = LoopTiming(),
                 on_failure: Optional[Callable[[Exception], None]] = None,
                 on_refused: Optional[Callable[[Dict[int, Refusal]], None]] = None):
        self._open_camera = open_camera
        self._on_frame = on_frame
        self._log = logger
        self._name = name
        self._clock = clock
        self._timing = timing
        self._on_failure = on_failure
        self._on_refused = on_refused or self._log_refused
        self._lock = threading.Lock()      # guards camera and wanted controls
        self._camera: Optional[Camera] = None
        self._wanted: Dict[int, int] = {}  # V4L2 id -> value, applied at every (re)open
        self._thread: Optional[threading.Thread] = None
        self._stop = threading.Event()
        # Counted per frame in plain attributes; stats() makes the snapshot.
        self._stats = CaptureStats()
        self._frames = self._stale = self._corrupt = self._errors = self._dropped = 0
        self._last_index: Optional[int] = None   # of the frame before, while reading on
        self._not_before = 0.0
        self._rate_start, self._rate_frames, self._rate = 0.0, 0, 0.0

    # --- the interface the node uses ---------------------------------------------------

    @property
    def camera(self) -> Optional[Camera]:
        """Return the open camera, or None while it is lost or closed."""
        return self._camera

    def open(self) -> Camera:  # noqa: A003
        """Open and negotiate the camera and apply the wanted controls; SourceError if not."""
        with self._lock:
            if self._camera is None:
                self._set_camera(self._open_camera())
            return self._camera

    def start(self) -> None:
        """
        Stream and read frames on the capture thread (opening the camera first if it is closed).

        SourceError (one line) when the camera does not open or its stream does not start.
        """
        thread = self._thread
        if thread is not None:
            if thread.is_alive() and not self._stop.is_set():
                return  # reading already
            if not self.pause():
                return  # a paused thread that has still not ended
        with self._lock:
            if self._camera is None:
                self._set_camera(self._open_camera())
            try:
                self._camera.start()
            except BusFull as error:
                # Not an error of the configuration: the capture thread waits for room.
                self._log.warning(str(error))
                self._update(waiting=str(error))
        self._stop.clear()
        self._last_index = None
        self._not_before = self._clock.now()
        # Said before the thread runs: what it reports (a loss) is never overwritten.
        self._update(streaming=True)
        self._thread = threading.Thread(target=self._run, name='capture', daemon=True)
        self._thread.start()

    resume = start

    def pause(self, timeout: float = 2.0) -> bool:
        """
        Stop reading and streaming, keeping the device open with its controls; False if not.

        A source that cannot stop its stream may go on filling buffers meanwhile: what it
        captured before start() is dropped then, never handed to on_frame. A thread that did
        not end within timeout is left to end (a read stuck in the driver); start() and close()
        wait for it (False meanwhile).
        """
        thread = self._thread
        if thread is None:
            return True
        self._stop.set()
        camera = self._camera
        if camera is not None:
            camera.interrupt()  # a synthetic camera or a file waiting for its next frame
        thread.join(timeout)
        if thread.is_alive():
            return False
        self._thread = None
        with self._lock:
            if self._camera is not None:
                self._camera.stop()
        self._update(streaming=False)
        return True

    def close(self, timeout: float = 2.0) -> bool:
        """Stop reading and release the device; False if the thread did not end in time."""
        ended = self.pause(timeout)
        if ended:
            with self._lock:
                camera, self._camera = self._camera, None
            if camera is not None:
                camera.release()
            self._update(present=False)
        return ended

    def set_controls(self, values: Mapping[int, int], keep: bool = True) -> Dict[int, Refusal]:
        """
        Set controls (V4L2 id -> value) on the camera; return those it refused and why.

        The others are kept (unless keep is False: a button's press) and applied again after
        every reconnect; while the device is lost they are only kept, and applied once it is
        back. A refused value is not kept; a press while the device is lost is refused.
        """
        with self._lock:
            camera = self._camera
            if camera is not None:
                refused = camera.set_controls(values)
            elif keep:
                refused = {}
            else:
                refused = {cid: Refusal(cid, ': %s is not open now' % self._name)
                           for cid in values}
            if keep:
                self._wanted.update((cid, value) for cid, value in values.items()
                                    if cid not in refused)
        return refused

    def wanted_controls(self) -> Dict[int, int]:
        """Return the controls set through the loop (applied again at each reopen)."""
        return dict(self._wanted)

    def controls(self) -> List[ControlInfo]:
        """Return the camera's controls with their current values (none while lost)."""
        with self._lock:
            camera = self._camera
            return camera.controls() if camera is not None else []

    def stats(self) -> CaptureStats:
        """Return the counters so far (a snapshot)."""
        camera = self._camera
        return replace(self._stats, frames=self._frames, stale=self._stale,
                       corrupt=self._corrupt, errors=self._errors, dropped=self._dropped,
                       measured_fps=self._rate,
                       io_method=camera.io_method if camera is not None else '')

    @property
    def running(self) -> bool:
        """Return True while the capture thread runs."""
        return self._thread is not None and self._thread.is_alive()

    # --- the capture thread ------------------------------------------------------------

    def _set_camera(self, camera: Optional[Camera]) -> None:
        """Take camera as the current one (lock held): apply the wanted controls to it."""
        self._camera = camera
        if camera is None:
            self._update(present=False)
            return
        refused = camera.set_controls(self._wanted)
        if refused:
            self._on_refused(refused)
        keep_frame_buffers(camera.width, camera.height)
        self._update(present=True, pixel_format='file' if camera.file else
                     camera.pixel_format.fourcc, width=camera.width, height=camera.height,
                     fps=camera.fps)

    def _log_refused(self, refusals: Dict[int, Refusal]) -> None:
        for refusal in refusals.values():
            self._log.warning("%s; left at the camera's own value"
                              % refusal.words(lambda cid: 'control 0x%08x' % cid))

    def _update(self, **changes) -> None:
        self._stats = replace(self._stats, **changes)

    def _run(self) -> None:
        try:
            self._capture()
        except Exception as error:  # on_frame failed: the node decides what that means
            if self._on_failure is None:
                raise
            self._on_failure(error)

    def _stall_limit(self, camera, first) -> float:
        limit = max(self._timing.min_stall_s, self._timing.stall_periods / max(camera.fps, 1e-3))
        return max(limit, self._timing.first_frame_s) if first else limit

    def _capture(self) -> None:
        # Looked up once here rather than once per frame.
        stopped, now_fn, on_frame = self._stop.is_set, self._clock.now, self._on_frame
        failed_reads = 0
        last_frame = now_fn()
        first = True   # no frame yet from this camera
        while not stopped():
            camera = self._camera
            if camera is None or not camera.streaming:
                if (self._reopen() if camera is None else self._wait_for_room(camera)):
                    last_frame = self._not_before = now_fn()
                    first, self._last_index = True, None
                continue
            frame = camera.read()
            if stopped():
                return
            now = now_fn()
            if frame is None:
                failed_reads += 1
                stalled = now - last_frame >= self._stall_limit(camera, first)
                if stalled or failed_reads >= self._timing.lost_after_failed_reads:
                    self._lose(camera, failed_reads, now - last_frame if stalled else None)
                    failed_reads = 0
                continue
            failed_reads = 0
            # Frames the device's numbering skips before this one never came: dropped.
            index, last = frame.index, self._last_index
            self._last_index = index
            if last is not None and index is not None and index > last + 1:
                self._dropped += index - last - 1
            if frame.capture_time is not None and frame.capture_time < self._not_before:
                self._stale += 1
                continue
            if frame.error:
                last_frame, first = now, False   # the device is there: it is no stall
                self._count_error()
                continue
            if frame.corrupt:
                self._count_corrupt()
                continue
            last_frame, first = now, False
            # The rate frames arrive at: counted over windows of about a second.
            self._rate_frames += 1
            if now - self._rate_start >= 1.0:
                self._measure(now)
            on_frame(camera, frame)
            if frame.corrupt:  # found out while decoding it: on_frame published nothing
                self._count_corrupt()
                continue
            self._frames += 1

    def _count_error(self) -> None:
        self._errors += 1
        if self._errors == 1 or self._errors % 100 == 0:
            self._log.warning('%s delivered a frame flagged as an error (%d so far); dropped, '
                              'never published' % (self._name, self._errors))

    def _count_corrupt(self) -> None:
        self._corrupt += 1
        if self._corrupt == 1 or self._corrupt % 100 == 0:
            self._log.warning('%s sent a corrupt frame (%d so far); skipped, never published'
                              % (self._name, self._corrupt))

    def _measure(self, now) -> None:
        """End a window of a second or more (frames counted in it): its rate; start the next."""
        if self._rate_start:
            self._rate = (self._rate_frames - 1) / (now - self._rate_start)
        self._rate_start, self._rate_frames = now, 1

    def _lose(self, camera, failed_reads, stalled_s) -> None:
        if stalled_s is not None:
            self._log.warning('%s sent no frame for %.1f s (stalled); releasing it and '
                              'reopening' % (self._name, stalled_s))
        else:
            self._log.warning('lost %s after %d failed reads; releasing it and reopening' % (
                self._name, failed_reads))
        with self._lock:
            self._set_camera(None)
        camera.release()
        self._update(lost=self._stats.lost + 1,
                     stalls=self._stats.stalls + (stalled_s is not None))
        self._rate_start, self._rate_frames, self._rate = 0.0, 0, 0.0

    def _wait_for_room(self, camera) -> bool:
        """
        Start the stream the bus had no room for, with back-off; True once it streams.

        False when the loop stops, or the device fails otherwise (it is then lost).
        """
        attempt = 0
        last_log = self._clock.now()   # start() has said it once already
        backoff = self._timing.backoff_s
        while not self._stop.wait(backoff[min(attempt, len(backoff) - 1)]):
            attempt += 1
            try:
                with self._lock:
                    camera.start()
            except BusFull as error:
                now = self._clock.now()
                if now - last_log >= self._timing.log_period_s:
                    last_log = now
                    self._log.warning(str(error))
                continue
            except SourceError as error:   # unplugged meanwhile: lost, reopened
                self._log.warning('%s; releasing it and reopening' % error)
                with self._lock:
                    self._set_camera(None)
                camera.release()
                self._update(lost=self._stats.lost + 1, waiting='')
                return False
            self._update(waiting='')
            self._log.info('%s streams after %d attempt(s): the bus has room again' % (
                self._name, attempt))
            return True
        return False

    def _reopen(self) -> bool:
        """Try to reopen the device with back-off until it is back or the loop stops."""
        attempt = 0
        last_log = None
        backoff = self._timing.backoff_s
        while not self._stop.is_set():
            if self._stop.wait(backoff[min(attempt, len(backoff) - 1)]):
                return False
            attempt += 1
            try:
                with self._lock:
                    camera = self._open_camera()
                    if self._stop.is_set():
                        camera.release()
                        return False
                    self._set_camera(camera)
                    try:
                        camera.start()
                    except BusFull as error:
                        self._log.warning(str(error))   # _wait_for_room goes on from here
                        self._update(waiting=str(error))
                    except SourceError:
                        self._set_camera(None)
                        camera.release()
                        raise
            except SourceError as error:
                now = self._clock.now()
                if last_log is None or now - last_log >= self._timing.log_period_s:
                    last_log = now
                    self._log.warning('reopen attempt %d failed: %s' % (attempt, error))
                continue
            self._update(reconnects=self._stats.reconnects + 1)
            self._log.info('%s is back after %d attempt(s); %s' % (
                self._name, attempt, 'waiting for room on its USB bus' if self._stats.waiting
                else 'publishing resumes'))
            return True
        return False
