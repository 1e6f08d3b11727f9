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
CommandGate: what a robot-driving step sends, and when, on a fake clock.

Commands are Velocity (forward, turn) tuples, STOP the zero one; the reason is the sign. Each
test reads what the gate sent, in order: the command and why. Stops go out in copies
(stop_repeats); most tests ask for one copy, so that each stop is one command, and the tests of
the copies ask for three.
"""

import threading
import time

from fake_clock import FakeClock
from py_vision.steps.commands import CommandGate, DISABLED, FAILED, FRAME, GateSettings
from py_vision.steps.commands import HELD_BACK, Limits, REPEAT, RESENT, STALE, STOP, STOPPED
from py_vision.steps.commands import TIMEOUT, Velocity, WATCH_RETRY_S, Watchdog
import pytest

ZERO = (0.0, 0.0)
MOTION = {'thumb_up': (1.0, 0.0), 'fist': (-1.0, 0.0), 'point_left': (0.0, 1.0)}


class Recorder:
    """The gate's send: keeps (command, why)."""

    def __init__(self):
        self.sent = []

    def __call__(self, command, why):
        self.sent.append((tuple(command), why))

    def commands(self):
        return [command for command, _ in self.sent]

    def reasons(self):
        return [why for _, why in self.sent]


def gate_and_record(**options):
    """Return a gate (one copy of each stop unless said), what it sends, and its clock."""
    clock = FakeClock()
    sent = Recorder()
    options.setdefault('stop_repeats', 1)
    return CommandGate(sent, GateSettings(**options), clock=clock, sleep=clock.sleep), sent, clock


def show(gate, signs, age=0.01, clock=None, period=0.1):
    """Give the gate one frame per sign, `period` apart; return what each returned."""
    answers = []
    for sign in signs:
        answers.append(gate.frame(sign, Velocity(*MOTION.get(sign, ZERO)), age))
        if clock is not None:
            clock.t += period
    return answers


def test_a_sign_moves_the_robot_only_once_held_hold_frames():
    gate, sent, _ = gate_and_record(hold_frames=3)
    assert show(gate, ['thumb_up'] * 4) == [HELD_BACK, HELD_BACK, FRAME, FRAME]
    assert sent.commands() == [ZERO, ZERO, (1.0, 0.0), (1.0, 0.0)]


def test_a_sign_moves_the_robot_only_once_held_hold_time_whatever_the_frame_rate():
    # At 50 frames a second, 3 frames are 40 ms of a sign: a misread that short never moves
    # the robot; 0.2 s of it does (its frames' arrivals, not when they are processed).
    gate, sent, clock = gate_and_record(hold_frames=3, hold_time=0.2)
    show(gate, ['thumb_up'] * 10, clock=clock, period=0.02)
    assert sent.commands() == [ZERO] * 10
    show(gate, ['thumb_up'], clock=clock)
    assert sent.commands()[-1] == (1.0, 0.0)
    # A frame that arrived long ago (its age) counts from its arrival.
    gate, sent, clock = gate_and_record(hold_frames=2, hold_time=0.2)
    gate.frame('thumb_up', Velocity(1.0, 0.0), age=0.01)
    clock.t += 0.3
    gate.frame('thumb_up', Velocity(1.0, 0.0), age=0.2)   # arrived 0.09 s after the first
    assert sent.commands() == [ZERO, ZERO]


def test_a_flickering_sign_never_reverses_the_robot_from_one_frame_to_the_next():
    gate, sent, _ = gate_and_record(hold_frames=3)
    # Forward, one frame of fist among the thumbs-up, forward again.
    show(gate, ['thumb_up'] * 4 + ['fist'] + ['thumb_up'] * 4)
    assert sent.commands() == [ZERO, ZERO, (1.0, 0.0), (1.0, 0.0),
                               ZERO,                           # the change stops it first
                               ZERO, ZERO, (1.0, 0.0), (1.0, 0.0)]
    assert (-1.0, 0.0) not in sent.commands()
    # Alternating every frame: the robot never moves.
    gate, sent, _ = gate_and_record(hold_frames=3)
    show(gate, ['thumb_up', 'fist'] * 5)
    assert set(sent.commands()) == {ZERO}


@pytest.mark.parametrize('stop_sign', ['no_hand', 'open_hand', 'unknown'])
def test_a_sign_without_a_motion_stops_the_robot_at_once(stop_sign):
    gate, sent, _ = gate_and_record(hold_frames=3)
    show(gate, ['thumb_up'] * 3 + [stop_sign] + ['thumb_up'])
    assert sent.commands() == [ZERO, ZERO, (1.0, 0.0), ZERO, ZERO]
    assert sent.reasons()[3] == FRAME


