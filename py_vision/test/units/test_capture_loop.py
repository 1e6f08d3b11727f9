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


"""CaptureLoop: losses, reopen, controls re-applied, stale, corrupt, error and dropped frames."""

import threading
import time

from py_vision.capture import Camera, CaptureLoop, LoopTiming, SourceError, SyntheticDevices
from py_vision.capture.controls import CID
from py_vision.capture.source import Frame
from py_vision.control_names import ControlNames
from ros_harness import wait_until

FAST = LoopTiming(backoff_s=(0.01,), stall_periods=3, min_stall_s=0.2, first_frame_s=0.5)


class Log:
    """A logger that keeps its lines."""

    def __init__(self):
        self.lines = []

    def info(self, text):
        self.lines.append('INFO ' + text)

    def warning(self, text):
        self.lines.append('WARN ' + text)

    def error(self, text):
        self.lines.append('ERROR ' + text)


class Device:
    """Opens the synthetic camera: unplugged, stalled, corrupt, error, skipped frames at will."""

    def __init__(self, fps=100.0):
        self.fps = fps
        self.devices = SyntheticDevices()
        self.present = threading.Event()
        self.present.set()
        self.stalled = threading.Event()
        self.corrupt = threading.Event()
        self.errors = threading.Event()
        self.skip = threading.Event()    # every other frame never delivered
        self.opened = 0
        self.streaming = []              # start() and stop() of the cameras, in order

    def open(self):  # noqa: A003
        if not self.present.is_set():
            raise SourceError('cannot open video_device "test": unplugged')
        camera = Camera.open('synthetic', 160, 120, self.fps, 'mjpg', synthetic=self.devices)
        self.opened += 1
        device, read, start, stop = self, camera.read, camera.start, camera.stop

        def read_as_device():
            if not device.present.is_set():
                return None
            if device.stalled.is_set():
                time.sleep(0.25)   # the read times out: no frame, no error
                return None
            frame = read()
            if frame is not None and device.skip.is_set():
                frame = read()
            if frame is not None and device.corrupt.is_set():
                return Frame(frame.index, frame.capture_time, frame.pixel_format, frame.width,
                             frame.height, frame.data[:len(frame.data) // 2], corrupt=True)
            if frame is not None and device.errors.is_set():
                return Frame(frame.index, frame.capture_time, frame.pixel_format, error=True)
            return frame

        def start_as_device():
            device.streaming.append('start')
            start()

        def stop_as_device():
            device.streaming.append('stop')
            stop()
        camera.read, camera.start, camera.stop = read_as_device, start_as_device, stop_as_device
        return camera


def value(camera, cid):
    return next(control.value for control in camera.controls() if control.cid == cid)


def run_loop(device, timing=FAST):
    frames, log = [], Log()
    loop = CaptureLoop(device.open, lambda camera, frame: frames.append(frame), log,
                       name='test', timing=timing)
    return loop, frames, log


def test_frames_flow_and_stats_say_what_the_device_gives():
    device = Device()
    loop, frames, log = run_loop(device)
    loop.start()
    try:
        wait_until(lambda: len(frames) >= 20, 10, what='20 frames')
        stats = loop.stats()
        assert stats.present and stats.streaming and stats.pixel_format == 'MJPG'
        assert (stats.width, stats.height, stats.fps) == (160, 120, 100.0)
        wait_until(lambda: loop.stats().measured_fps > 50, 10, what='a measured rate')
    finally:
        assert loop.close()
    assert not loop.stats().present and loop.camera is None


def test_an_unplug_is_a_loss_the_device_is_reopened_and_controls_applied_again():
    device = Device()
    loop, frames, log = run_loop(device)
    loop.start()
    try:
        assert loop.set_controls({CID.BRIGHTNESS: 20}) == {}
        wait_until(lambda: frames, 10, what='frames')
        device.present.clear()
        wait_until(lambda: loop.stats().lost == 1, 10, what='the loss')
        assert any('lost test after 5 failed reads' in line for line in log.lines)
        device.present.set()
        wait_until(lambda: loop.stats().reconnects == 1, 10, what='the reconnect')
        assert value(loop.camera, CID.BRIGHTNESS) == 20
        count = len(frames)
        wait_until(lambda: len(frames) > count, 10, what='frames after the reconnect')
    finally:
        loop.close()


def test_a_stall_is_a_loss_not_a_hang():
    device = Device()
    loop, frames, log = run_loop(device)
    loop.start()
    try:
        wait_until(lambda: frames, 10, what='frames')
        device.stalled.set()
        wait_until(lambda: loop.stats().stalls == 1, 10, what='the stall noticed')
        assert any('sent no frame for' in line and 'stalled' in line for line in log.lines)
        device.stalled.clear()
        wait_until(lambda: loop.stats().reconnects >= 1, 10, what='the reconnect')
    finally:
        loop.close()


def test_corrupt_frames_are_counted_and_never_handed_on():
    device = Device()
    loop, frames, log = run_loop(device)
    loop.start()
    try:
        wait_until(lambda: frames, 10, what='frames')
        device.corrupt.set()
        wait_until(lambda: loop.stats().corrupt >= 5, 10, what='corrupt frames')
        device.corrupt.clear()
        count = len(frames)
        wait_until(lambda: len(frames) > count + 5, 10, what='whole frames again')
    finally:
        loop.close()
    assert not any(frame.corrupt for frame in frames)
    assert loop.stats().lost == 0  # corrupt frames are not a lost device
    assert sum('corrupt frame' in line for line in log.lines) == 1


def test_frames_flagged_as_errors_are_counted_and_never_handed_on():
    device = Device()
    loop, frames, log = run_loop(device)
    loop.start()
    try:
        wait_until(lambda: frames, 10, what='frames')
        device.errors.set()
        wait_until(lambda: loop.stats().errors >= 5, 10, what='error frames')
        count = len(frames)
        device.errors.clear()
        wait_until(lambda: len(frames) > count + 5, 10, what='frames again')
    finally:
        loop.close()
    assert not any(frame.error for frame in frames)
    stats = loop.stats()
    assert stats.lost == 0 and stats.corrupt == 0   # the device is there and sends whole ones
    assert sum('flagged as an error' in line for line in log.lines) == 1


def test_frames_the_numbering_skips_are_counted_as_dropped():
    device = Device()
    loop, frames, log = run_loop(device)
    loop.start()
    try:
        wait_until(lambda: len(frames) >= 5, 10, what='frames')
        device.skip.set()
        before = len(frames)
        wait_until(lambda: len(frames) >= before + 10, 10, what='frames with gaps')
        device.skip.clear()
        seen = list(frames)
        stats = loop.stats()
    finally:
        loop.close()
    # A reader the machine's load makes late misses frames of this 100 fps camera too: the
    # numbering shows those, and they count as dropped as well.
    gaps = [later.index - earlier.index for earlier, later in zip(seen, seen[1:])]
    # Every frame handed on after the skipping began follows one that never came.
    assert all(gap >= 2 for gap in gaps[before:before + 9]), gaps
    assert stats.dropped >= sum(gap - 1 for gap in gaps) >= 9


def test_pause_keeps_the_device_and_resume_drops_what_was_captured_before():
    device = Device()
    loop, frames, log = run_loop(device)
    camera = loop.open()
    assert not loop.running and loop.stats().present and frames == []
    loop.start()
    wait_until(lambda: frames, 10, what='frames')
    assert loop.pause()
    assert loop.camera is camera and loop.stats().present and not loop.stats().streaming
    assert device.streaming == ['start', 'stop']   # the stream stopped, the device kept
    assert loop.set_controls({CID.CONTRAST: 10}) == {}
    paused_at = device.devices.clock.now()
    frames.clear()
    loop.resume()
    wait_until(lambda: len(frames) >= 3, 10, what='frames after resume')
    loop.close()
    assert all(frame.capture_time >= paused_at for frame in frames)
    assert device.opened == 1 and device.streaming[:3] == ['start', 'stop', 'start']
    assert loop.stats().dropped == 0   # frames missed while paused are not drops
    assert value(camera, CID.CONTRAST) == 10


def test_a_refused_control_is_said_and_not_kept():
    device = Device()
    loop, frames, log = run_loop(device)
    loop.open()
    try:
        names = ControlNames(loop.controls())
        refused = loop.set_controls({CID.BRIGHTNESS: 500, CID.CONTRAST: 10})
        assert [names.words(r) for r in refused.values()] == [
            "brightness: 500 is out of the camera's range -64..64"]
        assert loop.wanted_controls() == {CID.CONTRAST: 10}
        refused = loop.set_controls({CID.FOCUS_ABSOLUTE: 10})
        assert names.words(refused[CID.FOCUS_ABSOLUTE], {CID.FOCUS_ABSOLUTE: 'focus'}) == \
            'focus is inactive while focus_automatic_continuous is 1'
    finally:
        loop.close()


def test_a_batch_sets_the_automatic_mode_first_and_is_applied_so_after_a_reconnect():
    device = Device()
    loop, frames, log = run_loop(device)
    loop.start()
    try:
        # Focus before autofocus in the batch: autofocus goes first, so the focus is free.
        assert loop.set_controls({CID.FOCUS_ABSOLUTE: 40, CID.FOCUS_AUTO: 0}) == {}
        assert value(loop.camera, CID.FOCUS_ABSOLUTE) == 40
        # A press (keep=False) is not pressed again after a reconnect.
        assert loop.set_controls({CID.GAIN: 7}, keep=False) == {}
        assert loop.wanted_controls() == {CID.FOCUS_ABSOLUTE: 40, CID.FOCUS_AUTO: 0}
        device.present.clear()
        wait_until(lambda: loop.stats().lost == 1, 10, what='the loss')
        device.present.set()
        wait_until(lambda: loop.stats().reconnects == 1, 10, what='the reconnect')
        camera = loop.camera
        assert (value(camera, CID.FOCUS_AUTO), value(camera, CID.FOCUS_ABSOLUTE),
                value(camera, CID.GAIN)) == (0, 40, 0)
    finally:
        loop.close()


def test_what_a_reopened_camera_refuses_is_heard_by_id():
    device = Device()
    heard = []
    loop = CaptureLoop(device.open, lambda camera, frame: None, Log(), name='test',
                       timing=FAST, on_refused=heard.append)
    loop.open()
    try:
        loop.close()
        assert loop.set_controls({CID.BRIGHTNESS: 500}) == {}   # kept, checked when it is back
        pressed = loop.set_controls({CID.GAIN: 1}, keep=False)   # a press cannot wait
        assert [r.why for r in pressed.values()] == [': test is not open now']
        loop.open()
        assert [(cid, refusal.why) for refusals in heard
                for cid, refusal in refusals.items()] == [
            (CID.BRIGHTNESS, ": 500 is out of the camera's range -64..64")]
    finally:
        loop.close()
