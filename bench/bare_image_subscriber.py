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
The reference subscriber: bare rclpy, records every frame it receives.

Usage: bare_image_subscriber.py OUT.json RELIABILITY [--py-vision-profile] [--ros-args ...]
Subscribes to usb_camera/image (sensor_msgs/Image) and records, per message, the monotonic
arrival time, the frame index (header.frame_id when it is a number, as the reference publisher
sends it, else decoded from the synthetic source's image) and the latency from header.stamp to
the callback. Prints FIRST_FRAME_MARK at the first frame and writes OUT.json on SIGINT/SIGTERM.
With --py-vision-profile it runs on the Fast DDS profile usbcam_subscriber gives itself
(py_vision.dds, tailored the same way: the reference of bench_receive.py); without, on what
the environment says.
"""

import sys

from bench_common import (announce_first_frame, image_qos, monotonic, StopFlag,
                          write_json)
import numpy as np
from py_vision.capture.synthetic_picture import read_frame_index
import rclpy
from rclpy.executors import SingleThreadedExecutor
from rclpy.signals import SignalHandlerOptions
from sensor_msgs.msg import Image


class Recorder:
    """The subscription callback and what it has recorded."""

    def __init__(self, node):
        self.clock = node.get_clock()
        self.events = []

    def frame_index(self, msg):
        if msg.header.frame_id.isdigit():
            return int(msg.header.frame_id)
        if msg.encoding != 'bgr8':
            return None
        image = np.frombuffer(msg.data, dtype=np.uint8).reshape(msg.height, msg.width, 3)
        return read_frame_index(image)

    def callback(self, msg):
        now_ns = self.clock.now().nanoseconds
        arrival = monotonic()
        stamp_ns = msg.header.stamp.sec * 1000000000 + msg.header.stamp.nanosec
        if not self.events:
            announce_first_frame()
        self.events.append((arrival, self.frame_index(msg), (now_ns - stamp_ns) / 1e9))


def use_subscriber_profile():
    """Point Fast DDS at the profile usbcam_subscriber makes for itself (before rclpy.init)."""
    from py_vision import dds, transport
    dds.use_packaged_profile(dds.NO_IMAGES, [], 'usbcam_subscriber',
                             image_topics=transport.image_topics('/usb_camera/image'))


def main():
    out, reliability = sys.argv[1:3]
    args = sys.argv[3:]
    if args[:1] == ['--py-vision-profile']:
        args = args[1:]
        use_subscriber_profile()
    # The process stops itself on SIGINT/SIGTERM (after writing its results), not rclpy.
    rclpy.init(args=args, signal_handler_options=SignalHandlerOptions.NO)
    stop = StopFlag()
    node = rclpy.create_node('bare_image_subscriber')
    qos = image_qos(reliability)
    recorder = Recorder(node)
    node.create_subscription(Image, 'usb_camera/image', recorder.callback, qos)
    executor = SingleThreadedExecutor()
    executor.add_node(node)
    try:
        while not stop.is_set():
            executor.spin_once(timeout_sec=0.1)
    finally:
        write_json(out, {'received': recorder.events})
        node.destroy_node()
        rclpy.try_shutdown()


if __name__ == '__main__':
    main()
