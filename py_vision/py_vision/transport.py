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
compressed plugin writes it for bgr8); ``camera_info`` beside it (``<dir of T>/camera_info``)
carries their ``CameraInfo``. `ImagePublisher` produces each form only while its topic has
subscribers, and publishes a camera's own JPEG untouched. `subscribe()` is what an
image_transport subscriber's ``image_transport`` parameter (``raw`` or ``compressed``) chooses.
"""

from typing import Callable, Optional, Tuple

import cv2
import numpy as np
from py_vision.cv_bridge import fill_message_data
from py_vision.params import Spec
from py_vision.qos import ImageSubscription
from py_vision.throttled_log import ThrottledLog
from sensor_msgs.msg import CompressedImage, Image

TRANSPORTS = ('raw', 'compressed')
# The largest image a subscriber takes: an 8K bgr8 frame (7680x4320) is 99.5 MB.
MAX_IMAGE = Spec('max_image_mb', 100.0, 'largest image taken, in MB (1e6 bytes) of pixels: a '
                 'larger one (from any member of the ROS domain) is refused with a warning',
                 (0.001, 10000.0))

JPEG_FORMAT = 'bgr8; jpeg compressed bgr8'
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

    def __init__(self, node, base_topic: str, qos, bridge, lazy_raw: bool = True):
        self._bridge = bridge
        self._lazy_raw = lazy_raw
        self.raw = node.create_publisher(Image, base_topic, qos)
        self.compressed = node.create_publisher(
            CompressedImage, compressed_topic(node, base_topic), qos)
        self.jpeg_quality = 80
        self.encoded = 0        # JPEG encodes made here (not the camera's own)

    def wants_raw(self) -> bool:
        """Return True while the raw topic has subscribers."""
        return self.raw.get_subscription_count() > 0

    def wants_compressed(self) -> bool:
        """Return True while the compressed topic has subscribers."""
        return self.compressed.get_subscription_count() > 0

    def publish(self, header, bgr: Callable[[], Optional[np.ndarray]],
                jpeg: Optional[np.ndarray] = None) -> Tuple[bool, bool]:
        """
        Publish one frame with header to the topics that have subscribers.

        bgr() returns the pixels (it may decode); jpeg is the camera's own JPEG, published as
        it is. Returns (raw published, compressed published).
        """
        raw_done = compressed_done = False
        if self.wants_raw() or not self._lazy_raw:
            image = bgr()
            if image is None:
                return False, False  # not a whole image (a JPEG that does not decode): no part
            msg = self._bridge.cv2_to_imgmsg(image, 'bgr8')
            msg.header = header
            self.raw.publish(msg)
            raw_done = True
        if self.wants_compressed():
            if jpeg is None:
                image = bgr()
                if image is not None:
                    ok, encoded = cv2.imencode(
                        '.jpg', image, [cv2.IMWRITE_JPEG_QUALITY, self.jpeg_quality])
                    jpeg = encoded if ok else None
                    self.encoded += 1
            if jpeg is not None:
                msg = CompressedImage(header=header, format=JPEG_FORMAT)
                fill_message_data(msg, jpeg)
                self.compressed.publish(msg)
                compressed_done = True
        return raw_done, compressed_done


def image_bytes(msg) -> int:
    """Return the bytes an Image holds, or a CompressedImage decodes to (as far as it says)."""
    if isinstance(msg, CompressedImage):
        size = jpeg_size(msg.data) if len(msg.data) else None
        return max(len(msg.data), size[0] * size[1] * 3 if size else 0)
    return max(len(msg.data), msg.height * msg.step)


class _SizeLimit:
    """A subscription's callback that refuses images over max_bytes before anything else."""

    def __init__(self, node, callback, max_bytes: float):
        self._callback = callback
        self._max_bytes = max_bytes
        self._log = ThrottledLog(node.get_logger())
        self.subscription: Optional[ImageSubscription] = None

    def __call__(self, msg):
        size = image_bytes(msg)
        if size <= self._max_bytes:
            self._callback(msg)
            return
        what = msg.format if isinstance(msg, CompressedImage) else '%dx%d %s' % (
            msg.width, msg.height, msg.encoding)
        self._log.warning('too large', 'refused a %s image of %.1f MB on %s: over max_image_mb '
                          '(%g MB)' % (what[:40], size / 1e6, self.subscription.topic_name,
                                       self._max_bytes / 1e6))
        self.subscription.renew()


def subscribe(node, base_topic: str, transport: str, callback, depth: int = 10,
              max_image_mb: float = MAX_IMAGE.default) -> ImageSubscription:
    """
    Subscribe to base_topic's frames as `transport` says: raw Images or CompressedImages.

    The subscription hears reliable and best-effort publishers alike (qos.ImageSubscription).
    An image over max_image_mb (of pixels, or of JPEG data) never reaches callback: it is one
    rate-limited warning, and the subscription is made anew so that the memory the middleware
    took for it is given back.
    """
    limit = _SizeLimit(node, callback, max_image_mb * 1e6)
    if transport == 'compressed':
        subscription = ImageSubscription(node, CompressedImage,
                                         compressed_topic(node, base_topic), limit, depth=depth)
    else:
        subscription = ImageSubscription(node, Image, base_topic, limit, depth=depth)
    limit.subscription = subscription
    return subscription
