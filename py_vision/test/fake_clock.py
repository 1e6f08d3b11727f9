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

"""The tests' one clock: time that moves only when a test moves it or something sleeps."""


class FakeClock:
    """
    A stand-in for time.monotonic and time.sleep that never waits.

    It is both shapes py_vision takes a clock in: a callable (`clock()`, as time.monotonic) and
    the capture layer's Clock (`now()`, `sleep()`). Sleeping advances the time at once; a test
    moves it with `clock.t += seconds` (a busy caller) and reads `slept` (how long the code under
    test chose to wait).
    """

    def __init__(self, t: float = 1000.0):
        self.t = t
        self.slept = 0.0

    def __call__(self) -> float:
        return self.t

    def now(self) -> float:
        """Return the time, as time.monotonic() does."""
        return self.t

    def sleep(self, seconds: float) -> None:
        """Advance the time by seconds at once (a negative wait is none)."""
        waited = max(0.0, seconds)
        self.slept += waited
        self.t += waited
