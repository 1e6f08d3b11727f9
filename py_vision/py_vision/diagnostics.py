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
/diagnostics for a node, in rclpy only: what diagnostic_updater does, without it.

diagnostic_updater has no wheel and is not on the boards. `Diagnostics` publishes one
diagnostic_msgs/DiagnosticArray on /diagnostics about once a second, with one
DiagnosticStatus per status function the node registers, in the form diagnostic_aggregator
and rqt_robot_monitor read: `name` "<node name>: <what>", `hardware_id` the device, `level`
OK, WARN, ERROR or STALE, a one-line `message`, and key/value pairs.
"""

import collections
from dataclasses import dataclass, field
from typing import Callable, Dict, List, Optional, Tuple

from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus, KeyValue
from py_vision.params import Parameters
from py_vision.qos import create_publisher
from rclpy.qos import QoSProfile

__all__ = ['DIAGNOSTICS_TOPIC', 'Diagnostics', 'ERROR', 'OK', 'Recent', 'STALE', 'Status',
           'WARN']

DIAGNOSTICS_TOPIC = '/diagnostics'
PERIOD_S = 1.0
OK, WARN, ERROR, STALE = (DiagnosticStatus.OK, DiagnosticStatus.WARN, DiagnosticStatus.ERROR,
                          DiagnosticStatus.STALE)
LEVEL_NAMES = {OK: 'OK', WARN: 'WARN', ERROR: 'ERROR', STALE: 'STALE'}


@dataclass
class Status:
    """What one status function reports: a level, a one-line message and key/value pairs."""

    level: int
    message: str
    values: Dict[str, object] = field(default_factory=dict)
    hardware_id: str = ''


class Recent:
    """
    How much counters grew over the last few reports (a window of about `reports` seconds).

    A status that says "frames skipped lately" reads this, not the totals since start: a
    burst long ago is no reason to warn now, and a single late frame on a loaded machine
    is a small fraction of a window.
    """

    def __init__(self, reports: int = 5):
        self._history = collections.deque(maxlen=reports + 1)

    def update(self, **counts: int) -> Dict[str, int]:
        """Record the counters' totals now; return how much each grew over the window."""
        self._history.append(counts)
        first = self._history[0]
        return {name: value - first.get(name, value) for name, value in counts.items()}

    def clear(self) -> None:
        """Forget the history (after a reconnect, say): the next window starts now."""
        self._history.clear()


def _text(value) -> str:
    if value is None:
        return ''  # nothing measured yet
    if isinstance(value, bool):
        return 'true' if value else 'false'
    if isinstance(value, float):
        return '%.1f' % value
    return str(value)


class Diagnostics:
    """
    Publishes the statuses of a node's parts on /diagnostics, about once a second.

    `add(what, report)` registers `report()`, which returns a Status; it runs on the node's
    executor at every period. A report that raises is published as ERROR naming the error,
    so a broken status function shows instead of hiding the rest. With period_s None there is
    no timer: the node calls publish() about once a second from a timer of its own (one
    executor wake-up for both).
    """

    def __init__(self, parameters: Parameters, hardware_id: str = '',
                 period_s: Optional[float] = PERIOD_S):
        node = self._node = parameters.node
        self.hardware_id = hardware_id
        self._reports: List[Tuple[str, Callable[[], Status]]] = []
        self.publisher = create_publisher(parameters, DiagnosticArray, DIAGNOSTICS_TOPIC,
                                          QoSProfile(depth=10))
        self._timer = None if period_s is None else node.create_timer(period_s, self.publish)

    def add(self, what: str, report: Callable[[], Status]) -> None:
        """Register report() as the status "<node name>: <what>"."""
        self._reports.append((what, report))

    def statuses(self) -> List[DiagnosticStatus]:
        """Return the current DiagnosticStatus of every registered part."""
        node_name = self._node.get_name()
        out = []
        for what, report in self._reports:
            try:
                status = report()
            except Exception as error:  # a bug in a report must not hide the others
                status = Status(ERROR, 'status unavailable: %s: %s' % (
                    type(error).__name__, error))
            out.append(DiagnosticStatus(
                level=status.level, name='%s: %s' % (node_name, what),
                message=status.message,
                hardware_id=status.hardware_id or self.hardware_id,
                values=[KeyValue(key=key, value=_text(value))
                        for key, value in status.values.items()]))
        return out

    def publish(self) -> None:
        """Publish every status now, stamped with the node's clock."""
        msg = DiagnosticArray(status=self.statuses())
        msg.header.stamp = self._node.get_clock().now().to_msg()
        self.publisher.publish(msg)

    def close(self) -> None:
        """Stop publishing (the node destroys the publisher with itself)."""
        if self._timer is not None:
            self._node.destroy_timer(self._timer)
