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
A managed usbcam_publisher as a lifecycle manager and a monitor see it, for the tests.

`Lifecycle` is what `ros2 lifecycle set/get` do (the node's change_state and get_state
services); `CameraStatus` reads the camera's status on /diagnostics.
"""

from diagnostic_msgs.msg import DiagnosticArray
from lifecycle_msgs.msg import Transition
from lifecycle_msgs.srv import ChangeState, GetState
from rclpy.qos import QoSProfile, ReliabilityPolicy
from ros_harness import wait_until

NODE = 'usbcam_publisher'
RELIABLE = QoSProfile(depth=100, reliability=ReliabilityPolicy.RELIABLE)


class Lifecycle:
    """What `ros2 lifecycle set/get` do: the node's change_state and get_state services."""

    def __init__(self, peer, node=NODE):
        # change_state's client is made first: see _wait_until_answered.
        self._change = peer.node.create_client(ChangeState, '/%s/change_state' % node)
        self._get = peer.node.create_client(GetState, '/%s/get_state' % node)
        for client in (self._change, self._get):
            assert client.wait_for_service(timeout_sec=30), 'no %s' % client.srv_name
        self._wait_until_answered()

    def _wait_until_answered(self):
        """
        Ask get_state until the node answers: then it has found where to send its answers.

        wait_for_service() says that this side has found the node's service, not that the
        node has found this client's reply reader; an answer sent before it has is dropped
        (Fast DDS waits 100 ms for the reader, then logs 'failed to send response') and the
        request waits forever. A transition cannot be asked twice; get_state can. The node
        learns this process's readers in the order they were made, so once get_state's
        answer arrives, change_state's (made before it) arrives too.
        """
        def answered():
            future = self._get.call_async(GetState.Request())
            try:
                wait_until(future.done, 3, what='get_state')
            except AssertionError:
                self._get.remove_pending_request(future)
                return False
            return True
        wait_until(answered, 30, 0.0, what='an answer from %s' % self._get.srv_name)

    def _call(self, client, request):
        future = client.call_async(request)
        wait_until(future.done, 30, what='an answer from %s' % client.srv_name)
        return future.result()

    def set(self, transition_id):  # noqa: A003 (as `ros2 lifecycle set`)
        """Request a transition; return whether it succeeded."""
        request = ChangeState.Request(transition=Transition(id=transition_id))
        return self._call(self._change, request).success

    def get(self):
        """Return the current state's label."""
        return self._call(self._get, GetState.Request()).current_state.label


class CameraStatus:
    """The publisher's status on /diagnostics, as a monitor reads it."""

    def __init__(self, peer):
        self.arrays = peer.collect(DiagnosticArray, '/diagnostics', RELIABLE)

    def count(self):
        return len(self.arrays)

    def latest(self):
        for array in reversed(self.arrays):
            for status in array.status:
                if status.name == '%s: camera' % NODE:
                    return status, {kv.key: kv.value for kv in status.values}
        return None, {}

    def wait_reports(self, n=2):
        """Wait for n more reports: the node's own clock, about a second each."""
        start = self.count()
        wait_until(lambda: self.count() >= start + n, 30, what='%d diagnostics reports' % n)
        return self.latest()
