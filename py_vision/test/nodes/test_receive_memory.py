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
A node that takes frames keeps their memory for the next ones.

glibc gives the memory of a freed 640x480 message back to the system and the next frame faults
it in again, page by page: half of the CPU a frame costs a subscriber (bench/bench_receive.py).
Page faults are counted here, not time: they do not depend on the machine's load.
"""

import os

from diagnostic_msgs.msg import DiagnosticArray
import pytest
from rclpy.qos import QoSProfile, ReliabilityPolicy
from ros_harness import status_values, wait_until

RELIABLE = QoSProfile(depth=100, reliability=ReliabilityPolicy.RELIABLE)
FRAME_PAGES = 640 * 480 * 3 / os.sysconf('SC_PAGE_SIZE')


def minor_faults(pid):
    with open('/proc/%d/stat' % pid) as stream:
        return int(stream.read().rsplit(')', 1)[1].split()[7])


@pytest.mark.parametrize('executable, params, status, key', [
    ('usbcam_subscriber', {'display': 'none'}, 'usbcam_subscriber: stream', 'frames'),
    ('vision_step', {}, 'vision_step: processing', 'frames in'),
    ('cv_bridge_test', {}, 'cv_bridge_test: processing', 'frames in'),
])
def test_a_frame_is_not_faulted_in_again(launch, peer, executable, params, status, key):
    arrays = peer.collect(DiagnosticArray, '/diagnostics', RELIABLE)
    node = launch(executable, params)
    launch('usbcam_publisher', {'video_device': 'synthetic', 'framerate': 15.0})

    def frames():
        return int(status_values(arrays, status).get(key, 0))
    try:
        wait_until(lambda: frames() >= 10, 60, what='10 frames counted by %s' % executable)
    except AssertionError as error:
        node.fail(str(error))
    first, faults = frames(), minor_faults(node.pid)
    wait_until(lambda: frames() >= first + 30, 60, what='30 more frames')
    per_frame = (minor_faults(node.pid) - faults) / (frames() - first)
    # A frame's memory faulted in again is 225 faults (the message's three copies: 675).
    assert per_frame < 0.1 * FRAME_PAGES, node.tail() + '\n%.0f page faults a frame' % per_frame
