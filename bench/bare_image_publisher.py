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
The reference publisher: bare rclpy, prebuilt bgr8 frames, a paced loop, nothing else.

Usage: bare_image_publisher.py OUT.json WIDTH HEIGHT FPS RELIABILITY [--py-vision-profile]
    [--ros-args ...]
Publishes sensor_msgs/Image on usb_camera/image; header.frame_id carries the frame index and
header.stamp the publish time. On SIGINT/SIGTERM it writes the (monotonic time, index) of
every frame it published to OUT.json. With --py-vision-profile it runs on the Fast DDS profile
usbcam_publisher gives itself for frames of that size (py_vision.dds: shared memory for three
of them); without, on what the environment says.
"""

import sys
import time

from bench_common import image_qos, monotonic, StopFlag, write_json
from py_vision.capture.synthetic_picture import synthetic_frame
import rclpy
from rclpy.signals import SignalHandlerOptions
from sensor_msgs.msg import Image

DISTINCT_FRAMES = 4


def build_messages(width, height):
    """Return a few ready-to-send Image messages (the payload never changes afterwards)."""
    messages = []
    for index in range(DISTINCT_FRAMES):
        frame = synthetic_frame(index, width, height)
        msg = Image()
        msg.height, msg.width = frame.shape[:2]
        msg.encoding = 'bgr8'
        msg.is_bigendian = 0
        msg.step = msg.width * 3
        msg.data = frame.tobytes()
        messages.append(msg)
    return messages


def use_camera_profile(width, height):
    """Point Fast DDS at the profile usbcam_publisher makes for frames of this size."""
    from py_vision import dds
    size = ['--ros-args', '-p', 'image_width:=%d' % width, '-p', 'image_height:=%d' % height]
    dds.use_packaged_profile(dds.OWN_SIZE, [sys.argv[0]] + size, 'usbcam_publisher',
                             image_topics=())


def main():
    out, width, height, fps, reliability = sys.argv[1:6]
    width, height, fps = int(width), int(height), float(fps)
    args = sys.argv[6:]
    if args[:1] == ['--py-vision-profile']:
        args = args[1:]
        use_camera_profile(width, height)
    # The process stops itself on SIGINT/SIGTERM (after writing its results), not rclpy.
    rclpy.init(args=args, signal_handler_options=SignalHandlerOptions.NO)
    stop = StopFlag()
    node = rclpy.create_node('bare_image_publisher')
    qos = image_qos(reliability)
    publisher = node.create_publisher(Image, 'usb_camera/image', qos)
    messages = build_messages(width, height)
    clock = node.get_clock()
    published = []
    period = 1.0 / fps
    start = monotonic()
    index = 0
    try:
        while not stop.is_set():
            due = start + index * period
            remaining = due - monotonic()
            if remaining > 0:
                time.sleep(remaining)
            elif remaining < -period:
                # Too slow for this rate: keep going from now rather than bursting to catch up.
                start = monotonic() - index * period
            msg = messages[index % DISTINCT_FRAMES]
            msg.header.frame_id = str(index)
            msg.header.stamp = clock.now().to_msg()
            publisher.publish(msg)
            published.append((monotonic(), index))
            index += 1
    finally:
        write_json(out, {'published': published})
        node.destroy_node()
        rclpy.try_shutdown()


if __name__ == '__main__':
    main()
