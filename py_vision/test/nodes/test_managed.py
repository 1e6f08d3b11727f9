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
usbcam_publisher with managed:=true, driven over the real lifecycle services.

What `ros2 lifecycle set` and a lifecycle manager see: the state after each transition, what
is published in each state, the camera opened and released (the node's log), a configure
that fails with the reason and leaves the node usable, shutdown and Ctrl-C in every state.
"""

import signal

from lifecycle_client import CameraStatus, Lifecycle, NODE, RELIABLE
from lifecycle_msgs.msg import Transition
from param_client import get_parameters
from py_vision.usbcam_publisher import USBImagePublisher
import pytest
from rclpy.lifecycle import TransitionCallbackReturn
from rclpy.parameter import Parameter
from ros_harness import wait_until
from sensor_msgs.msg import CameraInfo, CompressedImage, Image

CAMERA = {'video_device': 'synthetic', 'framerate': 10.0, 'image_width': 160,
          'image_height': 120, 'managed': True}
# The transition that ends the node from each primary state.
SHUTDOWN = {'unconfigured': Transition.TRANSITION_UNCONFIGURED_SHUTDOWN,
            'inactive': Transition.TRANSITION_INACTIVE_SHUTDOWN,
            'active': Transition.TRANSITION_ACTIVE_SHUTDOWN}
# How to reach each primary state from unconfigured.
TO_STATE = {'unconfigured': (), 'inactive': (Transition.TRANSITION_CONFIGURE,),
            'active': (Transition.TRANSITION_CONFIGURE, Transition.TRANSITION_ACTIVATE)}


def publishers_of(peer, topic):
    return peer.node.count_publishers(topic)


def test_every_transition_publishes_only_while_active(launch, peer):
    raw = peer.collect(Image, 'usb_camera/image', RELIABLE)
    compressed = peer.collect(CompressedImage, 'usb_camera/image/compressed', RELIABLE)
    info = peer.collect(CameraInfo, 'usb_camera/camera_info', RELIABLE)
    status = CameraStatus(peer)
    node = launch('usbcam_publisher', CAMERA)
    lifecycle = Lifecycle(peer)

    # unconfigured: nothing opened, no image topics, the node says what it waits for.
    assert lifecycle.get() == 'unconfigured'
    _, values = status.wait_reports()
    assert values['lifecycle state'] == 'unconfigured'
    assert values['device present'] == 'false' and values['frames'] == '0'
    assert publishers_of(peer, '/usb_camera/image') == 0
    assert 'opened' not in node.output()
    assert 'waiting for configure' in node.output()

    # configure: the camera is opened and negotiated, the topics exist, nothing is captured.
    assert lifecycle.set(Transition.TRANSITION_CONFIGURE)
    assert lifecycle.get() == 'inactive'
    node.wait_for_output(r'opened synthetic: 160x120 YUYV')
    wait_until(lambda: publishers_of(peer, '/usb_camera/image') == 1, 20, what='the publisher')
    _, values = status.wait_reports()
    assert values['lifecycle state'] == 'inactive' and values['device present'] == 'true'
    _, values = status.wait_reports()
    assert values['frames'] == '0' and not raw and not compressed and not info

    # activate: raw, compressed and camera_info are published.
    assert lifecycle.set(Transition.TRANSITION_ACTIVATE)
    assert lifecycle.get() == 'active'
    wait_until(lambda: len(raw) >= 5 and len(compressed) >= 5 and len(info) >= 5, 30,
               what='frames, compressed frames and camera_info while active')
    assert raw[0].width == 160 and info[0].header == raw[0].header

    # deactivate: the camera stops streaming and stays open, nothing more is published.
    assert lifecycle.set(Transition.TRANSITION_DEACTIVATE)
    assert lifecycle.get() == 'inactive'
    assert 'deactivated: streaming stopped after' in node.output()
    counts = (len(raw), len(compressed), len(info))
    _, values = status.wait_reports()
    frames = values['frames']
    _, values = status.wait_reports()
    assert values['frames'] == frames, 'the camera still captures while inactive'
    assert (len(raw), len(compressed), len(info)) == counts

    # activate again: publishing resumes from the camera kept open.
    assert lifecycle.set(Transition.TRANSITION_ACTIVATE)
    wait_until(lambda: len(raw) >= counts[0] + 5, 30, what='frames after activating again')
    assert node.output().count('opened synthetic') == 1

    # deactivate, cleanup: back to unconfigured with the camera and the topics released.
    assert lifecycle.set(Transition.TRANSITION_DEACTIVATE)
    assert lifecycle.set(Transition.TRANSITION_CLEANUP)
    assert lifecycle.get() == 'unconfigured'
    assert 'cleaned up: camera released' in node.output()
    wait_until(lambda: publishers_of(peer, '/usb_camera/image') == 0, 20,
               what='the image publisher gone after cleanup')

    # and configurable again.
    assert lifecycle.set(Transition.TRANSITION_CONFIGURE)
    assert lifecycle.get() == 'inactive'
    assert node.output().count('opened synthetic') == 2
    assert 'Traceback' not in node.output()


def test_a_camera_lost_while_active_is_reconnected(launch, peer):
    raw = peer.collect(Image, 'usb_camera/image', RELIABLE)
    node = launch('usbcam_publisher', dict(
        CAMERA, video_device='synthetic?stop_after=30&unplugged_for=2'))
    lifecycle = Lifecycle(peer)
    assert lifecycle.set(Transition.TRANSITION_CONFIGURE)
    assert lifecycle.set(Transition.TRANSITION_ACTIVATE)
    node.wait_for_output(r'WARN.*lost synthetic', 30)
    count = len(raw)
    node.wait_for_output(r'is back after \d+ attempt', 30)
    wait_until(lambda: len(raw) >= count + 5, 30, what='frames after the reconnect')
    assert lifecycle.get() == 'active'


def test_configure_fails_with_the_reason_and_the_node_stays_usable(launch, peer):
    node = launch('usbcam_publisher', dict(CAMERA, video_device='/dev/video_py_vision_missing'))
    lifecycle = Lifecycle(peer)
    assert not lifecycle.set(Transition.TRANSITION_CONFIGURE)
    node.wait_for_output(r'ERROR.*configure failed: .*/dev/video_py_vision_missing')
    assert lifecycle.get() == 'unconfigured'
    # Still answering, and a second attempt fails the same way (the device may come later).
    assert not lifecycle.set(Transition.TRANSITION_CONFIGURE)
    assert node.output().count('configure failed') == 2
    assert node.proc.poll() is None
    assert lifecycle.set(Transition.TRANSITION_UNCONFIGURED_SHUTDOWN)
    assert node.wait_exit(20) == 0
    assert 'Traceback' not in node.output()


def test_a_bad_parameter_fails_configure_instead_of_ending_the_node(launch, peer):
    node = launch('usbcam_publisher', dict(CAMERA, framerate=0.0))
    lifecycle = Lifecycle(peer)
    assert not lifecycle.set(Transition.TRANSITION_CONFIGURE)
    node.wait_for_output(r'ERROR.*configure failed: parameter framerate')
    assert lifecycle.get() == 'unconfigured'
    assert node.proc.poll() is None
    assert 'opened' not in node.output()


def test_a_mistyped_control_fails_configure_with_the_reason_every_time(launch, peer):
    # The controls are parameters only once the camera is open (at configure): a value of the
    # wrong type for one is a configure that fails saying so, and the camera is released.
    node = launch('usbcam_publisher', dict(CAMERA, brightness='bright'))
    lifecycle = Lifecycle(peer)
    for attempt in (1, 2):
        assert not lifecycle.set(Transition.TRANSITION_CONFIGURE)
        node.wait_for_output(r'ERROR.*configure failed: parameter brightness')
        assert node.output().count('configure failed: parameter brightness') == attempt
        assert lifecycle.get() == 'unconfigured'
    assert publishers_of(peer, '/usb_camera/image') == 0
    assert lifecycle.set(Transition.TRANSITION_UNCONFIGURED_SHUTDOWN)
    assert node.wait_exit(20) == 0
    assert 'Traceback' not in node.output()


@pytest.mark.parametrize('state', sorted(SHUTDOWN))
def test_shutdown_from_every_state_releases_the_camera_and_ends(launch, peer, state):
    node = launch('usbcam_publisher', CAMERA)
    lifecycle = Lifecycle(peer)
    for transition in TO_STATE[state]:
        assert lifecycle.set(transition)
    assert lifecycle.get() == state
    assert lifecycle.set(SHUTDOWN[state])
    assert node.wait_exit(20) == 0
    out = node.output()
    assert 'shut down from %s: camera released' % state in out
    assert 'Traceback' not in out


@pytest.mark.parametrize('state', sorted(SHUTDOWN))
def test_ctrl_c_in_every_state_ends_cleanly(launch, peer, state):
    node = launch('usbcam_publisher', CAMERA)
    lifecycle = Lifecycle(peer)
    for transition in TO_STATE[state]:
        assert lifecycle.set(transition)
    assert lifecycle.get() == state
    assert node.stop(signal.SIGINT, timeout=5) == 0
    out = node.output()
    if state == 'unconfigured':
        assert 'stopped in state unconfigured; no camera was open' in out
    else:
        assert 'camera released in state %s' % state in out
    assert 'Traceback' not in out


def test_the_plain_node_is_not_a_lifecycle_node(launch, peer):
    node = launch('usbcam_publisher', {'video_device': 'synthetic', 'image_width': 160,
                                       'image_height': 120})
    node.wait_for_output('opened synthetic')
    (managed,) = get_parameters(peer, NODE, ['managed'])
    assert managed.bool_value is False

    def listed():
        # Answering a service call does not mean the peer's graph knows the node's name yet
        # (discovery of the node and of its endpoints are separate): wait for both.
        if (NODE, '/') not in peer.node.get_node_names_and_namespaces():
            return None
        names = [name for name, _ in peer.node.get_service_names_and_types_by_node(NODE, '/')]
        return names if '/%s/set_parameters' % NODE in names else None
    services = wait_until(listed, 30, 0.1, 'the services of %s in the graph' % NODE)
    assert not [name for name in services if 'change_state' in name or 'get_state' in name]


class StuckCapture(USBImagePublisher):
    """The managed node, with a capture thread that does not end when asked (on demand)."""

    stuck = False

    def _close_camera(self):
        if self.stuck:
            return False
        return super()._close_camera()


def test_cleanup_fails_and_keeps_the_topics_when_the_capture_thread_does_not_end(peer):
    node = StuckCapture(context=peer.context, parameter_overrides=[
        Parameter(name, value=value) for name, value in CAMERA.items()])
    try:
        assert node.trigger_configure() == TransitionCallbackReturn.SUCCESS
        topics = node.images
        node.stuck = True
        # The thread may still publish: its publishers stay, and the node says why it failed.
        assert node.trigger_cleanup() == TransitionCallbackReturn.FAILURE
        assert node.images is topics and node.images.raw.handle is not None
        assert node.lifecycle_state() == 'inactive'
        node.stuck = False
        assert node.trigger_cleanup() == TransitionCallbackReturn.SUCCESS
        assert node.images is None
    finally:
        node.stuck = False
        node.close()
        node.destroy_node()
