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
Quality of service for the nodes' topics: built from their parameters, overridable per topic.

Every topic a py_vision node publishes takes rclpy's QoS overrides,
``qos_overrides.<topic>.publisher.<policy>`` for its history, depth, reliability and
durability: read-only parameters given on the command line, in a parameter file or by launch,
the same on Humble and Jazzy. They change the QoS the node chose (for the camera node, its
`reliability` and `depth` parameters: shorthands for all its topics at once). They are declared
here, checked like every other parameter (a value that cannot be used is one error naming it),
before rclpy reads them.
"""

from typing import Any

from py_vision.cdr_image import image_message
from py_vision.params import Parameters, Spec
from py_vision.receive_thread import ReceiveThread
from py_vision.serialized_take import SerializedTake
from rclpy.qos import HistoryPolicy, QoSPolicyKind, QoSProfile, ReliabilityPolicy
from rclpy.qos_overriding_options import QoSOverridingOptions
from sensor_msgs.msg import Image

try:
    from rclpy.event_handler import SubscriptionEventCallbacks
except ImportError:  # Humble
    from rclpy.qos_event import SubscriptionEventCallbacks

RELIABILITY = {
    'reliable': ReliabilityPolicy.RELIABLE,
    'best_effort': ReliabilityPolicy.BEST_EFFORT,
}


MAX_DEPTH = 1000
# The policies a user may override on each published topic, and the values each takes.
_POLICY_WORDS = {
    QoSPolicyKind.HISTORY: ('keep_last', 'keep_all', 'system_default'),
    QoSPolicyKind.RELIABILITY: ('reliable', 'best_effort', 'system_default'),
    QoSPolicyKind.DURABILITY: ('volatile', 'transient_local', 'system_default'),
}
_OVERRIDES = QoSOverridingOptions((QoSPolicyKind.HISTORY, QoSPolicyKind.DEPTH,
                                   QoSPolicyKind.RELIABILITY, QoSPolicyKind.DURABILITY))


def publisher_qos(reliability='reliable', depth=10):
    """Return the publisher QoS for a reliability name from RELIABILITY and a queue depth."""
    return QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=depth,
                      reliability=RELIABILITY[reliability])


def override_specs(topic: str, qos: QoSProfile):
    """Return the QoS override parameters of a publisher of topic (resolved) with qos."""
    prefix = 'qos_overrides.%s.publisher.' % topic
    specs = [Spec(prefix + 'depth', qos.depth, 'queue depth of the publisher of %s (with '
                  'history keep_last)' % topic, (1, MAX_DEPTH))]
    for policy, words in _POLICY_WORDS.items():
        name = policy.name.lower()
        specs.append(Spec(prefix + name, getattr(qos, name).name.lower(),
                          '%s of the publisher of %s' % (name, topic), choices=words))
    return specs


def create_publisher(parameters: Parameters, msg_type, topic: str, qos: QoSProfile) -> Any:
    """
    Return a publisher of topic with qos, changed by the user's QoS overrides for the topic.

    The overrides are declared (once: a publisher made again after a lifecycle cleanup finds
    them) and checked first; ConfigError names one that cannot be used.
    """
    node = parameters.node
    for spec in override_specs(node.resolve_topic_name(topic), qos):
        if not node.has_parameter(spec.name):
            parameters.declare(spec)
    # rclpy finds them declared and applies their values (rclpy.qos_overriding_options).
    return node.create_publisher(msg_type, topic, QoSProfile(
        history=qos.history, depth=qos.depth, reliability=qos.reliability,
        durability=qos.durability), qos_overriding_options=_OVERRIDES)


def _image_take():
    """Return how a ReceiveThread takes an Image: serialized, read in place (None: as rclpy)."""
    if not SerializedTake.usable():
        return None
    serialized = SerializedTake()

    def take(subscription):
        buffer = serialized.take(subscription.handle)
        return None if buffer is None else image_message(buffer)
    return take


class ImageSubscription:
    """
    A subscription that hears every publisher on its topic with the best reliability it can.

    It is reliable while all publishers are reliable (so nothing they send is lost) and
    best-effort as soon as one best-effort publisher appears (a reliable subscription cannot
    match it). This is what Jazzy's BEST_AVAILABLE does at creation time, kept up to date as
    publishers come and go, and available on Humble too.

    Its messages are taken on a thread of its own (receive_thread.ReceiveThread), not by the
    node's executor: callback runs there. close() ends that thread; the node calls it before
    it is destroyed. A sensor_msgs/Image is taken serialized into memory of its own and read
    from there (serialized_take, cdr_image): its pixels are copied twice on the way, not four
    times.
    """

    def __init__(self, node, msg_type, topic, callback, depth=10, check_period=0.5):
        self._node = node
        self._args = (msg_type, topic, callback)
        self._depth = depth
        self._renew = False
        self.reliability = ReliabilityPolicy.RELIABLE
        self._receiver = ReceiveThread(node, name='receive %s' % topic,
                                       take=_image_take() if msg_type is Image else None)
        self.subscription = self._create()
        self._receiver.follow(self.subscription)
        self._recheck()
        self._timer = node.create_timer(check_period, self._recheck)

    @property
    def topic_name(self):
        """Return the fully resolved topic name (the name as given on rclpy without it)."""
        return getattr(self.subscription, 'topic_name', self._args[1])

    def _create(self):
        msg_type, topic, callback = self._args
        events = SubscriptionEventCallbacks(incompatible_qos=self._on_incompatible)
        qos = QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=self._depth,
                         reliability=self.reliability)
        return self._node.create_subscription(msg_type, topic, callback, qos,
                                              event_callbacks=events,
                                              callback_group=self._receiver.callback_group)

    def _on_incompatible(self, event):
        # Handling the event replaces rclpy's default warning (in the receive thread's callback
        # group it is never even waited on). Resubscribing from inside the subscription's own
        # callback is not safe; the next check (within check_period) does it.
        pass

    def close(self, timeout: float = 5.0) -> bool:
        """Stop taking messages (after the callback under way); True if done within timeout."""
        return self._receiver.close(timeout)

    def renew(self):
        """
        Make the subscription anew at the next check (within check_period).

        The middleware keeps, for each subscription, buffers as large as the largest message
        it received (Fast DDS' history): a new subscription gives that memory back.
        """
        self._renew = True

    def _recheck(self):
        # rclpy expands and remaps a relative name here, as it does for the subscription.
        publishers = self._node.get_publishers_info_by_topic(self._args[1])
        wanted = ReliabilityPolicy.RELIABLE
        if any(p.qos_profile.reliability == ReliabilityPolicy.BEST_EFFORT for p in publishers):
            wanted = ReliabilityPolicy.BEST_EFFORT
        if wanted == self.reliability and not self._renew:
            return
        changed, self.reliability, self._renew = wanted != self.reliability, wanted, False
        # Destroyed before the next is made: the middleware's memory for it (Fast DDS keeps
        # one pool per topic and process) is given back, not handed on to the new one.
        self._receiver.release()
        self._node.destroy_subscription(self.subscription)
        self.subscription = self._create()
        self._receiver.follow(self.subscription)
        if changed:
            self._node.get_logger().info('subscribed to %s as %s to match its publishers' % (
                self.topic_name, wanted.name.lower()))
