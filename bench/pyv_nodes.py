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
py_vision's own nodes, unchanged, with a per-frame record for the benchmarks.

Usage: pyv_nodes.py publisher|publisher-noinfo|subscriber OUT.json --ros-args ...
Runs usbcam_publisher or usbcam_subscriber through py_vision's own main (so the packaged Fast
DDS profile, parameters and shutdown are exactly as installed) and, when the node stops, writes
to OUT.json what it did per frame: the publisher the (monotonic time, source frame index) of
every frame it captured, the subscriber the (arrival, frame index, latency) of every image it
counted (the index decoded here from the synthetic camera's frame code: the benchmark's probe,
not the node's work). Recording one tuple per frame is the only thing added; publisher-noinfo
also leaves CameraInfo out, to measure what publishing it costs.
"""

import sys

from bench_common import announce_first_frame, monotonic, write_json
import numpy as np
from py_vision import node_main
from py_vision.capture.synthetic_picture import read_frame_index
from py_vision.usbcam_publisher import USBImagePublisher
from py_vision.usbcam_subscriber import VideoSubscriber
from rclpy.time import Time

OUT = None


class BenchPublisher(USBImagePublisher):
    """usbcam_publisher that remembers when it captured which frame."""

    def publish_image(self, camera, frame):
        super().publish_image(camera, frame)
        record = self.__dict__.setdefault('bench_published', [])
        record.append((monotonic(), frame.index))

    def close(self):
        super().close()
        write_json(OUT, {'published': self.__dict__.get('bench_published', [])})


class _NoInfo:
    """A CameraInfo publisher that publishes nothing."""

    def publish(self, msg):
        pass


class BenchPublisherNoInfo(BenchPublisher):
    """BenchPublisher without CameraInfo: the reference for what CameraInfo costs."""

    def __init__(self):
        super().__init__()
        self.camera_infos = _NoInfo()  # from the first measured frame on


class BenchSubscriber(VideoSubscriber):
    """usbcam_subscriber that remembers every image it received, with its frame index."""

    def callback(self, msg):
        now = self.get_clock().now()
        latency = (now - Time.from_msg(msg.header.stamp)).nanoseconds / 1e9
        index = None
        if msg.encoding == 'bgr8':
            image = np.frombuffer(msg.data, np.uint8).reshape(msg.height, msg.step)
            index = read_frame_index(image[:, :msg.width * 3].reshape(
                msg.height, msg.width, 3))
        received = self.__dict__.setdefault('bench_received', [])
        if not received:
            announce_first_frame()
        received.append((monotonic(), index, latency))
        super().callback(msg)

    def close(self):
        super().close()
        write_json(OUT, {'received': self.__dict__.get('bench_received', [])})


ROLES = {'publisher': BenchPublisher, 'publisher-noinfo': BenchPublisherNoInfo,
         'subscriber': BenchSubscriber}


def main():
    global OUT
    role, OUT = sys.argv[1:3]
    sys.exit(node_main.run(ROLES[role], args=sys.argv[:1] + sys.argv[3:]))


if __name__ == '__main__':
    main()
