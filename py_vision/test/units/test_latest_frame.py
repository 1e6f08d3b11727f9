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

"""LatestFrameWorker: a slow step takes the newest item, a fast one every item in order."""

import threading

from fake_clock import FakeClock
from py_vision.latest_frame import LatestFrameWorker
import pytest
from ros_harness import wait_until

TIMEOUT = 10.0  # generous: only reached when something is broken


class Recorder:
    """A processing step that records its items and can be held inside a step."""

    def __init__(self):
        self.items = []
        self.started = threading.Event()
        self.release = threading.Event()
        self.release.set()

    def __call__(self, item):
        self.started.set()
        assert self.release.wait(TIMEOUT)
        self.items.append(item)


@pytest.fixture
def closing():
    """Close every worker a test makes, also when the test fails."""
    workers = []
    yield workers.append
    for worker in workers:
        worker.close()


def test_a_slow_step_takes_the_newest_item_and_counts_the_ones_it_skipped(closing):
    step = Recorder()
    worker = LatestFrameWorker(step)
    closing(worker)
    step.release.clear()
    worker.offer(0)
    assert step.started.wait(TIMEOUT)
    for item in range(1, 11):  # all arrive while item 0 is being processed
        worker.offer(item)
    step.release.set()
    wait_until(lambda: worker.processed == 2, TIMEOUT, what='the second step')
    assert step.items == [0, 10]
    assert (worker.frames_in, worker.processed, worker.skipped) == (11, 2, 9)
    # Then the worker waits for the next item, it does not run again on an old one.
    worker.offer(11)
    wait_until(lambda: worker.processed == 3, TIMEOUT, what='the third step')
    assert step.items == [0, 10, 11] and worker.skipped == 9


def test_items_that_arrive_when_the_step_is_ready_are_all_processed_in_order(closing):
    step = Recorder()
    worker = LatestFrameWorker(step)
    closing(worker)
    for item in range(50):
        worker.offer(item)
        wait_until(lambda: len(step.items) == item + 1, TIMEOUT, interval=0.001,
                   what='item %d to be processed' % item)
    assert step.items == list(range(50))
    assert (worker.frames_in, worker.processed, worker.skipped) == (50, 50, 0)


def test_none_is_an_item_like_any_other(closing):
    step = Recorder()
    worker = LatestFrameWorker(step)
    closing(worker)
    worker.offer(None)
    wait_until(lambda: worker.processed == 1, TIMEOUT, what='the step')
    assert step.items == [None]


def test_statistics_give_counts_and_percentiles_of_the_recent_window(closing):
    clock = FakeClock()
    durations = [i / 100 for i in range(1, 101)]  # 10 ms .. 1000 ms, one step each

    def step(duration):
        clock.t += duration
    worker = LatestFrameWorker(step, window_s=100.0, clock=clock, cpu_clock=clock)
    closing(worker)
    empty = worker.snapshot()
    assert empty == {'frames_in': 0, 'processed': 0, 'skipped': 0,
                     'processing_ms_p50': None, 'processing_ms_p99': None,
                     'age_ms_p50': None, 'age_ms_p99': None,
                     'part_ms_p50': None, 'part_ms_p99': None,
                     'rest_ms_p50': None, 'rest_ms_p99': None, 'part_items': 0,
                     'cpu_ms': 0, 'part_cpu_ms': 0}
    for count, duration in enumerate(durations, start=1):
        worker.offer(duration)
        wait_until(lambda: worker.processed == count, TIMEOUT, interval=0.001,
                   what='step %d' % count)
    for age_ms in range(200, 0, -1):  # 1 .. 200 ms, in any order
        worker.record_age(age_ms / 1e3)
    snap = worker.snapshot()
    assert (snap['frames_in'], snap['processed'], snap['skipped']) == (100, 100, 0)
    assert snap['processing_ms_p50'] == pytest.approx(500.0)
    assert snap['processing_ms_p99'] == pytest.approx(990.0)
    assert snap['age_ms_p50'] == pytest.approx(100.0)
    assert snap['age_ms_p99'] == pytest.approx(198.0)
    # The percentiles describe the last window_s seconds; the counts are since start.
    clock.t += 100.1
    later = worker.snapshot()
    assert later['processing_ms_p50'] is None and later['age_ms_p99'] is None
    assert later['processed'] == 100
    # Without a part clock nothing is split. The steps' CPU time (here: the fake clock's
    # time, their thread using all of it) is added up since start: 10 ms .. 1000 ms, 50.5 s.
    assert snap['part_ms_p50'] is None and snap['rest_ms_p50'] is None
    assert snap['part_items'] == 0 and snap['part_cpu_ms'] == 0
    assert later['cpu_ms'] == 50500


