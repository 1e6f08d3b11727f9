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
Subscribe to usb_camera/image in a separate process and check each frame's pixels.

Run by tests where an in-process peer cannot go (another network namespace). Prints one JSON
line: {"frames": N, "intact": K, "indexes": [...]} after `count` frames, then exits 0.
"""

import json
import sys

import numpy as np
from py_vision.capture.synthetic_picture import read_frame_index, synthetic_frame
import rclpy
from rclpy.qos import QoSProfile, ReliabilityPolicy
from sensor_msgs.msg import Image


def main():
    count = int(sys.argv[1])
    rclpy.init()
    node = rclpy.create_node('frame_checker')
    result = {'frames': 0, 'intact': 0, 'indexes': []}

    def check(msg):
        image = np.frombuffer(msg.data, np.uint8).reshape(msg.height, msg.width, 3)
        index = read_frame_index(image)
        result['frames'] += 1
        result['indexes'].append(index)
        if index is not None and np.array_equal(
                image, synthetic_frame(index, msg.width, msg.height)):
            result['intact'] += 1

    node.create_subscription(Image, 'usb_camera/image', check,
                             QoSProfile(depth=50, reliability=ReliabilityPolicy.RELIABLE))
    while rclpy.ok() and result['frames'] < count:
        rclpy.spin_once(node, timeout_sec=0.1)
    print(json.dumps(result), flush=True)
    node.destroy_node()
    rclpy.try_shutdown()


if __name__ == '__main__':
    main()
