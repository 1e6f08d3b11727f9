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

"""The subscriber's received-stream statistics: the gaps its summary line reports."""

from fake_clock import FakeClock
from py_vision.stats import gap_worth_saying, StreamStats


def stats_over(clock, arrivals, window_s=1.0):
    stats = StreamStats(window_s=window_s, clock=clock.now)
    for at in arrivals:
        clock.sleep(at - clock.now())
        stats.add(0.005, 640, 480, 'bgr8')
    return stats


def test_a_gap_is_said_when_the_first_frame_after_it_is_alone_in_the_window():
    # 20 fps, an outage of 2.9 s, and the summary comes just after the first frame back: the
    # window holds that frame only, so there is no rate to judge the gap by.
    clock = FakeClock()
    before = [1010.0 + i / 20 for i in range(20)]
    stats = stats_over(clock, before + [before[-1] + 2.9])
    clock.sleep(0.1)
    snapshot = stats.snapshot()
    assert snapshot['recent_frames'] == 1 and snapshot['fps'] == 0
    assert gap_worth_saying(snapshot) == 2.9


def test_a_steady_stream_has_no_gap_to_say_and_a_short_stall_neither():
    clock = FakeClock()
    steady = [1010.0 + i / 20 for i in range(40)]
    assert gap_worth_saying(stats_over(clock, steady).snapshot()) is None
    clock = FakeClock()
    stalled = steady + [steady[-1] + 0.8 + i / 20 for i in range(20)]   # under a second
    assert gap_worth_saying(stats_over(clock, stalled).snapshot()) is None
    clock = FakeClock()
    # 2 fps measured over a 5 s window: 2.5 s is five periods, not more.
    slow = [1010.0 + i * 0.5 for i in range(10)] + [1014.5 + 2.5]
    assert gap_worth_saying(stats_over(clock, slow, window_s=5.0).snapshot()) is None
