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
Commands a step sends to a robot, made to fail safe: `CommandGate`.

A step that drives a robot (hand_signs) decides a command for every frame it processes. What
it sees can flicker from one frame to the next, and frames can stop coming, come late, or make
the step fail. The gate stands between the step and its command publisher:

- **Hold.** A command that moves the robot goes out only once the same *reason* (hand_signs:
  the sign) has been seen on `hold_frames` processed frames in a row; until then, and whenever
  the reason changes, a zero command goes out instead: a robot moving on one reason always
  gets a zero before it moves on another, even with hold_frames 1. A zero goes out at once.
- **Stale frames.** A frame that arrived on this host more than `max_frame_age` seconds ago by
  the time its command is decided (measured from its arrival, not from its header's stamp: the
  camera may be another machine with another clock) stops the robot instead of steering it.
- **Watchdog.** When no frame has given a command for `command_timeout` seconds (`check()`,
  called from a timer), when the step fails on a frame (`frame_failed()`), when a frame is
  stale, and when the step stops (`stop()`), the gate sends one zero command of its own, then
  nothing until fresh frames give commands again: a twist_mux or a joystick can take over
  meanwhile. After it, a moving command needs `hold_frames` fresh frames again.
- **Stop.** `stop()` sends that zero command (if any command went out since the last one) and
  closes the gate: nothing is sent after it, even by a frame whose processing was under way.

The gate is thread-safe (frames come from the node's worker thread, the timer and the stop
from its executor's): every decision and the sending it leads to happen under one lock, so the
commands go out in the order they were decided. No ROS here: the step gives it `send`.
"""

import threading
import time
from typing import Any, Callable, Hashable, Optional

__all__ = ['CommandGate', 'FRAME', 'HELD_BACK', 'STALE', 'STOPPED', 'TIMEOUT', 'FAILED']

# Why a command went out (what `send` is told, and what `frame()` returns).
FRAME = 'frame'          # the frame's own command (moving: held long enough; or a zero)
HELD_BACK = 'held back'  # a zero instead of a moving command not yet held hold_frames
STALE = 'stale'          # a zero instead of the command of a frame older than max_frame_age
TIMEOUT = 'timeout'      # the gate's zero: no frame gave a command for command_timeout
FAILED = 'failed'        # the gate's zero: the step failed on a frame
STOPPED = 'stopped'      # the gate's zero: the step is stopping; nothing is sent after it
NOTHING = None           # nothing sent


class CommandGate:
    """
    Between a robot-driving step and its publisher: hold, stale frames, watchdog, stop.

    send(command, header, why) publishes one command: `command` is the step's own value (the
    gate only compares it with `zero`), `header` the frame's header (for the gate's own zeros:
    the last frame's, or None before any), `why` one of FRAME, HELD_BACK, STALE, TIMEOUT,
    FAILED, STOPPED. It returns False when the command was not sent (the node is stopping and
    drops what a frame under way publishes): the gate then counts it as not sent, so that its
    last zero still goes out at stop(). `clock` is monotonic seconds (time.monotonic; a
    FakeClock in tests).
    """

    def __init__(self, send: Callable[[Any, Any, str], Optional[bool]], zero: Any,
                 hold_frames: int = 3,
                 command_timeout: float = 0.5, max_frame_age: float = 0.5,
                 clock: Callable[[], float] = time.monotonic):
        self._send = send
        self.zero = zero
        self.hold_frames = hold_frames
        self.command_timeout = command_timeout
        self.max_frame_age = max_frame_age
        self.clock = clock
        self._lock = threading.Lock()
        self._reason: Optional[Hashable] = None  # what the last fresh frames agreed on
        self._held = 0                           # for how many frames in a row
        self._armed = False      # a command from a frame went out since the gate's last zero
        self._moving = False     # the last command sent was not the zero one
        self._last_command_at = 0.0
        self._last_header = None
        self._closed = False
        self.zeros_sent = 0      # the gate's own zeros (TIMEOUT, FAILED, STALE, STOPPED)

    @property
    def closed(self) -> bool:
        """Return True once stop() was called: nothing is sent any more."""
        return self._closed

    def frame(self, reason: Hashable, command: Any, header: Any,
              age: Optional[float] = None) -> Optional[str]:
        """
        Send what a processed frame calls for; return why (FRAME, HELD_BACK, STALE) or None.

        reason: what the command comes from (the sign); command: what the frame would have
        the robot do; age: seconds since the frame arrived on this host (None: not known,
        not checked). None is returned once the gate is closed: nothing is sent.
        """
        with self._lock:
            if self._closed:
                return NOTHING
            self._last_header = header
            if age is not None and age > self.max_frame_age:
                # The world has moved on since this frame: stop, once, and hold again after.
                self._forget()
                if self._armed:
                    self._zero(STALE)
                return STALE
            if reason == self._reason:
                self._held += 1
            else:
                self._reason, self._held = reason, 1
            why = FRAME
            # Not held long enough, or a new reason while the robot moves on another: stop.
            if command != self.zero and (self._held < self.hold_frames
                                         or (self._held == 1 and self._moving)):
                command, why = self.zero, HELD_BACK
            if self._send(command, header, why) is not False:
                self._armed = True
                self._moving = command != self.zero
                self._last_command_at = self.clock()
            return why

    def frame_failed(self) -> bool:
        """Send one zero: the step failed on a frame (unless one went out already); say if."""
        with self._lock:
            self._forget()
            return self._zero_once(FAILED)

    def check(self) -> bool:
        """Send one zero when no frame gave a command for command_timeout s; say if it did."""
        with self._lock:
            if self._armed and self.clock() - self._last_command_at >= self.command_timeout:
                self._forget()
                return self._zero_once(TIMEOUT)
            return False

    def stop(self) -> bool:
        """Send the last zero (when a command went out since the gate's last zero) and close."""
        with self._lock:
            try:
                return self._zero_once(STOPPED)
            finally:
                self._closed = True

    def _forget(self) -> None:
        """Forget the sign being held: a moving command needs hold_frames frames again."""
        self._reason, self._held = None, 0

    def _zero_once(self, why: str) -> bool:
        if self._closed or not self._armed:
            return False
        return self._zero(why)

    def _zero(self, why: str) -> bool:
        """Send the gate's own zero; once sent, it is armed again only by a frame's command."""
        if self._send(self.zero, self._last_header, why) is False:
            return False  # dropped (the node is stopping): stop() must still send one
        self._armed = self._moving = False
        self.zeros_sent += 1
        return True
