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
What a callback that raised becomes: one error line per kind and minute, not the node's end.

Nothing that arrives over ROS ends a node: an exception raised by a callback (a malformed
request in rclpy's own parameter service, a defect in the node's) is logged, naming the
callback, and the node goes on. The executor's callbacks (node_main) and those of the
subscriptions taken on a thread of their own (receive_thread) are recorded alike.
"""

from pathlib import Path
import traceback

from py_vision.throttled_log import ThrottledLog

__all__ = ['CallbackFailures']


class CallbackFailures:
    """The exceptions callbacks raised: one error line per kind and minute, not the node's end."""

    PERIOD_S = 60.0
    # The frames between whatever called the callback (the executor's spin_once(), a receive
    # thread's loop) and the callback that raised.
    CALLERS = ('executors.py', 'task.py', 'node_main.py', 'receive_thread.py')

    def __init__(self, logger):
        self._log = ThrottledLog(logger, self.PERIOD_S)

    def record(self, error: Exception) -> None:
        """Log error (once per kind and period), naming the callback that raised it."""
        frames = [frame for frame in traceback.extract_tb(error.__traceback__)
                  if Path(frame.filename).name not in self.CALLERS]
        where = ''
        if frames:
            path = Path(frames[0].filename)
            where = ' in %s (%s/%s)' % (frames[0].name, path.parent.name, path.name)
        kind = '%s%s' % (type(error).__name__, where)
        self._log.error(kind, 'a callback failed%s: %s: %s; it was skipped and the node goes on'
                        % (where, type(error).__name__, error))
