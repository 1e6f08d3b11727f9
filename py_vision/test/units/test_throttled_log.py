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


"""ThrottledLog: one line per kind and period, and what it held back counted in the next."""

from fake_clock import FakeClock
from py_vision.throttled_log import ThrottledLog


class Lines:
    """A logger that keeps its lines."""

    def __init__(self):
        self.lines = []

    def warning(self, message):
        self.lines.append(('warning', message))

    def error(self, message):
        self.lines.append(('error', message))


def test_one_line_per_key_and_period_and_the_count_of_those_held_back():
    clock = FakeClock(100.0)
    logger = Lines()
    log = ThrottledLog(logger, period=10.0, clock=clock)
    log.warning('big', 'an image too large')
    log.error('bad', 'a bad request')
    for _ in range(3):
        clock.t += 1.0
        log.warning('big', 'an image too large')
    assert logger.lines == [('warning', 'an image too large'), ('error', 'a bad request')]
    clock.t = 111.0
    log.warning('big', 'an image too large')
    assert logger.lines[-1] == ('warning', 'an image too large (3 more like it in the last 11 s)')
    clock.t = 125.0
    log.warning('big', 'an image too large')
    assert logger.lines[-1] == ('warning', 'an image too large')


def test_warnings_and_errors_through_one_throttled_log_on_an_rclpy_logger():
    # rclpy refuses a call site whose severity changes between calls.
    from rclpy.logging import get_logger
    log = ThrottledLog(get_logger('test_throttled_log'), period=0.0)
    for _ in range(2):
        log.warning('a', 'a warning')
        log.error('b', 'an error')
        log.warning('b', 'a warning of the kind of the error')
