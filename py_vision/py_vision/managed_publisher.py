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
usbcam_publisher as a lifecycle (managed) node: what ``-p managed:=true`` builds.

The camera follows the node's lifecycle state, driven by `ros2 lifecycle set`, launch_ros's
LifecycleNode or any lifecycle manager (rclpy.lifecycle, the same on Humble 3.3 and Jazzy 7.1):

- unconfigured: parameters declared, nothing opened, nothing published;
- configure: parameters checked, publishers made, the camera opened and negotiated; a bad
  parameter or a device that cannot be opened fails the transition with one error line
  saying why, and the node stays unconfigured, ready to be configured again;
- activate: the capture thread starts and frames, compressed and camera_info are published;
- deactivate: the capture thread stops and releases the device, so the camera stops streaming
  and frees its USB bandwidth; the controls set are kept and applied again on activate;
- cleanup: the camera and the publishers are released (back to unconfigured);
- shutdown, from any state: everything released, and the process ends (status 0).

Only the capture thread publishes, and it runs only while active: nothing is published in any
other state. /diagnostics is published in every state, with the state in the camera's status.
Ctrl-C ends the node cleanly in any state (node_main calls close()).
"""

from py_vision.capture import SourceError
from py_vision.node_main import ConfigError
from py_vision.usbcam_publisher import USBImagePublisher
import rclpy
from rclpy.lifecycle import LifecycleNodeMixin, TransitionCallbackReturn
from rclpy.logging import get_logger
from rclpy.node import Node

SUCCESS = TransitionCallbackReturn.SUCCESS
FAILURE = TransitionCallbackReturn.FAILURE
# After shutdown the process ends this much later, once the answer to the transition request
# has gone out (ending rclpy at once could lose it, and `ros2 lifecycle set` would wait).
EXIT_AFTER_SHUTDOWN_S = 0.5


class ManagedPublisher(LifecycleNodeMixin, USBImagePublisher):
    """usbcam_publisher whose camera follows the lifecycle state (see the module's text)."""

    _state = 'unconfigured'

    def __init__(self, **node_options):
        # node_options: rclpy Node's keyword arguments (context, parameter_overrides...).
        Node.__init__(self, self.NODE_NAME, **node_options)
        LifecycleNodeMixin.__init__(self)
        # Checked at configure: an unusable value fails configure instead of ending the node.
        self._parameter_errors = []
        self._setup(self._declare_parameters(self._parameter_errors))
        self.get_logger().info(
            'managed: unconfigured; waiting for configure (ros2 lifecycle set %s configure)'
            % self.get_fully_qualified_name())

    def lifecycle_state(self):
        """Return the lifecycle state: unconfigured, inactive, active or finalized."""
        return self._state

    # --- transitions (on the executor's thread) --------------------------------------

    def on_configure(self, state):
        """Check the parameters, make the publishers, open and negotiate the camera."""
        if self._parameter_errors:
            for error in self._parameter_errors:
                self.get_logger().error('configure failed: %s' % error)
            return FAILURE
        self._make_publishers()
        try:
            self._configure_camera()
            # A value given for one of the camera's controls is checked only now.
            self._declare_controls()
        except ConfigError as error:
            self.get_logger().error('configure failed: %s' % error)
            self._release_all()
            return FAILURE
        self._load_calibration()
        self._state = 'inactive'
        self.get_logger().info('configured: camera open, not streaming')
        return SUCCESS

    def on_activate(self, state):
        """Start capturing and publishing (opening the camera again after a deactivate)."""
        try:
            self.capture.start()
        except SourceError as error:
            self.get_logger().error('activate failed: %s' % error)
            return FAILURE
        self._state = 'active'
        self.get_logger().info('activated: publishing on %s' % self.images.raw.topic_name)
        return SUCCESS

    def on_deactivate(self, state):
        """Stop capturing and release the device, so that it stops streaming."""
        # Once OpenCV has started a V4L2 stream only releasing the device stops it (and frees
        # its USB bandwidth); the controls set stay with the capture loop, which applies them
        # again when activate opens the device.
        self._close_camera()
        self._state = 'inactive'
        self.get_logger().info('deactivated: camera released, streaming stopped after %d '
                               'frames' % self.capture.stats().frames)
        return SUCCESS

    def on_cleanup(self, state):
        """Release the camera and the publishers; fail, keeping both, if it will not close."""
        if not self._release_all():
            self.get_logger().error(
                'cleanup failed: the capture thread of %s did not end; the camera and its '
                'topics are kept (try cleanup again)' % self.video_device)
            return FAILURE
        self._state = 'unconfigured'
        self.get_logger().info('cleaned up: camera released')
        return SUCCESS

    def on_shutdown(self, state):
        """Release everything, then end the process once the answer has gone out."""
        self._release_all()
        self._state = 'finalized'
        self.get_logger().info('shut down from %s: camera released; exiting' % state.label)
        self._exit_timer = self.create_timer(EXIT_AFTER_SHUTDOWN_S, self._exit)
        return SUCCESS

    def on_error(self, state):
        """Release everything after a transition raised; the node goes back to unconfigured."""
        self.get_logger().error('a transition from %s failed; releasing the camera' %
                                state.label)
        self._release_all()
        self._state = 'unconfigured'
        return SUCCESS

    # --- releasing -------------------------------------------------------------------

    def _close_camera(self):
        """Stop capturing and release the device; False if the capture thread is stuck."""
        if self.capture.close():
            return True
        get_logger(self._log_name + '.camera').warning(
            '%s is still busy; the system releases it at exit' % self.video_device)
        return False

    def _release_topics(self):
        if self.images is None:
            return
        for publisher in (self.images.raw, self.images.compressed, self.info_publisher):
            self.destroy_publisher(publisher)
        self.images = None
        service = getattr(self, 'set_info_service', None)
        if service is not None:
            self.destroy_service(service)
            self.set_info_service = None

    def _release_all(self):
        """Close the camera, then the topics; False, keeping the topics, if it did not close."""
        # A capture thread still running may publish at any moment: its publishers stay.
        if not self._close_camera():
            return False
        self._release_topics()
        return True

    def _exit(self):
        self.destroy_timer(self._exit_timer)
        rclpy.try_shutdown(context=self.context)

    def close(self):
        """Release whatever this state holds (Ctrl-C, SIGTERM or the end after shutdown)."""
        capture = self.capture
        if capture is None:  # start-up was interrupted before the capture loop existed
            return
        held = capture.running or capture.camera is not None
        if not self._close_camera():
            return
        logger = get_logger(self._log_name + '.camera')
        if held:
            logger.info('camera released in state %s after %d frames' % (
                self._state, capture.stats().frames))
        else:
            logger.info('stopped in state %s; no camera was open' % self._state)