def test_a_part_clock_splits_each_items_time_into_that_part_and_the_rest(closing):
    # part: the seconds inside models, say; its CPU time a quarter of its wall time (a model
    # run that waits for a core most of the time), the step's own work all CPU.
    clock, part, cpu = FakeClock(), FakeClock(0.0), FakeClock(0.0)

    def step(inside_s):
        clock.t += 0.003  # 3 ms of the step's own work, every item
        cpu.t += 0.003
        clock.t += inside_s
        part.t += inside_s
        cpu.t += inside_s / 4
        if inside_s > 0.085:
            raise ValueError('a step that fails after its model ran')
    worker = LatestFrameWorker(step, window_s=100.0, clock=clock, cpu_clock=cpu,
                               part_clock=lambda: (part.t, part.t / 4),
                               on_error=lambda error: None)
    closing(worker)
    # 90 items with 1 .. 90 ms inside the part, 10 with none (a frame no model ran on).
    parts = [ms / 1e3 for ms in range(1, 91)] + [0.0] * 10
    for count, inside in enumerate(parts, start=1):
        worker.offer(inside)
        wait_until(lambda: worker.processed == count, TIMEOUT, interval=0.001,
                   what='step %d' % count)
    snap = worker.snapshot()
    # Sorted, the parts are 10 zeros then 1 .. 90 ms: the 50th is 40 ms, the 99th 89 ms.
    assert snap['part_ms_p50'] == pytest.approx(40.0)
    assert snap['part_ms_p99'] == pytest.approx(89.0)
    assert snap['rest_ms_p50'] == pytest.approx(3.0) and snap['rest_ms_p99'] == pytest.approx(3.0)
    assert snap['processing_ms_p50'] == pytest.approx(43.0)
    assert snap['part_items'] == 90
    # CPU since start: 1 + 2 + .. + 90 ms in the part, a quarter of it (1023.75 ms); 3 ms
    # more an item in all.
    assert snap['part_cpu_ms'] == 1024
    assert snap['cpu_ms'] == 1324
    clock.t += 100.1
    later = worker.snapshot()
    assert later['part_ms_p50'] is None and later['rest_ms_p99'] is None
    assert later['part_items'] == 0


def test_the_processing_and_the_rest_cover_the_same_steps_however_the_clock_moves(closing):
    # A clock that moves a little every time it is read (a loaded machine): the processing
    # time and the rest of it (no part here: all of it) must come from one window, whatever
    # falls out of it between two readings.
    class Ticking(FakeClock):
        def __call__(self):
            self.t += 1e-4
            return self.t
    clock = Ticking()

    def step(seconds):
        clock.t += seconds
    worker = LatestFrameWorker(step, window_s=1.0, clock=clock,
                               part_clock=lambda: (0.0, 0.0))
    closing(worker)
    for count, seconds in enumerate([0.01 * (i % 7 + 1) for i in range(40)], start=1):
        worker.offer(seconds)
        wait_until(lambda: worker.processed == count, TIMEOUT, interval=0.001,
                   what='step %d' % count)
    for _ in range(12000):  # past the window's end, a tenth of a millisecond at a time
        clock.t += 1e-4
        snap = worker.snapshot()
        assert (snap['rest_ms_p50'], snap['rest_ms_p99']) == (
            snap['processing_ms_p50'], snap['processing_ms_p99']), snap
    assert snap['processing_ms_p50'] is None


def test_a_step_that_raises_is_reported_and_the_worker_goes_on():
    errors = []

    def step(item):
        if item == 'bad':
            raise ValueError('cannot use %s' % item)
        done.append(item)
    done = []
    worker = LatestFrameWorker(step, on_error=errors.append)
    try:
        worker.offer('bad')
        wait_until(lambda: worker.processed == 1, TIMEOUT, what='the failing step')
        worker.offer('good')
        wait_until(lambda: worker.processed == 2, TIMEOUT, what='the next step')
    finally:
        worker.close()
    assert done == ['good']
    assert [str(error) for error in errors] == ['cannot use bad']


def test_close_ends_a_long_step_that_polls_closed_and_drops_the_waiting_item():
    seen_closed = threading.Event()
    started = threading.Event()
    holder = {}

    def long_step(item):
        started.set()
        # A step of "forever" that checks for shutdown, as cv_bridge_test's simulated work.
        while not holder['worker'].closed:
            seen_closed.wait(0.001)
        seen_closed.set()
    worker = holder['worker'] = LatestFrameWorker(long_step)
    worker.offer(1)
    assert started.wait(TIMEOUT)
    worker.offer(2)  # waits behind the long step
    assert worker.close(timeout=TIMEOUT)
    assert seen_closed.is_set()
    assert (worker.frames_in, worker.processed, worker.skipped) == (2, 1, 1)
    worker.offer(3)  # after close: ignored
    assert worker.frames_in == 2 and worker.processed == 1


def test_close_does_not_wait_forever_for_a_step_that_ignores_it_nor_report_its_failure():
    step = Recorder()
    errors = []

    def failing_step(item):
        step(item)
        raise RuntimeError('the publisher is gone')
    worker = LatestFrameWorker(failing_step, on_error=errors.append)
    step.release.clear()
    worker.offer(1)
    assert step.started.wait(TIMEOUT)
    assert not worker.close(timeout=0.05)  # the step is still held: close gives up waiting
    step.release.set()
    wait_until(lambda: worker.processed == 1, TIMEOUT, what='the held step to end')
    assert errors == []
    assert worker.close(timeout=TIMEOUT)


def test_frame_age_is_counted_from_the_items_arrival_while_it_is_processed(closing):
    # The item waits in the slot while the one before it is processed: its age, read by the
    # step, includes that wait (not the item's own stamps: it has none here).
    clock = FakeClock()
    ages = []
    hold = Recorder()
    worker = None

    def step(item):
        hold(item)
        ages.append((item, worker.frame_age()))
    worker = LatestFrameWorker(step, clock=clock)
    closing(worker)
    assert worker.frame_age() is None  # between items
    hold.release.clear()
    worker.offer('first')
    assert hold.started.wait(TIMEOUT)
    clock.t += 0.2
    worker.offer('second')  # arrives 0.2 s after the first
    clock.t += 0.3
    hold.release.set()
    wait_until(lambda: len(ages) == 2, TIMEOUT, what='both items')
    assert ages == [('first', pytest.approx(0.5)), ('second', pytest.approx(0.3))]
    wait_until(lambda: worker.frame_age() is None, TIMEOUT, what='no item in progress')
