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
A subscription whose messages are taken on a thread of its own, not by the node's executor.

rclpy's executor, each time it wakes, rebuilds its wait set from every entity of the node
(parameter services, timers, guard conditions, the QoS event handlers of every publisher) in
Python; for a stream of frames, that is a large part of what a frame costs
(bench/bench_receive.py). A `ReceiveThread` waits on one subscription alone (and a guard
condition that wakes it when the subscription is replaced or the node closes), takes each
message and calls the subscription's callback there, on its own thread.

The subscription is created in `callback_group`, whose entities the executor never waits on
or runs (its QoS events are not handled either: nobody is told of an incompatible publisher,
as with a handler that does nothing). Its callback runs on the receive thread: what it shares
with the executor's callbacks it must guard. A callback that raises is logged like one of the
executor's (callback_failures), and the next message is taken. How a message is taken may be
given (`take`: a sensor_msgs/Image serialized, read without copying its pixels again); a
message that cannot be taken is one rate-limited warning, and the next is taken.
"""

import threading
import time
from typing import Any, Callable, Optional

from py_vision.callback_failures import CallbackFailures
from py_vision.throttled_log import ThrottledLog
from rclpy.callback_groups import CallbackGroup
from rclpy.exceptions import InvalidHandle
from rclpy.impl.implementation_singleton import rclpy_implementation as _rclpy

__all__ = ['OwnThread', 'ReceiveThread']

# How long the thread waits before it looks again whether its node still exists: a node
# destroyed without close() does not leave it waiting for good.
CHECK_PERIOD_NS = 500 * 1000 * 1000
# After a failure of rcl's own, before the next wait: a lasting one is not a busy loop.
ERROR_PAUSE_S = 0.1


class OwnThread(CallbackGroup):
    """A callback group the executor leaves alone: a ReceiveThread takes its entities."""

    def can_execute(self, entity) -> bool:
        """Return False: the executor neither waits on nor runs these entities."""
        return False

    def beginning_execution(self, entity) -> bool:
        """Return False: the executor never runs these entities."""
        return False

    def ending_execution(self, entity) -> None:
        """Nothing to do: the executor never runs these entities."""


class ReceiveThread:
    """
    Takes the messages of one subscription (which `follow` names) on a thread of its own.

    The subscription must be created in `callback_group`. To replace it: release() (the thread
    lets go of it, so that it can be destroyed at once), destroy it, follow() the new one.
    close() ends the thread.
    """

    def __init__(self, node, name: str = 'receive',
                 on_error: Optional[Callable[[Exception], None]] = None,
                 take: Optional[Callable[[Any], Any]] = None):
        """
        Make the thread (it starts with the first follow()).

        take(subscription) returns the subscription's next message, or None (default: as
        rclpy takes it); on_error(error) records what a callback raised (default: logged).
        """
        self.callback_group = OwnThread()
        self._context = node.context
        self._on_error = on_error or CallbackFailures(node.get_logger()).record
        self._take_one = take or _rclpy_take
        self._log = ThrottledLog(node.get_logger())
        self._wake = node.create_guard_condition(lambda: None, self.callback_group)
        self._cond = threading.Condition()
        self._subscription = None   # the one to take from, None while released
        self._released = threading.Event()
        self._closing = False
        self._thread = threading.Thread(target=self._run, name=name, daemon=True)
        self._started = False

    def follow(self, subscription) -> None:
        """Take subscription's messages from now on (made in callback_group)."""
        with self._cond:
            self._subscription = subscription
            self._cond.notify()
        if not self._started:
            self._started = True
            self._thread.start()

    def release(self, timeout: float = 5.0) -> bool:
        """
        Stop taking from the subscription; True once the thread has let go of it.

        It then lets go of it (after the callback under way, within timeout): destroyed, a
        subscription the thread does not hold is destroyed at once, its middleware's memory
        given back before another is made.
        """
        with self._cond:
            self._subscription = None
            self._released.clear()
        if not self._started or self._thread is threading.current_thread():
            return True
        self._wake.trigger()
        return self._released.wait(timeout)

    def close(self, timeout: float = 5.0) -> bool:
        """End the thread (after the callback under way); True if it ended within timeout."""
        with self._cond:
            self._closing = True
            self._cond.notify()
        if not self._started:
            return True
        try:
            self._wake.trigger()
        except InvalidHandle:  # the node was destroyed already: the thread sees it
            pass
        if self._thread is not threading.current_thread():
            self._thread.join(timeout)
        return not self._thread.is_alive()

    def _current(self):
        """Return the subscription to take from, waiting while there is none; None: closing."""
        with self._cond:
            while self._subscription is None and not self._closing:
                self._released.set()
                self._cond.wait()
            return None if self._closing else self._subscription

    def _run(self) -> None:
        wait_set = _rclpy.WaitSet(1, 1, 0, 0, 0, 0, self._context.handle)
        while self._context.ok():
            subscription = self._current()
            if subscription is None:
                return
            try:
                message = self._take(wait_set, subscription)
            except InvalidHandle:
                if subscription is self._subscription:
                    return  # destroyed and neither released nor replaced: the node is gone
                continue
            except Exception as error:  # noqa: B902 - a message that cannot be taken or read
                if self._closing or not self._context.ok():
                    return  # shut down under the thread
                self._log.warning(type(error).__name__, 'a message on %s could not be taken, '
                                  'skipped: %s: %s' % (subscription.topic_name,
                                                       type(error).__name__, error))
                time.sleep(ERROR_PAUSE_S)
                continue
            if message is None:
                continue
            try:
                subscription.callback(message)
            except Exception as error:  # noqa: B902 - the node's callback: log, go on
                self._on_error(error)
            # A frame is large: it is not held while waiting for the next one.
            del message

    def _take(self, wait_set, subscription):
        """Wait for a message (or the wake guard, or the check period); return it or None."""
        with subscription.handle, self._wake.handle:
            wait_set.clear_entities()
            wait_set.add_subscription(subscription.handle)
            wait_set.add_guard_condition(self._wake.handle)
            wait_set.wait(CHECK_PERIOD_NS)
            if not wait_set.is_ready('subscription', 0):
                return None
            return self._take_one(subscription)


def _rclpy_take(subscription):
    """Return the subscription's next message as rclpy takes it, or None (its handle held)."""
    taken = subscription.handle.take_message(subscription.msg_type, subscription.raw)
    return None if taken is None else taken[0]
