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
The recorded H.264 clip (uvc_emulator/clips/, made by make_clip.py), as access units.

Frame i of the clip shows index i in the synthetic picture's code (`read_frame_index`); an IDR
with its SPS and PPS every `KEYINT` frames.
"""

from pathlib import Path
from typing import List

CLIP = Path(__file__).resolve().parent / 'uvc_emulator' / 'clips' / 'synthetic_640x480.h264'
WIDTH, HEIGHT, FRAMES, KEYINT = 640, 480, 60, 15
_DELIMITER = b'\x00\x00\x00\x01\x09'   # every access unit of the clip starts with its AUD


def access_units(path: Path = CLIP) -> List[bytes]:
    """Return the clip's access units, in order, each starting with its delimiter."""
    data = path.read_bytes()
    starts = []
    position = data.find(_DELIMITER)
    while position >= 0:
        starts.append(position)
        position = data.find(_DELIMITER, position + 1)
    return [data[start:end] for start, end in zip(starts, starts[1:] + [len(data)])]


class ClipPublisher:
    """
    Publishes the clip's access units on a peer node, in a loop, as a camera would.

    As sensor_msgs/CompressedImage with format h264 (what py_vision publishes where
    foxglove_msgs is not installed), stamped now, at `rate`; `sent` lists the index of each unit
    published, in order; with when_subscribed, from the moment a subscriber has matched.
    Independent of py_vision's own publisher.
    """

    def __init__(self, peer, topic='usb_camera/image/h264', rate=30.0, first=0,
                 when_subscribed=False):
        from rclpy.qos import QoSProfile, ReliabilityPolicy
        self._node = peer.node
        self._units = access_units()
        self._next = first
        self._when_subscribed = when_subscribed   # nothing sent before a subscriber matches
        self.sent = []
        self.publisher = self._node.create_publisher(
            self._message_type(), topic,
            QoSProfile(depth=10, reliability=ReliabilityPolicy.RELIABLE))
        self._timer = self._node.create_timer(1.0 / rate, self._publish)

    @staticmethod
    def _message_type():
        from sensor_msgs.msg import CompressedImage
        return CompressedImage

    def _publish(self):
        if self._when_subscribed and not self.publisher.get_subscription_count():
            return
        msg = self._message_type()(format='h264')
        msg.header.stamp = self._node.get_clock().now().to_msg()
        msg.header.frame_id = 'clip'
        index = self._next % len(self._units)
        msg.data = self._units[index]
        self.publisher.publish(msg)
        self.sent.append(index)
        self._next += 1

    def stop(self):
        """Stop publishing."""
        self._node.destroy_timer(self._timer)
