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
rclpy's QoS overrides on every topic the nodes publish, as another node sees the publishers.

`qos_overrides./<topic>.publisher.<policy>` (history, depth, reliability, durability) changes
one topic's publisher; the camera node's `reliability` and `depth` stay shorthands for all of
its topics, and an override of one topic wins over them. What a publisher offers is read from
the ROS graph (reliability and durability travel with discovery), the rest from the node's
parameters.
"""

from lifecycle_client import Lifecycle
from lifecycle_msgs.msg import Transition
from param_client import describe_parameters, get_parameters
import pytest
from rclpy.parameter import parameter_value_to_python
from rclpy.qos import DurabilityPolicy, ReliabilityPolicy
from ros_harness import wait_until
from sensor_msgs.msg import Image

CAMERA = {'video_device': 'synthetic', 'framerate': 10.0, 'image_width': 160,
          'image_height': 120}
IMAGE = '/usb_camera/image'
OVERRIDE = 'qos_overrides.%s.publisher.%s'


def offered(peer, topic, node):
    """Return the QoS profile node's publisher of topic offers, once the graph has it."""
    def found():
        infos = [info for info in peer.node.get_publishers_info_by_topic(topic)
                 if info.node_name == node]
        return infos[0].qos_profile if infos else None
    return wait_until(found, 30, 0.1, 'the publisher of %s by %s in the graph' % (topic, node))


def test_an_override_changes_one_topic_and_wins_over_the_shorthand(launch, peer):
    publisher = launch('usbcam_publisher', dict(CAMERA, **{
        'reliability': 'best_effort', 'depth': 3,
        OVERRIDE % (IMAGE, 'reliability'): 'reliable',
        OVERRIDE % (IMAGE, 'depth'): 1,
        OVERRIDE % ('/usb_camera/camera_info', 'durability'): 'transient_local'}))
    image = offered(peer, IMAGE, 'usbcam_publisher')
    info = offered(peer, '/usb_camera/camera_info', 'usbcam_publisher')
    compressed = offered(peer, IMAGE + '/compressed', 'usbcam_publisher')
    assert image.reliability == ReliabilityPolicy.RELIABLE
    assert image.durability == DurabilityPolicy.VOLATILE
    assert info.reliability == ReliabilityPolicy.BEST_EFFORT   # the shorthand
    assert info.durability == DurabilityPolicy.TRANSIENT_LOCAL
    assert compressed.reliability == ReliabilityPolicy.BEST_EFFORT
    names = [OVERRIDE % (IMAGE, 'depth'), OVERRIDE % (IMAGE + '/compressed', 'depth'),
             OVERRIDE % (IMAGE, 'history')]
    assert [parameter_value_to_python(value) for value in get_parameters(
        peer, 'usbcam_publisher', names)] == [1, 3, 'keep_last']
    for descriptor in describe_parameters(peer, 'usbcam_publisher', names):
        assert descriptor.read_only, descriptor.name
    assert publisher.proc.poll() is None


def test_the_overridden_stream_still_reaches_a_subscriber(launch, peer):
    received = peer.collect(Image, IMAGE)
    launch('usbcam_publisher', dict(CAMERA, **{OVERRIDE % (IMAGE, 'reliability'):
                                               'best_effort'}))
    assert offered(peer, IMAGE, 'usbcam_publisher').reliability == \
        ReliabilityPolicy.BEST_EFFORT
    viewer = launch('usbcam_subscriber', {'display': 'none', 'stats_period': 1.0})
    viewer.wait_for_output(r'received \d+ frames', 30)
    wait_until(lambda: received, 30, what='frames on a best-effort stream')


@pytest.mark.parametrize('node,topic', [('cv_bridge_test', '/cv_bridge_image'),
                                        ('usbcam_subscriber', '/diagnostics')])
def test_every_node_takes_overrides_of_what_it_publishes(launch, peer, node, topic):
    launch(node, {'display': 'none', OVERRIDE % (topic, 'reliability'): 'best_effort'})
    assert offered(peer, topic, node).reliability == ReliabilityPolicy.BEST_EFFORT


@pytest.mark.parametrize('policy,value,accepted', [
    ('reliability', 'sometimes', 'reliable or best_effort or system_default'),
    ('depth', 0, '1..1000'),
    ('history', 'keep_some', 'keep_last or keep_all or system_default'),
])
def test_an_override_that_cannot_be_used_is_one_error(launch, policy, value, accepted):
    name = OVERRIDE % (IMAGE, policy)
    publisher = launch('usbcam_publisher', dict(CAMERA, **{name: value}))
    assert publisher.wait_exit(30) == 1
    out = publisher.output()
    assert 'Traceback' not in out
    assert 'parameter %s' % name in out and accepted in out, out


def test_a_managed_node_keeps_its_overrides_through_cleanup(launch, peer):
    launch('usbcam_publisher', dict(CAMERA, managed=True, **{
        OVERRIDE % (IMAGE, 'reliability'): 'best_effort'}))
    lifecycle = Lifecycle(peer)
    # Made again at the second configure, the publishers find their overrides declared.
    for transition in (Transition.TRANSITION_CONFIGURE, Transition.TRANSITION_CLEANUP,
                       Transition.TRANSITION_CONFIGURE):
        assert lifecycle.set(transition), transition
    assert offered(peer, IMAGE, 'usbcam_publisher').reliability == \
        ReliabilityPolicy.BEST_EFFORT
