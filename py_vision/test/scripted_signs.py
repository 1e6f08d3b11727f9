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

"""hand_signs with a scripted tracker, for test_command_safety: the frame says what happens."""

import threading
import time

from hand_poses import FOLDED, place, pose, THUMB_ACROSS, thumb_up
from py_vision.models.hands import Hand
from py_vision.steps.hand_signs import HandSigns

HANDS = {1: thumb_up(), 2: place(pose((FOLDED,) * 4, THUMB_ACROSS)), 3: thumb_up()}
SCORES = {3: 0.3}  # a thumbs-up the model is not sure of


class Scripted:
    """A tracker reading the frame's first pixel: blue the hand, green what to do."""

    def __init__(self, closing, cancelled):
        self.closing = closing
        self.cancelled = cancelled

    def find(self, image):
        hand, action = int(image[0, 0, 0]), int(image[0, 0, 1])
        if action == 1:
            raise RuntimeError('the model failed on this frame')
        if action == 2:
            print('blocking in process()', flush=True)
            self.closing.wait(20)
        if action == 3:
            time.sleep(1.0)
        if action == 4:
            print('processing until the stop begins', flush=True)
            began = time.monotonic()
            while not self.cancelled() and time.monotonic() - began < 20:
                time.sleep(0.01)
            time.sleep(max(0.0, 0.5 - (time.monotonic() - began)))
        return [Hand(HANDS[hand], 'right', SCORES.get(hand, 0.9))] if hand in HANDS else []


class ScriptedSigns(HandSigns):
    """hand_signs with the scripted tracker and hooks that block or report when asked."""

    def start(self, context):
        note = super().start(context)
        self.closing = threading.Event()
        self.blocked = False
        self.tracker = Scripted(self.closing, context.cancelled)
        return note

    def parameters_changed(self, changes):
        # hold_time 7.5 holds the executor's thread 10 s, once (a slow callback of the node).
        if changes.get('hold_time') == 7.5 and not self.blocked:
            self.blocked = True
            print('blocking the executor', flush=True)
            time.sleep(10.0)
            print('the executor is free again', flush=True)
        return super().parameters_changed(changes)

    def stopping(self):
        super().stopping()
        print('the stop is sent', flush=True)

    def close(self):
        super().close()
        # The frame being processed ends just after the step's last word: the worst moment.
        self.closing.set()
