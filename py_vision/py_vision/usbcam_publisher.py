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
usbcam_publisher: camera frames to sensor_msgs/Image (bgr8) on usb_camera/image.

The ROS 2 port of the tutorial's publisher, made robust: frames are read on a capture thread
(a camera paces itself, so there is no timer to drift against it), stamped with their capture
time and published at once, so no frame ever waits behind a newer one. A camera that fails
mid-stream is released and reopened with back-off, and publishing resumes when it is back.
"""

import threading
import time

import cv2
from py_vision.cv_bridge import CvBridge
from py_vision.frame_source import open_capture, SourceError
from py_vision.node_main import ConfigError, main_for
from py_vision.params import Parameters
from py_vision.qos import publisher_qos, RELIABILITY
import rclpy
from rclpy.logging import get_logger
from rclpy.node import Node
from rclpy.time import Time
from sensor_msgs.msg import Image

# Consecutive failed reads after which the device counts as gone (one bad read is noise).
LOST_AFTER_FAILED_READS = 5
REOPEN_BACKOFF_S = (0.25, 0.5, 1.0, 2.0, 4.0)
REOPEN_LOG_PERIOD_S = 5.0


class USBImagePublisher(Node):
    NODE_NAME = 'usbcam_publisher'

    def __init__(self):
        super().__init__(self.NODE_NAME)
        params = Parameters(self)
        self.video_device = params.declare(
            'video_device', '/dev/video0',
            'V4L2 device path, OpenCV camera index, video file, or "synthetic[?options]"',
            check=bool, accepted='a device path, an index, a file or synthetic')
        self.width = params.declare(
            'image_width', 640, 'requested frame width in pixels',
            check=lambda v: 0 < v <= 8192, accepted='1..8192')
        self.height = params.declare(
            'image_height', 480, 'requested frame height in pixels',
            check=lambda v: 0 < v <= 8192, accepted='1..8192')
        self.framerate = params.declare(
            'framerate', 10.0, 'frames per second',
            check=lambda v: 0 < v <= 1000, accepted='a number > 0 and <= 1000')
        self.frame_id = params.declare(
            'frame_id', 'usb_camera', 'header.frame_id of the images (can be changed live)',
            on_change=self._set_frame_id)
        reliability = params.declare(
            'reliability', 'reliable', 'publisher QoS reliability',
            check=RELIABILITY.__contains__, accepted=' or '.join(RELIABILITY))
        depth = params.declare(
            'depth', 10, 'publisher QoS queue depth', check=lambda v: 0 < v <= 1000,
            accepted='1..1000')

        self.bridge_ = CvBridge()
        self.publisher_ = self.create_publisher(
            Image, 'usb_camera/image', publisher_qos(reliability, depth))
        try:
            self.cap = self._open()
        except SourceError as error:
            raise ConfigError(str(error))
        self.frames_published = 0
        self.failed = False
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._capture_loop, name='capture', daemon=True)
        self._thread.start()

    def _set_frame_id(self, frame_id):
        self.frame_id = frame_id

    def _open(self):
        cap = open_capture(self.video_device, self.width, self.height, self.framerate)
        width = int(cap.get(cv2.CAP_PROP_FRAME_WIDTH))
        height = int(cap.get(cv2.CAP_PROP_FRAME_HEIGHT))
        fps = cap.get(cv2.CAP_PROP_FPS)
        note = ''
        if (width, height) != (self.width, self.height):
            note = ' (requested %dx%d; publishing what the device gives)' % (
                self.width, self.height)
        self.get_logger().info('opened %s: %dx%d at %.4g fps%s, publishing on %s' % (
            self.video_device, width, height, fps, note, self.publisher_.topic_name))
        return cap

    def _capture_loop(self):
        """Read, stamp and publish frames until close(); the camera belongs to this thread."""
        try:
            self._capture()
        except Exception as error:
            if self.context.ok():
                # A device or frame this node cannot handle: say so and end the node.
                self.get_logger().error('capturing from %s failed: %s: %s' % (
                    self.video_device, type(error).__name__, error))
                self.failed = True
                rclpy.try_shutdown(context=self.context)
            # else: Ctrl-C or SIGTERM shut rclpy down while a frame was being published.
        finally:
            cap, self.cap = self.cap, None
            if cap is not None:
                cap.release()

    def _capture(self):
        failed_reads = 0
        while not self._stop.is_set():
            if self.cap is None:
                self.cap = self._reopen()
                continue
            ok, frame = self.cap.read()
            if self._stop.is_set():
                return
            if not ok or frame is None:
                failed_reads += 1
                if failed_reads >= LOST_AFTER_FAILED_READS:
                    self.get_logger().warning(
                        'lost %s after %d failed reads; releasing it and reopening' % (
                            self.video_device, failed_reads))
                    self.cap.release()
                    self.cap = None
                    failed_reads = 0
                continue
            failed_reads = 0
            self._publish(frame, self._capture_stamp())

    def _capture_stamp(self):
        """Return the capture time of the frame just read, as a ROS time."""
        now = self.get_clock().now()
        captured = getattr(self.cap, 'last_capture_time', None)
        if captured is None:
            # OpenCV's V4L2 backend gives the driver's buffer time (CLOCK_MONOTONIC) here.
            captured = self.cap.get(cv2.CAP_PROP_POS_MSEC) / 1e3
        age_s = time.monotonic() - captured
        if not 0 <= age_s < 1.0:
            return now  # no usable capture time: the read has just returned the frame
        return Time(nanoseconds=now.nanoseconds - int(age_s * 1e9), clock_type=now.clock_type)

    def _publish(self, frame, stamp):
        msg = self.bridge_.cv2_to_imgmsg(frame, encoding='bgr8')
        msg.header.stamp = stamp.to_msg()
        msg.header.frame_id = self.frame_id
        self.publisher_.publish(msg)
        self.frames_published += 1

    def _reopen(self):
        """Try to reopen the device with back-off until it is back or the node stops."""
        attempt = 0
        last_log = 0.0
        while not self._stop.is_set():
            delay = REOPEN_BACKOFF_S[min(attempt, len(REOPEN_BACKOFF_S) - 1)]
            if self._stop.wait(delay):
                return None
            attempt += 1
            try:
                cap = self._open()
            except SourceError as error:
                if time.monotonic() - last_log >= REOPEN_LOG_PERIOD_S:
                    last_log = time.monotonic()
                    self.get_logger().warning('reopen attempt %d failed: %s' % (attempt, error))
                continue
            self.get_logger().info('%s is back after %d attempt(s); publishing resumes' % (
                self.video_device, attempt))
            return cap
        return None

    def close(self):
        """Stop capturing; the capture thread releases the camera."""
        thread = getattr(self, '_thread', None)
        if thread is None:  # start-up was interrupted before capturing began
            return
        self._stop.set()
        interrupt = getattr(self.cap, 'interrupt', None)
        if interrupt is not None:
            interrupt()  # a synthetic camera or a file waiting for its next frame
        thread.join(2.0)
        # rclpy may be shut down already (Ctrl-C): a logger that does not publish to /rosout.
        logger = get_logger(self.NODE_NAME + '.camera')
        if thread.is_alive():
            logger.warning('%s is still busy; the system releases it at exit' % self.video_device)
        else:
            logger.info('camera released after %d frames' % self.frames_published)


main = main_for(USBImagePublisher)


if __name__ == '__main__':
    main()
