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
Image topics the way image_transport lays them out, in rclpy.

A base topic ``T`` (after remapping) carries ``sensor_msgs/Image``; ``T/compressed`` carries
the same frames as ``sensor_msgs/CompressedImage`` (JPEG, ``format`` as image_transport's
compressed plugin writes it for bgr8, or mono8 for a grey picture); ``camera_info`` beside it
(``<dir of T>/camera_info``) carries their ``CameraInfo``. `ImagePublisher` produces each form
only while its topic has subscribers, in any encoding the bridge knows, and publishes a
camera's own JPEG untouched. `subscribe()` is what an
image_transport subscriber's ``image_transport`` parameter (``raw`` or ``compressed``) chooses.
"""

from typing import Callable, Optional, Tuple

import cv2
import numpy as np
from py_vision.cv_bridge import fill_message_data
from py_vision.params import Parameters
from py_vision.qos import create_publisher, ImageSubscription
from sensor_msgs.msg import CompressedImage, Image

TRANSPORTS = ('raw', 'compressed')
JPEG_FORMAT = 'bgr8; jpeg compressed bgr8'
MONO_JPEG_FORMAT = 'mono8; jpeg compressed mono8'
_SOF_MARKERS = frozenset(range(0xC0, 0xD0)) - {0xC4, 0xC8, 0xCC}


def compressed_topic(node, base_topic: str) -> str:
    """Return the compressed topic of base_topic as resolved (remapped) for node."""
    return node.resolve_topic_name(base_topic) + '/compressed'


def sibling_topic(node, base_topic: str, name: str) -> str:
    """Return the topic or service `name` beside base_topic (camera_info, set_camera_info)."""
    resolved = node.resolve_topic_name(base_topic)
    return resolved.rsplit('/', 1)[0] + '/' + name


def jpeg_size(data) -> Optional[Tuple[int, int]]:
    """Return (width, height) from a JPEG's frame header, or None if there is none."""
    view = memoryview(data).cast('B')
    i, end = 2, len(view) - 9
    if len(view) < 4 or view[0] != 0xFF or view[1] != 0xD8:
        return None
    while i < end:
        if view[i] != 0xFF:
            return None
        marker = view[i + 1]
        if marker == 0xFF:
            i += 1
            continue
        if marker in _SOF_MARKERS:
            return (view[i + 7] << 8) | view[i + 8], (view[i + 5] << 8) | view[i + 6]
        i += 2 + ((view[i + 2] << 8) | view[i + 3])
    return None


class ImagePublisher:
    """
    Raw and compressed publishers of one base topic, each used only while it has readers.

    With lazy_raw False the raw image is published whatever its subscribers (a processing
    node's output, which a subscriber still being discovered must not miss).
    """

    def __init__(self, parameters: Parameters, base_topic: str, qos, bridge,
                 lazy_raw: bool = True):
        self._bridge = bridge
        self._lazy_raw = lazy_raw
        node = parameters.node
        # Each topic takes the user's QoS overrides (qos.create_publisher).
        self.raw = create_publisher(parameters, Image, base_topic, qos)
        self.compressed = create_publisher(
            parameters, CompressedImage, compressed_topic(node, base_topic), qos)
        self.jpeg_quality = 80
        self.encoded = 0        # JPEG encodes made here (not the camera's own)

    def wants_raw(self) -> bool:
        """Return True while the raw topic has subscribers."""
        return self.raw.get_subscription_count() > 0

    def wants_compressed(self) -> bool:
        """Return True while the compressed topic has subscribers."""
        return self.compressed.get_subscription_count() > 0

    def publish(self, header, image: Callable[[], Optional[np.ndarray]],
                jpeg: Optional[np.ndarray] = None, encoding: str = 'bgr8',
                picture: Optional[Callable[[], Optional[np.ndarray]]] = None
                ) -> Tuple[bool, bool]:
        """
        Publish one frame with header to the topics that have subscribers.

        image() returns the pixels in `encoding` (it may convert or decode); jpeg is the
        camera's own JPEG, published as it is; picture() returns the 8-bit picture (BGR, or one
        channel for a grey one) a JPEG is encoded from when there is none (image() when not
        given: `encoding` is bgr8 or mono8 then). Returns (raw published, compressed published).
        """
        raw_done = compressed_done = False
        if self.wants_raw() or not self._lazy_raw:
            pixels = image()
            if pixels is None:
                return False, False  # not a whole image (a JPEG that does not decode): no part
            msg = self._bridge.cv2_to_imgmsg(pixels, encoding)
            msg.header = header
            self.raw.publish(msg)
            raw_done = True
        if self.wants_compressed():
            what = JPEG_FORMAT
            if jpeg is None:
                source = (picture or image)()
                if source is not None:
                    ok, encoded = cv2.imencode(
                        '.jpg', source, [cv2.IMWRITE_JPEG_QUALITY, self.jpeg_quality])
                    jpeg = encoded if ok else None
                    what = MONO_JPEG_FORMAT if source.ndim == 2 else JPEG_FORMAT
                    self.encoded += 1
            if jpeg is not None:
                msg = CompressedImage(header=header, format=what)
                fill_message_data(msg, jpeg)
                self.compressed.publish(msg)
                compressed_done = True
        return raw_done, compressed_done


def subscribe(node, base_topic: str, transport: str, callback,
              depth: int = 10) -> ImageSubscription:
    """
    Subscribe to base_topic's frames as `transport` says: raw Images or CompressedImages.

    The subscription hears reliable and best-effort publishers alike (qos.ImageSubscription).
    """
    if transport == 'compressed':
        return ImageSubscription(node, CompressedImage, compressed_topic(node, base_topic),
                                 callback, depth=depth)
    return ImageSubscription(node, Image, base_topic, callback, depth=depth)