def test_hold_frames_1_moves_at_the_first_frame_but_stops_before_another_sign():
    gate, sent, _ = gate_and_record(hold_frames=1)
    show(gate, ['fist', 'thumb_up', 'thumb_up'])
    # Backward, then a zero before forward: never a reversal from one frame to the next.
    assert sent.commands() == [(-1.0, 0.0), ZERO, (1.0, 0.0)]
    assert sent.reasons()[1] == HELD_BACK
    show(gate, ['no_hand', 'fist'])  # stopped already: the new sign moves at once
    assert sent.commands()[3:] == [ZERO, (-1.0, 0.0)]
    gate.configure(hold_frames=2)  # live
    show(gate, ['point_left', 'point_left'])
    assert sent.commands()[5:] == [ZERO, (0.0, 1.0)]


def test_speeds_are_capped_for_the_base():
    gate, sent, _ = gate_and_record(hold_frames=1, limits=Limits(max_linear=0.3,
                                                                 max_angular=0.5))
    gate.frame('thumb_up', Velocity(1.0, 0.0))
    gate.frame('no_hand', STOP)
    gate.frame('point_left', Velocity(0.0, 2.0))
    gate.frame('no_hand', STOP)
    gate.frame('fist', Velocity(-1.0, 0.0))
    assert sent.commands() == [(0.3, 0.0), ZERO, (0.0, 0.5), ZERO, (-0.3, 0.0)]


def test_a_moving_command_ramps_up_at_the_acceleration_limit_and_stops_at_once():
    # 0.5 m/s^2, commands 0.1 s apart: +0.05 m/s a command up to 0.2; the stop is immediate.
    gate, sent, clock = gate_and_record(hold_frames=1, limits=Limits(linear_accel=0.5,
                                                                     angular_accel=2.0))
    show(gate, ['no_hand'], clock=clock)
    show(gate, ['thumb_up'] * 6, clock=clock)
    forward = [round(linear, 6) for linear, _ in sent.commands()[1:]]
    assert forward == [0.05, 0.1, 0.15, 0.2, 0.25, 0.3]
    gate.frame('thumb_up', Velocity(0.2, 0.0))     # slower, at once (linear_speed lowered)
    gate.frame('no_hand', STOP)
    assert sent.commands()[-2:] == [(0.2, 0.0), ZERO]
    # After a quiet spell (the watchdog's stop first), a turn ramps from zero by one frame's
    # step, not by the whole quiet time.
    clock.t += 30.0
    gate.frame('point_left', Velocity(0.0, 3.0))
    clock.t += 0.1
    gate.frame('point_left', Velocity(0.0, 3.0))
    assert sent.sent[-3:] == [(ZERO, TIMEOUT), (ZERO, FRAME), ((0.0, pytest.approx(0.2)), FRAME)]


def test_a_reversal_is_never_sent_without_a_zero_first():
    # One reason whose command changes sign (a step's own): a zero in between, as for a change
    # of reason.
    gate, sent, _ = gate_and_record(hold_frames=1)
    gate.frame('steer', Velocity(0.5, 0.2))
    gate.frame('steer', Velocity(0.5, -0.2))
    gate.frame('steer', Velocity(0.5, -0.2))
    assert sent.commands() == [(0.5, 0.2), ZERO, (0.5, -0.2)]


def test_no_frame_for_command_timeout_sends_one_zero_then_nothing_until_frames_return():
    gate, sent, clock = gate_and_record(hold_frames=2, command_timeout=0.5)
    show(gate, ['thumb_up'] * 2, clock=clock)
    assert sent.commands()[-1] == (1.0, 0.0)
    clock.t += 0.35  # 0.45 s since the last command
    assert gate.check() == pytest.approx(0.05)   # the watchdog's next look
    clock.t += 0.05
    assert gate.check() is None                  # sent; nothing due until frames return
    assert sent.sent[-1] == (ZERO, TIMEOUT)
    for _ in range(20):  # the camera stays away: nothing more
        clock.t += 0.1
        assert gate.check() is None
    assert len(sent.sent) == 3
    # Frames return with the same sign: it must hold again before the robot moves.
    show(gate, ['thumb_up'] * 3, clock=clock)
    assert sent.commands()[3:] == [ZERO, (1.0, 0.0), (1.0, 0.0)]


