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
py_vision's own nodes, unchanged, with a per-frame record for the benchmark.

Usage: pyv_nodes.py publisher|subscriber OUT.json --ros-args ...
Runs usbcam_publisher or usbcam_subscriber through py_vision's own main (so the packaged Fast
DDS profile, parameters and shutdown are exactly as installed) and, when the node stops, writes
to OUT.json what it did per frame: the publisher the (monotonic time, source frame index) of
every image it published, the subscriber the (arrival, frame index, latency) its statistics
counted. Recording one tuple per frame is the only thing added.
"""

import sys

from bench_common import announce_first_frame, monotonic, write_json
from py_vision import node_main
from py_vision.usbcam_publisher import USBImagePublisher
from py_vision.usbcam_subscriber import VideoSubscriber

OUT = None


class BenchPublisher(USBImagePublisher):
    """usbcam_publisher that remembers when it published which frame."""

    def _publish(self, frame, stamp):
        super()._publish(frame, stamp)
        record = self.__dict__.setdefault('bench_published', [])
        record.append((monotonic(), getattr(self.cap, 'last_index', None)))

    def close(self):
        super().close()
        write_json(OUT, {'published': self.__dict__.get('bench_published', [])})


class BenchSubscriber(VideoSubscriber):
    """usbcam_subscriber that remembers what its statistics counted."""

    def __init__(self):
        super().__init__()
        self.bench_received = []
        add = self.stats.add

        def recording_add(latency_s, width, height, encoding, index=None):
            if not self.bench_received:
                announce_first_frame()
            self.bench_received.append((monotonic(), index, latency_s))
            add(latency_s, width, height, encoding, index)

        self.stats.add = recording_add

    def close(self):
        super().close()
        write_json(OUT, {'received': self.bench_received})


def main():
    global OUT
    role, OUT = sys.argv[1:3]
    node_class = {'publisher': BenchPublisher, 'subscriber': BenchSubscriber}[role]
    sys.exit(node_main.run(node_class, args=sys.argv[:1] + sys.argv[3:]))


if __name__ == '__main__':
    main()
