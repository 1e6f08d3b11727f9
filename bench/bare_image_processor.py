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
The reference for cv_bridge_test: bare rclpy, draw the red circle, publish the result.

Usage: bare_image_processor.py [--ros-args ...]
Subscribes to usb_camera/image, draws cv_bridge_test's filled circle on a copy of each bgr8
frame with numpy and OpenCV directly, and publishes it with the same header on
cv_bridge_image. Both QoS are the reference's reliable keep-last 10.
"""

import sys

from bench_common import image_qos, StopFlag
import cv2
import numpy as np
import rclpy
from rclpy.executors import SingleThreadedExecutor
from rclpy.signals import SignalHandlerOptions
from sensor_msgs.msg import Image


def main():
    # The process stops itself on SIGINT/SIGTERM, not rclpy.
    rclpy.init(args=sys.argv[1:], signal_handler_options=SignalHandlerOptions.NO)
    stop = StopFlag()
    node = rclpy.create_node('bare_image_processor')
    publisher = node.create_publisher(Image, 'cv_bridge_image', image_qos('reliable'))

    def callback(msg):
        image = np.frombuffer(msg.data, np.uint8).reshape(msg.height, msg.width, 3).copy()
        cv2.circle(image, (60, 60), 30, (0, 0, 255), -1)
        out = Image(header=msg.header, height=msg.height, width=msg.width, encoding='bgr8',
                    is_bigendian=0, step=msg.width * 3)
        out.data = image.tobytes()
        publisher.publish(out)

    node.create_subscription(Image, 'usb_camera/image', callback, image_qos('reliable'))
    executor = SingleThreadedExecutor()
    executor.add_node(node)
    try:
        while not stop.is_set():
            executor.spin_once(timeout_sec=0.1)
    finally:
        node.destroy_node()
        rclpy.try_shutdown()


if __name__ == '__main__':
    main()