def test_a_frame_failure_sends_one_zero_and_the_sign_must_hold_again():
    gate, sent, _ = gate_and_record(hold_frames=2)
    show(gate, ['thumb_up'] * 2)
    assert gate.frame_failed()
    assert not gate.frame_failed()  # failing on and on: one zero
    assert sent.sent[2:] == [(ZERO, FAILED)]
    show(gate, ['thumb_up'] * 2)
    assert sent.commands()[3:] == [ZERO, (1.0, 0.0)]


def test_a_stale_frame_stops_the_robot_instead_of_steering_it():
    gate, sent, _ = gate_and_record(hold_frames=1, max_frame_age=0.5)
    show(gate, ['thumb_up'])
    # Frames that arrived more than max_frame_age ago: one zero, not their motion.
    assert show(gate, ['fist', 'fist'], age=0.8) == [STALE, STALE]
    assert sent.sent[1:] == [(ZERO, STALE)]
    # Fresh again: steering again. An unknown age is not checked.
    show(gate, ['fist'], age=0.1)
    show(gate, ['fist'], age=None)
    assert sent.commands()[2:] == [(-1.0, 0.0), (-1.0, 0.0)]
    gate.configure(max_frame_age=2.0)  # live
    assert show(gate, ['fist'], age=0.8) == [FRAME]


def test_with_an_enable_input_the_robot_moves_only_while_it_is_fresh_and_true():
    gate, sent, clock = gate_and_record(hold_frames=2, enable_timeout=0.5, command_timeout=60)
    # Never enabled: frames send nothing at all (another input may drive).
    assert show(gate, ['thumb_up'] * 3, clock=clock) == [DISABLED] * 3
    assert sent.sent == []
    gate.enable(True)
    show(gate, ['thumb_up'] * 2, clock=clock)
    assert sent.commands() == [ZERO, (1.0, 0.0)]
    # The input says false: one stop at once, then quiet while frames come.
    gate.enable(False)
    assert sent.sent[-1] == (ZERO, DISABLED)
    assert show(gate, ['thumb_up'] * 3, clock=clock) == [DISABLED] * 3
    assert len(sent.sent) == 3
    # Enabled again: the sign must hold anew before the robot moves.
    gate.enable(True)
    show(gate, ['thumb_up'] * 2, clock=clock)
    assert sent.commands()[3:] == [ZERO, (1.0, 0.0)]
    # The input goes silent: the watchdog stops the robot once it is enable_timeout old.
    assert gate.check() == pytest.approx(0.3)
    clock.t += 0.3
    gate.check()
    assert sent.sent[-1] == (ZERO, DISABLED) and len(sent.sent) == 6
    clock.t += 1.0
    assert gate.check() is None and len(sent.sent) == 6
    # A frame that finds it lapsed before the watchdog did stops it too.
    gate.enable(True)
    show(gate, ['thumb_up'] * 2, clock=clock)
    clock.t += 0.4
    assert gate.frame('thumb_up', Velocity(1.0, 0.0)) == DISABLED
    assert sent.sent[-1] == (ZERO, DISABLED)


def test_a_late_watchdog_changes_nothing_a_frame_or_an_enable_finds_the_deadline_passed():
    # The watchdog's thread may run late (a loaded machine): whatever comes first after a
    # deadline acts on it. An enable that lapsed unseen, then true again: a stop, held anew.
    gate, sent, clock = gate_and_record(hold_frames=3, enable_timeout=0.5, command_timeout=60)
    gate.enable(True)
    show(gate, ['thumb_up'] * 3, clock=clock, period=0.05)
    clock.t += 0.6
    gate.enable(True)
    show(gate, ['thumb_up'], clock=clock)
    assert sent.sent[-2:] == [(ZERO, DISABLED), (ZERO, HELD_BACK)]
    # A frame after command_timeout without one: the watchdog's stop first, held anew.
    gate, sent, clock = gate_and_record(hold_frames=3, command_timeout=0.5)
    show(gate, ['thumb_up'] * 3, clock=clock, period=0.05)
    clock.t += 2.0
    show(gate, ['thumb_up'], clock=clock)
    assert sent.sent[-2:] == [(ZERO, TIMEOUT), (ZERO, HELD_BACK)]


