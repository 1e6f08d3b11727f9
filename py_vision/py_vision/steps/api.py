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
What a processing step is, as vision_step (and cv_bridge_test) sees it.

The smallest step is any object with `process(image, header)`: it gets the frame as a bgr8
numpy image (height x width x 3, uint8, the step's to change) and the frame's
std_msgs/Header, and returns the image to publish with that header, or None to publish
nothing for this frame. Everything else is optional; the base class `Step` gives it all:

- PARAMETERS: the step's own parameters (py_vision.params.Spec: typed, with a range or
  choices, `live` when they may change while it runs). The node declares them beside its own,
  so `--help`, `ros2 param describe` and `ros2 param set` show and take them like the node's.
- start(context): called once, before the first frame, with a StepContext: the node (to
  create publishers and timers), the logger, the parameters' start-up values, `threads`, the
  shipped models' paths, and `frame_age()`. A step loads its models here. It returns nothing,
  or a short note for the node's start-up line (say, the runtime and model files).
- parameters_changed(changes): a live parameter was set (name -> checked value); return None to
  accept, or why the change is refused.
- frame_failed(header, error): process() raised on this frame (or returned something that is
  not a bgr8 image or None). Called on the worker thread, right after; a step that drives
  something stops it here (hand_signs sends a zero command).
- stopping(): the node has been told to stop (a signal, the end of a launch), called at once,
  from the thread that stops the node, before the frame under way has ended: process() may
  still be running on the worker thread, but nothing it publishes through the context's
  publishers goes out any more. A step that drives something stops it here (hand_signs: its
  zero command); what it publishes here is its last word.
- close(): the node is stopping, after stopping(). By then process() is never called again:
  the one under way has returned, or (after STOP_GRACE_S) it is abandoned. A step releases what
  it holds here; what it publishes through the context's publishers still goes out. The node
  then waits (up to DELIVERY_TIMEOUT_S) until every reliable subscriber has acknowledged what
  stopping() and close() sent, before its publishers are destroyed.

process() runs on the node's worker thread, one frame at a time; parameters_changed(), the
timers (StepContext.create_timer) and the subscriptions' callbacks
(StepContext.create_subscription) run on the executor's; stopping() and close() on the
thread that stops the node. A process() that raises is logged
and counted, frame_failed() is called, and the next frame is tried.

Time inside models: the runtimes of py_vision.models time each model run on the thread that
runs it (py_vision.models.model_time); `models_clock()` is that thread's total, which
vision_step reads around each frame to split its processing time into the models' and the
rest. A step running a model some other way counts it with `model_time.timing()`.
"""

from dataclasses import dataclass
from typing import Any, Callable, ClassVar, Dict, Optional, Protocol, Sequence, Tuple

import numpy as np
from py_vision.models.model_time import thread_model_time
from py_vision.params import Spec

__all__ = ['DELIVERY_TIMEOUT_S', 'models_clock', 'ProcessesFrames', 'Step', 'StepContext',
           'STOP_GRACE_S']


class ProcessesFrames(Protocol):
    """The smallest step: process(image, header) -> the image to publish, or None."""

    def process(self, image: np.ndarray, header: Any) -> Optional[np.ndarray]:
        """Process one bgr8 frame; return the bgr8 image to publish, or None."""
        ...


def shipped_model_path(name: str) -> str:
    """Return the path of a model shipped in py_vision's share folder (ModelError: missing)."""
    from py_vision.models.files import shipped_model  # the models only when a step asks
    return shipped_model(name)


def models_clock() -> Tuple[float, float]:
    """Return the seconds the calling thread has spent inside models so far: (wall, CPU)."""
    total = thread_model_time()
    return total.seconds, total.cpu_seconds


# How long the node waits at stop for process() to return before it abandons it, and then for
# reliable subscribers to acknowledge what the step published last (vision_step.close()).
STOP_GRACE_S = 1.0
DELIVERY_TIMEOUT_S = 1.0


def _no_age() -> Optional[float]:
    return None


def _own_publisher(node, msg_type, topic: str, depth: int):
    return node.create_publisher(msg_type, topic, depth)


@dataclass
class StepContext:
    """
    What a step is given once, at start: the node and what it knows.

    frame_age(), called from process(), returns the seconds since the frame being processed
    arrived on this host (from its arrival, not its header's stamp: the camera may be another
    machine with another clock), or None where that is not known.
    """

    node: Any                          # the rclpy Node running the step
    logger: Any                        # the node's logger
    parameters: Dict[str, Any]         # the step's parameters' start-up values (PARAMETERS)
    threads: int = 1                   # the CPU threads a model may use
    cancelled: Callable[[], bool] = lambda: False  # True once the node is stopping
    model_path: Callable[[str], str] = shipped_model_path  # a shipped model's path
    frame_age: Callable[[], Optional[float]] = _no_age  # see above
    # How the node makes the step's publishers (vision_step: ones whose messages from an
    # abandoned process() are dropped, and whose last messages are waited for at stop).
    publisher_factory: Callable[..., Any] = _own_publisher
    # True while what process() returns goes anywhere (its image topic has a subscriber, or
    # the node shows it): a step may leave out drawing on the image while it is False.
    output_wanted: Callable[[], bool] = lambda: True

    def create_publisher(self, msg_type, topic: str, depth: int = 10):
        """Create a publisher of the node (reliable, keep-last depth)."""
        return self.publisher_factory(self.node, msg_type, topic, depth)

    def create_subscription(self, msg_type, topic: str, callback: Callable[[Any], None], qos):
        """Subscribe to topic on the node; callback gets each message on the executor's thread."""
        return self.node.create_subscription(msg_type, topic, callback, qos)

    def create_timer(self, period_s: float, callback: Callable[[], None]):
        """
        Call callback every period_s seconds of steady time, on the executor's thread.

        Steady: a simulated or adjusted ROS clock does not change it. What the callback shares
        with process() (another thread) needs a lock.
        """
        from rclpy.clock import Clock, ClockType  # a step made without ROS never gets here
        return self.node.create_timer(period_s, callback,
                                      clock=Clock(clock_type=ClockType.STEADY_TIME))


class Step:
    """A base class for steps: the optional parts of the API, each doing nothing."""

    PARAMETERS: ClassVar[Sequence[Spec]] = ()

    def start(self, context: StepContext) -> Optional[str]:
        """Get ready (load models, create publishers); return a note for the start-up line."""
        return None

    def process(self, image: np.ndarray, header: Any) -> Optional[np.ndarray]:
        """Process one bgr8 frame; return the bgr8 image to publish, or None."""
        raise NotImplementedError('%s does not define process()' % type(self).__name__)

    def parameters_changed(self, changes: Dict[str, Any]) -> Optional[str]:
        """Take changed live parameters (name -> value); return None, or why they are refused."""
        return None

    def frame_failed(self, header: Any, error: Exception) -> None:
        """React to process() failing on the frame with this header (worker thread)."""

    def stopping(self) -> None:
        """Stop what the step drives, at once; process() may still be running (see above)."""

    def close(self) -> None:
        """Release what the step holds, publish its last messages; the node is stopping."""


def step_parameters(step_class: type) -> Tuple[Spec, ...]:
    """Return the parameters a step class declares (none for a plain object with process)."""
    return tuple(getattr(step_class, 'PARAMETERS', ()))
