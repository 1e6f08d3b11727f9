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
Through shared memory, what comes through it: on Fast DDS 2.6, a viewer's frames and nothing else.

Fast DDS 2.6.0 (Humble, the boards) can stop reading a process' shared-memory port for good
(docs/boards.md, "A node nobody hears"). There py_vision's nodes listen on UDP, but for the
readers of their images: a viewer's frames still come through shared memory, and nothing
anyone else sends it does. What a process received through shared memory shows in its memory
map: the receiver maps the sender's segment (`/dev/shm/fastrtps_<id>`, whose `_el` lock its
owner holds) when the first message from it arrives, and only then. On Jazzy (Fast DDS 2.14,
which has the fix) a node listens on shared memory as Fast DDS has it: the test's own calls reach
the viewer through it too.
"""

import os
from pathlib import Path
import re

from param_client import get_parameters, set_parameter
from py_vision import dds, node_main
import ros_harness
from sensor_msgs.msg import CompressedImage, Image

SEGMENT = re.compile(r'/dev/shm/(fastrtps_[0-9a-f]+)$')


def lock_owners():
    """Return {inode: pid} of the locks held on files (/proc/locks)."""
    owners = {}
    for line in Path('/proc/locks').read_text().splitlines():
        fields = line.split()
        # 1: FLOCK  ADVISORY  WRITE 1234 00:1f:567 0 EOF (a blocked request has '->')
        if len(fields) >= 6 and fields[1] != '->':
            owners[int(fields[5].rsplit(':', 1)[1])] = int(fields[4])
    return owners


def segment_owners(pid):
    """Return {segment name: owner pid} of the Fast DDS segments process pid maps."""
    names = set()
    for line in Path('/proc/%d/maps' % pid).read_text().splitlines():
        match = SEGMENT.search(line)
        if match:
            names.add(match.group(1))
    owners = lock_owners()
    found = {}
    for name in names:
        try:
            found[name] = owners.get(os.stat('/dev/shm/%s_el' % name).st_ino)
        except FileNotFoundError:  # its owner has gone
            found[name] = None
    return found


def test_a_viewer_receives_frames_and_nothing_else_through_shared_memory(ros_env, domain_id):
    camera = ros_harness.NodeProcess('usbcam_publisher', ros_harness.ros_args(
        {'video_device': 'synthetic', 'framerate': 30.0}), ros_env)
    viewer = ros_harness.NodeProcess('usbcam_subscriber', ros_harness.ros_args(
        {'display': 'none', 'stats_period': 0.5}), ros_env)
    peer = ros_harness.RosPeer(domain_id, 'shm_test_peer')
    try:
        viewer.wait_for_output(r'received [1-9]\d* frames', 30)
        # The test's calls: discovery, requests, replies between this process and the viewer.
        assert set_parameter(peer, 'usbcam_subscriber', 'stats_period', 1.0).successful
        assert get_parameters(peer, 'usbcam_subscriber', ['stats_period'])[0].double_value == 1.0
        owners = set(segment_owners(viewer.pid).values())
        own = viewer.pid in owners
        assert own, 'the viewer maps no segment of its own: %s\n%s' % (owners, viewer.tail())
        assert camera.pid in owners, (
            'no frame came through shared memory: the viewer maps no segment of the camera '
            '(pid %d): %s\n%s\n%s' % (camera.pid, owners, viewer.tail(), camera.tail()))
        # Its profile copy: its own on Humble (a UDP port of its own in it), there while it runs.
        copy = Path(ros_env.get('TMPDIR') or '/tmp', 'py_vision_fastdds_%d_pid%d.xml' % (
            os.getuid(), viewer.pid))
        if ros_harness.ON_HUMBLE:
            assert owners <= {viewer.pid, camera.pid}, (
                'the viewer received through shared memory from other processes (this test '
                'is pid %d): %s\n%s' % (os.getpid(), owners, viewer.tail()))
            assert copy.is_file(), 'no %s\n%s' % (copy, viewer.tail())
        else:
            assert os.getpid() in owners, (
                "on Fast DDS 2.14 the test's calls come through shared memory: %s" % owners)
        assert viewer.stop() == 0
        assert not copy.exists(), 'the viewer left %s behind' % copy
        assert 'was taken by another process' not in viewer.output()
    finally:
        peer.close()
        viewer.kill()
        camera.kill()


class Recorder:
    """A logger that keeps its warnings."""

    def __init__(self):
        self.warnings = []

    def warning(self, text):
        self.warnings.append(text)

    def error(self, text):
        self.warnings.append('error: ' + text)


class Subscribed:
    """What node_main reads of a node: its subscriptions (msg_type, topic_name) and logger."""

    def __init__(self, *subscriptions):
        self.subscriptions = [type('Subscription', (), {'msg_type': msg_type, 'topic_name': topic})
                              for msg_type, topic in subscriptions]
        self.logger = Recorder()

    def get_logger(self):
        return self.logger


def test_an_image_subscription_dds_did_not_give_shared_memory_is_said(monkeypatch):
    # The topics come from the command line before rclpy starts (ros_arguments.topic_name,
    # checked against rcl in test_ros_arguments): a node that then subscribed elsewhere would
    # get its frames through UDP, slowly, without a word. It says so.
    predicted = ('/usb_camera/image', '/usb_camera/image/compressed')
    monkeypatch.setattr(dds, 'shm_topics', lambda: predicted)
    monkeypatch.setattr(dds, 'lost_port', lambda: None)
    node = Subscribed((Image, '/usb_camera/image'), (CompressedImage, '/cam/compressed'))
    node_main._check_transport(node, predicted)
    (said,) = node.logger.warnings
    assert said.startswith('frames on /cam/compressed come through UDP')
    # The topics it was given, or Fast DDS not split (Jazzy, or a user's profile): nothing.
    node = Subscribed((Image, '/usb_camera/image'), (CompressedImage, predicted[1]))
    node_main._check_transport(node, predicted)
    monkeypatch.setattr(dds, 'shm_topics', lambda: ())
    other = Subscribed((Image, '/cam/image'))
    node_main._check_transport(other, predicted)
    assert node.logger.warnings == other.logger.warnings == []


def test_a_node_whose_udp_port_was_taken_says_nobody_can_reach_it(monkeypatch):
    # dds picks the port before rclpy starts; another process may bind it before Fast DDS
    # does (test_dds: dds.lost_port), and the node would be "a node nobody hears", silently.
    monkeypatch.setattr(dds, 'lost_port', lambda: 7777)
    monkeypatch.setattr(dds, 'shm_topics', lambda: ())
    node = Subscribed((Image, '/usb_camera/image'))
    node_main._check_transport(node, ())
    (said,) = node.logger.warnings
    assert said.startswith('error: UDP port 7777') and 'restart it' in said