def test_with_a_command_rate_the_last_frames_command_goes_out_again_until_the_timeout():
    # A board processing 2 frames a second, a base that stops after 0.5 s without a command:
    # the command again 10 times a second, ramping on, until the next frame or the timeout.
    gate, sent, clock = gate_and_record(hold_frames=1, command_rate=10.0, command_timeout=1.0,
                                        limits=Limits(linear_accel=1.0))
    show(gate, ['no_hand'], clock=clock, period=0.5)
    gate.frame('thumb_up', Velocity(1.0, 0.0))
    for _ in range(4):
        clock.t += 0.1
        assert gate.check() == pytest.approx(0.1)
    forward = [round(command[0], 6) for command in sent.commands()]
    assert forward == [0.0, 0.5, 0.6, 0.7, 0.8, 0.9]
    assert sent.reasons()[2:] == [RESENT] * 4
    # The timeout, measured from the last frame's command, ends it: the stop, then quiet.
    for _ in range(10):
        clock.t += 0.1
        gate.check()
    assert sent.sent[-1] == (ZERO, TIMEOUT)
    count = len(sent.sent)
    clock.t += 5.0
    assert gate.check() is None and len(sent.sent) == count
    # A frame's zero goes out again too (the input stays alive in a twist_mux), not the
    # gate's own stop's.
    show(gate, ['no_hand'], clock=clock, period=0.1)
    gate.check()
    assert sent.sent[-2:] == [(ZERO, FRAME), (ZERO, RESENT)]


def test_each_stop_goes_out_in_copies_then_nothing():
    gate, sent, clock = gate_and_record(hold_frames=1, command_timeout=0.5, stop_repeats=3,
                                        stop_repeat_period=0.05)
    gate.frame('thumb_up', Velocity(1.0, 0.0))
    clock.t += 0.5
    assert gate.check() == pytest.approx(0.05)
    for _ in range(2):
        clock.t += 0.05
        gate.check()
    clock.t += 1.0
    assert gate.check() is None
    assert sent.sent == [((1.0, 0.0), FRAME), (ZERO, TIMEOUT), (ZERO, REPEAT), (ZERO, REPEAT)]
    # A frame's zero after a moving command is a stop too; a moving command cancels the
    # copies still to come (a new sign held).
    gate, sent, clock = gate_and_record(hold_frames=1, stop_repeats=3)
    show(gate, ['thumb_up', 'no_hand'])
    clock.t += 0.05
    gate.check()
    show(gate, ['fist'])
    clock.t += 0.05
    gate.check()
    assert sent.commands() == [(1.0, 0.0), ZERO, ZERO, (-1.0, 0.0)]


def test_stop_sends_the_last_zero_and_its_copies_and_nothing_follows_it():
    gate, sent, clock = gate_and_record(hold_frames=1, stop_repeats=3,
                                        stop_repeat_period=0.05)
    show(gate, ['thumb_up'])
    slept = clock.slept
    assert gate.stop()
    assert sent.sent[1:] == [(ZERO, STOPPED), (ZERO, REPEAT), (ZERO, REPEAT)]
    assert clock.slept - slept == pytest.approx(0.1)
    # A frame whose processing was under way, a failure, the watchdog: nothing goes out.
    assert gate.frame('thumb_up', Velocity(1.0, 0.0), 0.0) is None
    assert not gate.frame_failed()
    clock.t += 10
    assert gate.check() is None and not gate.stop()
    assert len(sent.sent) == 4 and gate.closed


def test_the_stop_finishes_the_copies_of_a_stop_just_sent():
    gate, sent, clock = gate_and_record(hold_frames=1, stop_repeats=3, command_timeout=0.5)
    show(gate, ['thumb_up'])
    clock.t += 0.5
    gate.check()                  # the watchdog's zero; its copies not yet due
    assert not gate.stop()        # no new zero of its own, but the copies go out
    assert sent.reasons() == [FRAME, TIMEOUT, REPEAT, REPEAT]


def test_no_zero_of_the_gates_own_without_a_command_before_it():
    # Never a frame: nothing to stop. After the watchdog's zero: the stop adds none, so a
    # joystick that took over is not overridden.
    gate, sent, clock = gate_and_record()
    clock.t += 10
    assert gate.check() is None and not gate.frame_failed() and not gate.stop()
    assert sent.sent == []
    gate, sent, clock = gate_and_record(command_timeout=0.5)
    show(gate, ['thumb_up'])
    clock.t += 1
    gate.check()
    assert not gate.stop()
    assert sent.reasons() == [HELD_BACK, TIMEOUT]
    assert gate.zeros_sent == 1


