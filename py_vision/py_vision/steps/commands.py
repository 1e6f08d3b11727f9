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
Velocity commands a step sends to a robot, made to fail safe: `CommandGate` and its watchdog.

A step that drives a robot (hand_signs) decides a command for every frame it processes. What
it sees can flicker from one frame to the next, and frames can stop coming, come late, or make
the step fail. The gate stands between the step and its command publisher:

- **Hold.** A command that moves the robot goes out only once the same *reason* (hand_signs:
  the sign) has been seen on `hold_frames` processed frames in a row, spanning at least
  `hold_time` seconds of their arrivals; until then, and whenever the reason changes, a zero
  command goes out instead: a robot moving on one reason always gets a zero before it moves on
  another, even with hold_frames 1, and before any reversal. A zero goes out at once.
- **Limits.** A moving command is capped to the base's speeds (`Limits`) and ramped up by at
  most the acceleration limit times the time since the last command went out; slowing down and
  stopping are never ramped.
- **Stale frames.** A frame that arrived on this host more than `max_frame_age` seconds ago by
  the time its command is decided (from its arrival, not its header's stamp: the camera may be
  another machine with another clock) stops the robot instead of steering it.
- **Enable.** With an enable input (`enable_timeout` set), the robot moves only while the last
  `enable(True)` is younger than enable_timeout; `enable(False)` or its expiry stops it, and
  frames send nothing until it is enabled again (another input may drive meanwhile).
- **Watchdog.** When no frame has given a command for `command_timeout` seconds, when the step
  fails on a frame (`frame_failed()`), when a frame is stale, when the enable lapses and when
  the step stops (`stop()`), the gate sends a zero of its own, then nothing until fresh frames
  give commands again: a twist_mux or a joystick can take over meanwhile. After it, a moving
  command needs a sign held anew. The deadlines are kept by `watch()`, the gate's own thread
  (`Watchdog`), on the monotonic clock: no executor, no ROS time, no other callback delays it;
  a frame that finds a deadline passed (the thread late) stops the robot first too.
- **A command rate.** With `command_rate`, the last frame's command goes out again that many
  times a second until the next frame's (or the watchdog's stop): a base whose own timeout is
  shorter than the time between two processed frames keeps its command, for no longer than
  command_timeout.
- **Every stop reaches every reader.** Each stop (the gate's own zero, or a frame's zero after a
  moving command) goes out `stop_repeats` times, `stop_repeat_period` apart, then nothing: a
  best-effort reader that loses one copy gets the next. A moving command cancels the copies
  still to come.
- **Stop.** `stop()` closes the gate and sends the last zero (its copies included, at once in
  the calling thread) when a command went out since the gate's last zero: nothing is sent after
  it, even by a frame whose processing is under way.

