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

Commands here are (forward, turn) tuples, (0, 0) the zero one; the reason is the sign. Each
test reads what the gate sent, in order: the command and why.
"""

import threading

from fake_clock import FakeClock
from py_vision.steps.commands import CommandGate, FAILED, FRAME, HELD_BACK, STALE, STOPPED
from py_vision.steps.commands import TIMEOUT
import pytest

ZERO = (0.0, 0.0)
MOTION = {'thumb_up': (1.0, 0.0), 'fist': (-1.0, 0.0), 'point_left': (0.0, 1.0)}


class Recorder:
    """The gate's send: keeps (command, header, why)."""

    def __init__(self):
        self.sent = []

    def __call__(self, command, header, why):
        self.sent.append((command, header, why))

    def commands(self):
        return [command for command, _, _ in self.sent]

    def reasons(self):
        return [why for _, _, why in self.sent]


def gate_and_record(**options):
    clock = FakeClock()
    sent = Recorder()
    return CommandGate(sent, ZERO, clock=clock, **options), sent, clock


def show(gate, signs, header='frame', age=0.01, clock=None, period=0.1):
    """Give the gate one frame per sign, `period` apart; return what each returned."""
    answers = []
    for sign in signs:
        answers.append(gate.frame(sign, MOTION.get(sign, ZERO), header, age))
        if clock is not None:
            clock.t += period
    return answers


def test_a_sign_moves_the_robot_only_once_held_hold_frames():
    gate, sent, _ = gate_and_record(hold_frames=3)
    assert show(gate, ['thumb_up'] * 4) == [HELD_BACK, HELD_BACK, FRAME, FRAME]
    assert sent.commands() == [ZERO, ZERO, (1.0, 0.0), (1.0, 0.0)]


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
    gate.hold_frames = 2  # live
    show(gate, ['point_left', 'point_left'])
    assert sent.commands()[5:] == [ZERO, (0.0, 1.0)]


def test_no_frame_for_command_timeout_sends_one_zero_then_nothing_until_frames_return():
    gate, sent, clock = gate_and_record(hold_frames=2, command_timeout=0.5)
    show(gate, ['thumb_up'] * 2, clock=clock)
    assert sent.commands()[-1] == (1.0, 0.0)
    clock.t += 0.35  # 0.45 s since the last command
    assert not gate.check()
    clock.t += 0.05
    assert gate.check()
    assert sent.sent[-1] == (ZERO, 'frame', TIMEOUT)
    for _ in range(20):  # the camera stays away: nothing more
        clock.t += 0.1
        assert not gate.check()
    assert len(sent.sent) == 3
    # Frames return with the same sign: it must hold again before the robot moves.
    show(gate, ['thumb_up'] * 3, clock=clock)
    assert sent.commands()[3:] == [ZERO, (1.0, 0.0), (1.0, 0.0)]


def test_a_frame_failure_sends_one_zero_and_the_sign_must_hold_again():
    gate, sent, _ = gate_and_record(hold_frames=2)
    show(gate, ['thumb_up'] * 2)
    assert gate.frame_failed()
    assert not gate.frame_failed()  # failing on and on: one zero
    assert sent.sent[2:] == [(ZERO, 'frame', FAILED)]
    show(gate, ['thumb_up'] * 2)
    assert sent.commands()[3:] == [ZERO, (1.0, 0.0)]


def test_a_stale_frame_stops_the_robot_instead_of_steering_it():
    gate, sent, _ = gate_and_record(hold_frames=1, max_frame_age=0.5)
    show(gate, ['thumb_up'])
    # Frames that arrived more than max_frame_age ago: one zero, not their motion.
    assert show(gate, ['fist', 'fist'], age=0.8) == [STALE, STALE]
    assert sent.sent[1:] == [(ZERO, 'frame', STALE)]
    # Fresh again: steering again. An unknown age is not checked.
    show(gate, ['fist'], age=0.1)
    show(gate, ['fist'], age=None)
    assert sent.commands()[2:] == [(-1.0, 0.0), (-1.0, 0.0)]
    gate.max_frame_age = 2.0  # live
    assert show(gate, ['fist'], age=0.8) == [FRAME]


def test_stop_sends_the_last_zero_and_nothing_follows_it():
    gate, sent, clock = gate_and_record(hold_frames=1)
    show(gate, ['thumb_up'], header='last')
    assert gate.stop()
    assert sent.sent[-1] == (ZERO, 'last', STOPPED)
    # A frame whose processing was under way, a failure, the watchdog: nothing goes out.
    assert gate.frame('thumb_up', (1.0, 0.0), 'late', 0.0) is None
    assert not gate.frame_failed()
    clock.t += 10
    assert not gate.check() and not gate.stop()
    assert len(sent.sent) == 2 and gate.closed


def test_no_zero_of_the_gates_own_without_a_command_before_it():
    # Never a frame: nothing to stop. After the watchdog's zero: the stop adds none, so a
    # joystick that took over is not overridden.
    gate, sent, clock = gate_and_record()
    clock.t += 10
    assert not gate.check() and not gate.frame_failed() and not gate.stop()
    assert sent.sent == []
    gate, sent, clock = gate_and_record(command_timeout=0.5)
    show(gate, ['thumb_up'])
    clock.t += 1
    assert gate.check() and not gate.stop()
    assert sent.reasons() == [HELD_BACK, TIMEOUT]
    assert gate.zeros_sent == 1


def test_a_zero_the_stopping_node_dropped_is_sent_again_by_the_stop():
    # The node silences the step's publishers before the frame under way ends; that frame,
    # stale, has its zero dropped (send says False): the stop must still send the last zero.
    sent = Recorder()
    dropping = threading.Event()

    def send(command, header, why):
        if dropping.is_set() and why != STOPPED:
            return False
        sent(command, header, why)
        return True
    gate = CommandGate(send, ZERO, hold_frames=1, max_frame_age=0.5)
    show(gate, ['thumb_up'])
    dropping.set()
    assert show(gate, ['thumb_up'], age=1.0) == [STALE]
    assert not gate.frame_failed()  # dropped too: not counted as sent
    assert gate.stop()
    assert sent.sent == [((1.0, 0.0), 'frame', FRAME), (ZERO, 'frame', STOPPED)]


def test_the_stop_waits_for_a_command_being_sent_and_comes_after_it():
    # A frame's command being sent on the worker thread while the node stops: the gate's lock
    # puts the last zero after it, whatever the threads do.
    sending = threading.Event()
    release = threading.Event()
    sent = []

    def send(command, header, why):
        if why == FRAME:
            sending.set()
            release.wait(10)
        sent.append(why)
    gate = CommandGate(send, ZERO, hold_frames=1)
    worker = threading.Thread(target=gate.frame, args=('thumb_up', (1.0, 0.0), 'h', 0.0))
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
