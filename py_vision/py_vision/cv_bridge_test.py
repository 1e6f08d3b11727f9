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
cv_bridge_test: the processing step of the second tutorial, ported to ROS 2.

Every image from usb_camera/image is converted to an OpenCV bgr8 image with the bridge, gets
a red filled circle at (60, 60) with radius 30 when it is larger than 60x60, and goes out on
cv_bridge_image with the header it came with. A message the bridge cannot convert is logged
(at most once per ERROR_LOG_PERIOD_S) and skipped; the node keeps going. With `display` set,
the processed frames are also shown, like the subscriber shows its own.
"""

import cv2
from py_vision.cv_bridge import CvBridge, CvBridgeError
from py_vision.display import declare_display_parameters, Display
from py_vision.node_main import main_for
from py_vision.params import Parameters
from py_vision.qos import ImageSubscription, publisher_qos
from py_vision.stats import StreamStats
from rclpy.node import Node
from rclpy.time import Time
from sensor_msgs.msg import Image

CIRCLE_CENTER, CIRCLE_RADIUS, CIRCLE_BGR = (60, 60), 30, (0, 0, 255)
ERROR_LOG_PERIOD_S = 5.0


class CvBridgeTest(Node):
    NODE_NAME = 'cv_bridge_test'

    def __init__(self):
        super().__init__(self.NODE_NAME)
        params = Parameters(self)
        display, web_host, web_port = declare_display_parameters(params, 'none')

        self.bridge_ = CvBridge()
        self.stats = StreamStats(window_s=5.0)
        self.display = Display(self.get_logger(), display, web_host, web_port, 'cv_bridge_image')
        # Reliable with a queue of 10, the ROS 2 default: what the seed's rospy publisher
        # gives, and both reliable and best-effort subscribers (rqt_image_view) receive it.
        self.publisher_ = self.create_publisher(Image, 'cv_bridge_image', publisher_qos())
        self.subscription_ = ImageSubscription(self, Image, 'usb_camera/image', self.callback)
        self.display.attach(self, self.stats, self.publisher_.topic_name)
        self.get_logger().info('drawing on images from %s, publishing them on %s' % (
            self.subscription_.topic_name, self.publisher_.topic_name))

    def callback(self, msg):
        try:
            image = self.bridge_.imgmsg_to_cv2(msg, 'bgr8')
        except CvBridgeError as error:
            self.stats.add_error()
            self.get_logger().error(
                'cannot convert a %dx%d "%s" image to bgr8, skipped: %s (%d skipped so far)' % (
                    msg.width, msg.height, msg.encoding, error, self.stats.errors),
                throttle_duration_sec=ERROR_LOG_PERIOD_S)
            return
        # The bridge returns a writable image the node owns (a view of this message's data,
        # or a converted copy), so the circle is drawn in place.
        rows, cols = image.shape[:2]
        if cols > 60 and rows > 60:
            cv2.circle(image, CIRCLE_CENTER, CIRCLE_RADIUS, CIRCLE_BGR, -1)
        self.publisher_.publish(self.bridge_.cv2_to_imgmsg(image, 'bgr8', header=msg.header))
        if self.stats.frames == 0:
            self.get_logger().info('first image: %dx%d %s' % (cols, rows, msg.encoding))
        latency = self.get_clock().now() - Time.from_msg(msg.header.stamp)
        self.stats.add(latency.nanoseconds / 1e9, cols, rows, 'bgr8')
        self.display.show(image)

    def close(self):
        """Close the window or the browser viewer (releasing its port)."""
        display = getattr(self, 'display', None)  # None when start-up was interrupted
        if display is not None:
            display.close()


main = main_for(CvBridgeTest)


if __name__ == '__main__':
    main()