The gate is thread-safe (frames come from the node's worker thread, the enable input from its
executor, deadlines from the watchdog's thread, the stop from the main thread): every decision
and the sending it leads to happen under one lock, so the commands go out in the order they
were decided. No ROS here: the step gives it `send`.
"""

from dataclasses import dataclass, field, replace
import math
import threading
import time
from typing import Callable, Hashable, NamedTuple, Optional

__all__ = ['CommandGate', 'DISABLED', 'FAILED', 'FRAME', 'GateSettings', 'HELD_BACK', 'Limits',
           'REPEAT', 'RESENT', 'STALE', 'STOP', 'STOPPED', 'TIMEOUT', 'Velocity', 'WATCH_RETRY_S',
           'Watchdog']

# Why a command went out (what `send` is told, and what `frame()` returns).
FRAME = 'frame'          # the frame's own command (moving: held long enough; or a zero)
HELD_BACK = 'held back'  # a zero instead of a moving command not yet held long enough
STALE = 'stale'          # a zero instead of the command of a frame older than max_frame_age
TIMEOUT = 'timeout'      # the gate's zero: no frame gave a command for command_timeout
FAILED = 'failed'        # the gate's zero: the step failed on a frame
DISABLED = 'disabled'    # the gate's zero: the enable input said false or lapsed
STOPPED = 'stopped'      # the gate's zero: the step is stopping; nothing is sent after it
REPEAT = 'repeat'        # another copy of the last stop's zero
RESENT = 'resent'        # the last frame's command again (command_rate), until the next
NOTHING = None           # nothing sent
# Times are sums of float seconds: a sign held hold_time to the microsecond has held it.
_CLOCK_SLACK_S = 1e-6
# How soon the watchdog tries again after a send raised or was dropped.
WATCH_RETRY_S = 0.1


class Velocity(NamedTuple):
    """A velocity command: forward (m/s, Twist linear.x) and turn left (rad/s, angular.z)."""

    linear: float = 0.0
    angular: float = 0.0


STOP = Velocity()


def _limited(previous: float, wanted: float, cap: float, accel: float, dt: float) -> float:
    """Return wanted capped to +-cap and, away from zero, at most accel * dt past previous."""
    wanted = max(-cap, min(cap, wanted))
    if accel <= 0.0 or wanted == 0.0:
        return wanted
    if previous * wanted < 0.0:
        previous = 0.0  # a reversal ramps up from standing still
    if abs(wanted) <= abs(previous):
        return wanted   # slowing down: at once
    return math.copysign(min(abs(wanted), abs(previous) + accel * dt), wanted)


@dataclass(frozen=True)
class Limits:
    """What the base may be asked: speed caps, and acceleration limits (0: none) per second."""

    max_linear: float = math.inf    # m/s
    max_angular: float = math.inf   # rad/s
    linear_accel: float = 0.0       # m/s^2
    angular_accel: float = 0.0      # rad/s^2

    def apply(self, previous: Velocity, wanted: Velocity, dt: float) -> Velocity:
        """Return wanted within the caps, ramped from previous (sent dt seconds ago)."""
        return Velocity(
            _limited(previous.linear, wanted.linear, self.max_linear, self.linear_accel, dt),
            _limited(previous.angular, wanted.angular, self.max_angular, self.angular_accel,
                     dt))


@dataclass(frozen=True)
class GateSettings:
    """How a CommandGate decides; hold_*, max_frame_age and limits may change while it runs."""

    hold_frames: int = 3              # frames a reason must hold in a row before it moves
    hold_time: float = 0.0            # seconds those frames' arrivals must span
    command_timeout: float = 0.5      # seconds without a frame's command: one stop
    max_frame_age: float = 0.5        # seconds since a frame arrived: too old to steer
    stop_repeats: int = 3             # copies of each stop's zero
    stop_repeat_period: float = 0.05  # seconds between them
    command_rate: float = 0.0         # the last frame's command again, this often (0: never)
    enable_timeout: Optional[float] = None  # the enable input's lifetime; None: no input
    limits: Limits = field(default_factory=Limits)


# send(command, why) publishes one command; it returns False when the command was not sent
# (the node is stopping and drops what a frame under way publishes).
Send = Callable[[Velocity, str], Optional[bool]]


class CommandGate:
    """
    Between a robot-driving step and its publisher: hold, limits, stale frames, enable, stops.

    send(command, why) publishes one Velocity; `why` is FRAME, HELD_BACK, STALE, RESENT,
    TIMEOUT, FAILED, DISABLED, STOPPED or REPEAT. When it returns False the command counts as
    not sent, so that the gate's last zero still goes out at stop(). `clock` is monotonic
    seconds and `sleep` waits (time.monotonic and time.sleep; a FakeClock in tests).
    """

    def __init__(self, send: Send, settings: GateSettings = GateSettings(),
                 clock: Callable[[], float] = time.monotonic,
                 sleep: Callable[[float], None] = time.sleep):
        self._send = send
        self.settings = settings
        self.clock = clock
        self.sleep = sleep
        self._changed = threading.Condition(threading.Lock())  # wakes the watchdog
        self._reason: Optional[Hashable] = None  # what the last fresh frames agreed on
        self._held = 0                           # for how many frames in a row
        self._held_since = 0.0                   # from the first of them's arrival
        self._armed = False      # a command from a frame went out since the gate's last zero
        self._last = STOP        # the last command sent
        self._last_sent_at: Optional[float] = None
        self._last_frame_at: Optional[float] = None  # when the last frame was decided on
        self._last_command_at = 0.0              # the last frame's command
        self._wanted = STOP                      # what it asked for, before the ramp
        self._resend_at = 0.0                    # when it goes out again (command_rate)
        self._copies_left = 0                    # copies of the last stop still to send
        self._next_copy_at = 0.0
        self._enabled_at: Optional[float] = None  # the last enable(True)
        self._enabled = False                     # what the gate last took the input to say
        self._closed = False
        self.zeros_sent = 0      # the gate's own zeros (TIMEOUT, FAILED, STALE, DISABLED, STOPPED)

    @property
    def closed(self) -> bool:
        """Return True once stop() was called: nothing is sent any more."""
        return self._closed

    def configure(self, **changes) -> None:
        """Change settings (GateSettings' names) while it runs: the next decision uses them."""
        with self._changed:
            self.settings = replace(self.settings, **changes)
            self._changed.notify()

    def frame(self, reason: Hashable, command: Velocity,
              age: Optional[float] = None) -> Optional[str]:
        """
        Send what a processed frame calls for; return why (FRAME, HELD_BACK, STALE, DISABLED).

        reason: what the command comes from (the sign); command: what the frame would have the
        robot do; age: seconds since the frame arrived on this host (None: not known, not
        checked). DISABLED: nothing was sent (the enable input is off). None is returned once
        the gate is closed: nothing is sent.
        """
        with self._changed:
            if self._closed:
                return NOTHING
            now = self.clock()
            # What the watchdog should have done by now, done first (its thread may be late).
            self._expire(now)
            settings = self.settings
            if not self._enable_holds(now):
                return DISABLED
            previous_frame_at, self._last_frame_at = self._last_frame_at, now
            if age is not None and age > settings.max_frame_age:
                # The world has moved on since this frame: stop, once, and hold again after.
                self._forget()
                if self._armed:
                    self._zero(STALE, now)
                return STALE
            arrived = now - (age or 0.0)
            if reason == self._reason:
                self._held += 1
            else:
                self._reason, self._held, self._held_since = reason, 1, arrived
            why = FRAME
            held = self._held >= settings.hold_frames and (
                settings.hold_time <= 0.0
                or arrived - self._held_since >= settings.hold_time - _CLOCK_SLACK_S)
            moving = self._last != STOP
            reverses = any(new * old < 0.0 for new, old in zip(command, self._last))
            # Not held long enough, a new reason while the robot moves on another, or a
            # reversal: stop first.
            if command != STOP and (not held or (self._held == 1 and moving) or reverses):
                command, why = STOP, HELD_BACK
            wanted = command
            if command != STOP:
                # The ramp's step: the time since the last command, or since the last frame
                # after a quiet spell (a robot standing still starts from one frame's step).
                dt = min([settings.command_timeout] + [now - at for at in (
                    self._last_sent_at, previous_frame_at) if at is not None])
                command = settings.limits.apply(self._last, command, dt)
            if self._send(command, why) is not False:
                self._armed = True
                self._last_command_at = now
                self._wanted = wanted
                self._sent(command, now, stopping=moving and command == STOP)
            return why

    def frame_failed(self) -> bool:
        """Send a stop: the step failed on a frame (unless one went out already); say if."""
        with self._changed:
            self._forget()
            return self._zero_once(FAILED, self.clock())

    def enable(self, enabled: bool) -> None:
        """Take the enable input: True lets frames drive for enable_timeout, False stops."""
        with self._changed:
            if self._closed or self.settings.enable_timeout is None:
                return
            now = self.clock()
            self._enable_holds(now)   # a lapse nobody has seen yet is a stop, first
            self._enabled_at = now if enabled else None
            self._enable_holds(now)
            self._changed.notify()

    def check(self) -> Optional[float]:
        """
        Send what is due (a timeout's or an enable's stop, a stop's copy, a command again).

        Return the seconds until something may next be due, or None when nothing can be before
        the gate changes (the watchdog waits that long).
        """
        with self._changed:
            return self._check(self.clock())

    def watch(self, on_error: Optional[Callable[[Exception], None]] = None) -> None:
        """
        Keep the gate's deadlines until stop() (the watchdog thread's body).

        A send that raises (the node's middleware gone under it) is given to on_error, and
        tried again WATCH_RETRY_S later: the watchdog never ends before the gate is stopped.
        """
        with self._changed:
            while not self._closed:
                try:
                    delay = self._check(self.clock())
                except Exception as error:  # noqa: B902 - whatever send raised
                    if on_error is not None:
                        on_error(error)
                    delay = WATCH_RETRY_S
                self._changed.wait(delay)

    def stop(self) -> bool:
        """
        Close the gate and send the last zero with its copies, in the calling thread.

        Only when a command went out since the gate's last zero; copies of an earlier stop
        still to come are sent too. Return True when the last zero went out.
        """
        with self._changed:
            if self._closed:
                return False
            self._closed = True
            self._changed.notify()
            copies, sent = self._copies_left, False
            if self._armed and self._send(STOP, STOPPED) is not False:
                self.zeros_sent += 1
                self._armed, sent = False, True
                copies = self.settings.stop_repeats - 1
            self._copies_left = 0
            period = self.settings.stop_repeat_period
        # Closed: nothing else sends any more, so the copies keep their place without the lock.
        for _ in range(copies):
            self.sleep(period)
            self._send(STOP, REPEAT)
        return sent

    def _expire(self, now: float) -> None:
        """Stop the robot when the enable input lapsed or no frame gave a command in time."""
        if self.settings.enable_timeout is not None:
            self._enable_holds(now)
        if self._armed and now >= self._last_command_at + self.settings.command_timeout:
            self._forget()
            self._zero_once(TIMEOUT, now)

    def _check(self, now: float) -> Optional[float]:
        if self._closed:
            return None
        settings = self.settings
        self._expire(now)
        waits = []
        if settings.enable_timeout is not None and self._enabled:
            waits.append(self._enabled_at + settings.enable_timeout - now)
        if self._armed:
            # Still armed past the deadline: its stop was dropped (the node is stopping, and
            # stop() sends it): look again a little later rather than at once, again and again.
            left = self._last_command_at + settings.command_timeout - now
            waits.append(left if left > 0.0 else WATCH_RETRY_S)
        if self._copies_left and now >= self._next_copy_at:
            if self._send(STOP, REPEAT) is not False:
                self._last, self._last_sent_at = STOP, now
            self._copies_left -= 1
            self._next_copy_at = now + settings.stop_repeat_period
        if self._copies_left:
            waits.append(self._next_copy_at - now)
        elif self._armed and settings.command_rate > 0.0:
            if now >= self._resend_at:
                self._resend(now)
            waits.append(self._resend_at - now)
        return max(0.0, min(waits)) if waits else None

    def _resend(self, now: float) -> None:
        """Send the last frame's command again (ramped on), command_rate times a second."""
        command = self._wanted
        if command != STOP:
            dt = min(now - self._last_sent_at, self.settings.command_timeout)
            command = self.settings.limits.apply(self._last, command, dt)
        self._resend_at = now + 1.0 / self.settings.command_rate
        if self._send(command, RESENT) is not False:
            self._last, self._last_sent_at = command, now

    def _enable_holds(self, now: float) -> bool:
        """Return whether frames may drive; stop once when the enable input went off or lapsed."""
        timeout = self.settings.enable_timeout
        if timeout is None:
            return True
        enabled = self._enabled_at is not None and now < self._enabled_at + timeout
        if self._enabled and not enabled:
            self._forget()   # moving again needs a sign held anew
            self._zero_once(DISABLED, now)
        self._enabled = enabled
        return enabled

    def _forget(self) -> None:
        """Forget the sign being held: a moving command needs it held anew."""
        self._reason, self._held = None, 0

    def _zero_once(self, why: str, now: float) -> bool:
        if self._closed or not self._armed:
            return False
        return self._zero(why, now)

    def _zero(self, why: str, now: float) -> bool:
        """Send the gate's own zero; once sent, it is armed again only by a frame's command."""
        if self._send(STOP, why) is False:
            return False  # dropped (the node is stopping): stop() must still send one
        self._armed = False
        self.zeros_sent += 1
        self._sent(STOP, now, stopping=True)
        return True

    def _sent(self, command: Velocity, now: float, stopping: bool) -> None:
        """Record a command sent; a stop schedules its copies, a moving command cancels them."""
        self._last, self._last_sent_at = command, now
        if self.settings.command_rate > 0.0:
            self._resend_at = now + 1.0 / self.settings.command_rate
        if stopping:
            self._copies_left = self.settings.stop_repeats - 1
            self._next_copy_at = now + self.settings.stop_repeat_period
        elif command != STOP:
            self._copies_left = 0
        self._changed.notify()  # the watchdog's next deadline may have changed


class Watchdog:
    """The gate's own thread: keeps its deadlines (gate.watch()) until the gate is stopped."""

    def __init__(self, gate: CommandGate, on_error: Optional[Callable[[Exception], None]] = None,
                 name: str = 'command_watchdog'):
        self._thread = threading.Thread(target=gate.watch, args=(on_error,), name=name,
                                        daemon=True)
        self._thread.start()

    def join(self, timeout: float = 1.0) -> bool:
        """Wait for the thread to end (after gate.stop()); return True if it did."""
        self._thread.join(timeout)
        return not self._thread.is_alive()
