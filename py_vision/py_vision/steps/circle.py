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
The `circle` step: the second tutorial's red filled circle, and cv_bridge_test's step.

A red filled circle at (60, 60), radius 30, on every image wider and taller than 60 pixels.
`simulated_work_ms` adds busy processing time to every frame, to try the pipeline with a slow
step before writing a real one.
"""

import time
from typing import Any, Callable, Dict, Optional

import cv2
import numpy as np
from py_vision.params import Spec
from py_vision.steps.api import Step, StepContext

CIRCLE_CENTER, CIRCLE_RADIUS, CIRCLE_BGR = (60, 60), 30, (0, 0, 255)
MAX_SIMULATED_WORK_MS = 10000.0
# One call of the simulated work: short enough to meet its end time and notice a shutdown
# within a millisecond, long enough that the loop around it costs nothing.
_WORK_CHUNK = np.ones(65536, np.float32)


def simulated_work(seconds: float, cancelled: Callable[[], bool]) -> None:
    """
    Keep one core busy for `seconds` of wall-clock time, or until cancelled() is true.

    numpy computes with the GIL released, as OpenCV and accelerator calls do, so the node's
    other thread keeps taking messages meanwhile, as it would beside real vision code.
    """
    out = np.empty_like(_WORK_CHUNK)
    deadline = time.monotonic() + seconds
    while time.monotonic() < deadline and not cancelled():
        np.sin(_WORK_CHUNK, out=out)


def work_note(milliseconds: float) -> str:
    """Return what the start-up line says of the simulated work ('' when there is none)."""
    return ', simulated work %g ms a frame' % milliseconds if milliseconds else ''


class Circle(Step):
    """A red filled circle on the frame, after simulated_work_ms of busy work."""

    PARAMETERS = (
        Spec('simulated_work_ms', 0.0, 'busy processing time added to every frame, to try '
             'the pipeline with a slow step', (0.0, MAX_SIMULATED_WORK_MS), live=True),
    )

    def __init__(self):
        self.simulated_work_s = 0.0
        self._cancelled: Callable[[], bool] = lambda: False
        self._logger = None

    def start(self, context: StepContext) -> Optional[str]:
        """Take the simulated work's start-up value."""
        self.simulated_work_s = context.parameters['simulated_work_ms'] / 1e3
        self._cancelled = context.cancelled
        self._logger = context.logger
        return None

    def parameters_changed(self, changes: Dict[str, Any]) -> Optional[str]:
        """Take a new simulated_work_ms."""
        milliseconds = changes['simulated_work_ms']
        self.simulated_work_s = milliseconds / 1e3
        self._logger.info('simulated work is now %g ms a frame' % milliseconds)
        return None

    def process(self, image: np.ndarray, header: Any) -> Optional[np.ndarray]:
        """Work for simulated_work_ms, then draw the circle in place (None once cancelled)."""
        if self.simulated_work_s > 0:
            simulated_work(self.simulated_work_s, self._cancelled)
            if self._cancelled():
                return None  # the node is being torn down: drop the frame
        rows, cols = image.shape[:2]
        if cols > 60 and rows > 60:
            cv2.circle(image, CIRCLE_CENTER, CIRCLE_RADIUS, CIRCLE_BGR, -1)
        return image