def test_a_zero_the_stopping_node_dropped_is_sent_again_by_the_stop():
    # The node silences the step's publishers before the frame under way ends; that frame,
    # stale, has its zero dropped (send says False): the stop must still send the last zero.
    sent = Recorder()
    dropping = threading.Event()

    def send(command, why):
        if dropping.is_set() and why != STOPPED:
            return False
        sent(command, why)
        return True
    gate = CommandGate(send, GateSettings(hold_frames=1, max_frame_age=0.5, stop_repeats=1))
    show(gate, ['thumb_up'])
    dropping.set()
    assert show(gate, ['thumb_up'], age=1.0) == [STALE]
    assert not gate.frame_failed()  # dropped too: not counted as sent
    assert gate.stop()
    assert sent.sent == [((1.0, 0.0), FRAME), (ZERO, STOPPED)]


def test_the_stop_waits_for_a_command_being_sent_and_comes_after_it():
    # A frame's command being sent on the worker thread while the node stops: the gate's lock
    # puts the last zero after it, whatever the threads do.
    sending = threading.Event()
    release = threading.Event()
    sent = []

    def send(command, why):
        if why == FRAME:
            sending.set()
            release.wait(10)
        sent.append(why)
    gate = CommandGate(send, GateSettings(hold_frames=1, stop_repeats=1))
    worker = threading.Thread(target=gate.frame, args=('thumb_up', Velocity(1.0, 0.0), 0.0))
    worker.start()
    assert sending.wait(10)
    stopper = threading.Thread(target=gate.stop)
    stopper.start()
    stopper.join(0.2)
    assert stopper.is_alive(), 'stop() returned while a command was being sent'
    release.set()
    worker.join(10)
    stopper.join(10)
    assert sent == [FRAME, STOPPED]


class Timed:
    """A send that records when each command went out (the real monotonic clock)."""

    def __init__(self):
        self.sent = []
        self.changed = threading.Condition()

    def __call__(self, command, why):
        with self.changed:
            self.sent.append((time.monotonic(), tuple(command), why))
            self.changed.notify_all()

    def wait_for(self, count, timeout):
        with self.changed:
            return self.changed.wait_for(lambda: len(self.sent) >= count, timeout)


def test_the_watchdog_thread_keeps_the_deadline_on_its_own():
    # Real threads, real clock: the watchdog wakes for the deadline on its own (no executor, no
    # other thread calling check()); its zero and copies come once the timeout has passed. A
    # bound that a watchdog ten times too slow cannot meet, loose enough for a loaded machine.
    sent = Timed()
    gate = CommandGate(sent, GateSettings(hold_frames=1, command_timeout=0.2, stop_repeats=3,
                                          stop_repeat_period=0.05))
    watchdog = Watchdog(gate)
    gate.frame('thumb_up', Velocity(1.0, 0.0))
    assert sent.wait_for(4, timeout=2.0), sent.sent
    (moved, _, _), (zero_at, _, why), *copies = sent.sent
    assert why == TIMEOUT and [c[2] for c in copies] == [REPEAT, REPEAT]
    assert 0.2 <= zero_at - moved < 1.5
    assert copies[0][0] - zero_at >= 0.05
    gate.stop()
    assert watchdog.join(2.0)
    assert len(sent.sent) == 4   # the watchdog's zero was the last word: no stop zero


def test_the_watchdog_thread_outlives_a_send_that_raises():
    # The middleware failing under the watchdog (a context shut down): said, tried again, and
    # the thread goes on until the gate is stopped.
    sent = Timed()
    failures = []

    def send(command, why):
        if why == TIMEOUT and not failures:
            raise RuntimeError('publisher gone')
        sent(command, why)
    gate = CommandGate(send, GateSettings(hold_frames=1, command_timeout=0.1, stop_repeats=1))
    watchdog = Watchdog(gate, on_error=failures.append)
    gate.frame('thumb_up', Velocity(1.0, 0.0))
    assert sent.wait_for(2, timeout=5.0), sent.sent
    assert [type(error) for error in failures] == [RuntimeError]
    assert sent.sent[-1][2] == TIMEOUT
    gate.stop()
    assert watchdog.join(2.0)


def test_a_dropped_stop_is_tried_again_later_not_in_a_spin():
    # The node silencing the step's publishers just before stop(): the watchdog's stop is
    # dropped, and the watchdog looks again WATCH_RETRY_S later, not at once over and over.
    dropping = []

    def send(command, why):
        return not dropping
    clock = FakeClock()
    gate = CommandGate(send, GateSettings(hold_frames=1, command_timeout=0.5), clock=clock,
                       sleep=clock.sleep)
    gate.frame('thumb_up', Velocity(1.0, 0.0))
    dropping.append(True)
    clock.t += 1.0
    assert gate.check() == pytest.approx(WATCH_RETRY_S)
