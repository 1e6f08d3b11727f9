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

A camera's own H.264 or HEVC goes out untouched, one access unit per message, by
`VideoPublisher`: as ``foxglove_msgs/CompressedVideo`` on ``T/foxglove`` (the topic of
image_transport's foxglove plugin) where foxglove_msgs 3.0 or newer is installed, else as
``sensor_msgs/CompressedImage`` with format ``h264`` (``h265``) on ``T/h264`` (``T/h265``);
docs/transport.md says why.
"""

from dataclasses import dataclass
import threading
from typing import Callable, List, Optional, Tuple

import cv2
import numpy as np
from py_vision.cv_bridge import fill_message_data, share_message_data
from py_vision.frame_memory import FrameStream
from py_vision.params import Parameters, Spec
from py_vision.qos import create_publisher, ImageSubscription
from py_vision.serialized import SerializedImage
from py_vision.serialized_publisher import SerializedPublisher
from py_vision.throttled_log import ThrottledLog
from sensor_msgs.msg import CompressedImage, Image

try:
    from foxglove_msgs.msg import CompressedVideo
except ImportError:  # not installed, or older than 3.0 (Humble's boards have neither)
    CompressedVideo = None

TRANSPORTS = ('raw', 'compressed')
# The topics a camera's own video may be on, by their last name (`video_topic`).
VIDEO_TRANSPORTS = ('foxglove', 'h264', 'h265')
# The largest image a subscriber takes: an 8K bgr8 frame (7680x4320) is 99.5 MB.
MAX_IMAGE = Spec('max_image_mb', 100.0, 'largest image taken, in MB (1e6 bytes) of pixels: a '
                 'larger one (from any member of the ROS domain) is refused with a warning',
                 (0.001, 10000.0))
JPEG_FORMAT = 'bgr8; jpeg compressed bgr8'
MONO_JPEG_FORMAT = 'mono8; jpeg compressed mono8'
_SOF_MARKERS = frozenset(range(0xC0, 0xD0)) - {0xC4, 0xC8, 0xCC}
_NO_PIXELS = np.empty(0, np.uint8)   # what a kept message holds between frames


def image_topics(resolved_base: str) -> Tuple[str, ...]:
    """Return every topic a subscriber may read base's frames on: raw, compressed, video."""
    return (resolved_base,) + tuple('%s/%s' % (resolved_base, transport)
                                    for transport in ('compressed',) + VIDEO_TRANSPORTS)


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

    Raw images go out serialized (py_vision.serialized): the Image's bytes are kept in a
    buffer of the publisher's own, reused frame after frame, and the pixels are written into
    it once (by the conversion itself where the caller can convert into it, `into`), then
    handed to the middleware as they are (SerializedPublisher). Where rclpy does not allow that
    they go out as an Image message holding the pixels, which rclpy copies. A camera may write
    its frames straight into messages of the publisher's own (`frame_buffers()`): a frame
    published as it was captured (`in_buffer`) then goes out without a copy.

    With lazy_raw False the raw image is published whatever its subscribers (a benchmark's
    stream, whose cost must not depend on who listens).

    publish() may be called from more than one thread (a camera's video decoder ending while
    the next one starts): one frame at a time goes through the buffer.
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
        # The last raw message and its layout: frame after frame of one layout, only its
        # header and data change (the bridge checked the layout once).
        self._raw_msg, self._raw_layout = None, None
        self._serialized = SerializedPublisher(self.raw)
        self._image = SerializedImage()
        # The fields of the last image's message (height, width, encoding, step, is_bigendian,
        # size) and its pixels' place in the serialized message: (its bytes, them shaped as
        # the image).
        self._fields = None
        self._pixels = None
        # Messages a camera captures into (frame_buffers), by the camera's buffer index.
        self._slots: Optional[List[SerializedImage]] = None
        self._lock = threading.Lock()

    def frame_buffers(self, count: int, nbytes: int) -> Optional[List[np.ndarray]]:
        """
        Return count arrays of nbytes for a camera to write its frames into, or None.

        Each is the pixel bytes of a raw message of the publisher's own (SerializedImage
        with a capacity), whose fields are laid out before them: a frame published with
        in_buffer=index goes out as it was captured, never copied. The same messages are
        handed out again while count and size allow (the camera that had them is closed by
        then); None where raw images do not go out serialized.
        """
        if not self._serialized.available:
            return None
        with self._lock:
            slots = self._slots
            if slots is None or len(slots) != count or slots[0].pixels().size < nbytes:
                self._slots = slots = [SerializedImage(nbytes) for _ in range(count)]
            return [slot.pixels()[:nbytes] for slot in slots]

    def _raw_message(self, pixels: np.ndarray, encoding: str) -> Image:
        """
        Return an Image of pixels holding their bytes themselves, not a copy.

        It is published at once: rclpy copies the bytes (a camera's own buffer, with native)
        into the middleware's message then, and the message lets them go.
        """
        layout = (pixels.shape, pixels.dtype.str, encoding)
        if layout != self._raw_layout:
            self._raw_msg = self._bridge.cv2_to_imgmsg(pixels, encoding, share=True)
            self._raw_layout = layout
        else:
            share_message_data(self._raw_msg, pixels)
        return self._raw_msg

    def _publish_in_place(self, header, image, encoding, in_buffer) -> bool:
        """Publish the message a frame was captured into; False where image() is not in it."""
        slots = self._slots
        if slots is None or not 0 <= in_buffer < len(slots):
            return False
        slot = slots[in_buffer]
        pixels = image()
        # The message holds exactly the image's bytes, or its copy goes out instead.
        if pixels is None or not pixels.flags.c_contiguous or \
                pixels.__array_interface__['data'][0] != slot.pixels_address:
            return False
        self._lay_out(pixels, encoding)
        try:
            slot.prepare(header, *self._fields)
        except ValueError:
            return False
        self._serialized.publish_at(*slot.where())
        return True

    def _publish_raw(self, header, image, encoding, into, in_buffer=None) -> bool:
        """Publish the raw image; False when it is not a whole image (nothing published)."""
        if in_buffer is not None and self._publish_in_place(header, image, encoding, in_buffer):
            return True
        if not self._serialized.available:
            pixels = image()
            if pixels is None:
                return False
            msg = self._raw_message(pixels, encoding)
            msg.header = header
            try:
                self.raw.publish(msg)
            finally:
                # The message is kept for the next frame, its bytes not: they may be the
                # camera's buffer, which must be unmapped when the camera is released.
                share_message_data(msg, _NO_PIXELS)
            return True
        if into is not None and self._fields is not None and self._raw_layout[2] == encoding:
            # Written straight into the message laid out as the last frame's.
            out = self._pixels_out(header)
            pixels = into(out)
            if pixels is out:
                self._serialized.publish_at(*self._image.where())
                return True
        else:
            pixels = image()
        if pixels is None:
            return False
        self._lay_out(pixels, encoding)
        out = self._pixels_out(header)
        np.copyto(out, pixels)
        self._serialized.publish_at(*self._image.where())
        return True

    def _lay_out(self, pixels: np.ndarray, encoding: str) -> None:
        """Take pixels' layout for the messages from now on (the bridge checks it once)."""
        layout = (pixels.shape, pixels.dtype.str, encoding)
        if layout != self._raw_layout:
            msg = self._bridge.cv2_to_imgmsg(pixels, encoding, share=True)
            self._fields = (msg.height, msg.width, msg.encoding, msg.step, msg.is_bigendian,
                            pixels.nbytes)
            self._raw_layout = layout
            self._pixels = None

    def _pixels_out(self, header) -> np.ndarray:
        """Lay the message out with header; return its pixel bytes, shaped as the image."""
        self._image.prepare(header, *self._fields)
        data = self._image.data()
        if self._pixels is None or self._pixels[0] is not data:
            shape, dtype, _ = self._raw_layout
            self._pixels = (data, data.view(dtype).reshape(shape))
        return self._pixels[1]

    def wants_raw(self) -> bool:
        """Return True while the raw topic has subscribers."""
        return self.raw.get_subscription_count() > 0

    def wants_compressed(self) -> bool:
        """Return True while the compressed topic has subscribers."""
        return self.compressed.get_subscription_count() > 0

    def publish(self, header, image: Callable[[], Optional[np.ndarray]],
                jpeg: Optional[np.ndarray] = None, encoding: str = 'bgr8',
                picture: Optional[Callable[[], Optional[np.ndarray]]] = None,
                into: Optional[Callable[[np.ndarray], Optional[np.ndarray]]] = None,
                in_buffer: Optional[int] = None) -> Tuple[bool, bool]:
        """
        Publish one frame with header to the topics that have subscribers.

        image() returns the pixels in `encoding` (it may convert or decode); into(out), when
        given, writes them into out instead, an array shaped as the last frame's image (the
        message's own bytes), and returns out, or the image in an array of its own where it
        does not fit out, or None as image() does; jpeg is the camera's own JPEG, published as
        it is; picture() returns the 8-bit picture (BGR, or one channel for a grey one) a JPEG
        is encoded from when there is none (image() when not given: `encoding` is bgr8 or
        mono8 then); in_buffer, the index of the frame_buffers() array the frame was captured
        into, if it was (the raw message is that one's where image() is exactly its bytes).
        Returns (raw published, compressed published).
        """
        with self._lock:
            return self._publish(header, image, jpeg, encoding, picture, into, in_buffer)

    def _publish(self, header, image, jpeg, encoding, picture, into,
                 in_buffer) -> Tuple[bool, bool]:
        raw_done = compressed_done = False
        if self.wants_raw() or not self._lazy_raw:
            if not self._publish_raw(header, image, encoding, into, in_buffer):
                return False, False  # not a whole image (a JPEG that does not decode): no part
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
                share_message_data(msg, jpeg)
                self.compressed.publish(msg)
                compressed_done = True
        return raw_done, compressed_done


def image_bytes(msg) -> int:
    """Return the bytes an image holds: an Image's pixels, a JPEG's decoded, or the data."""
    if isinstance(msg, Image):
        return max(len(msg.data), msg.height * msg.step)
    size = jpeg_size(msg.data) if isinstance(msg, CompressedImage) and len(msg.data) else None
    return max(len(msg.data), size[0] * size[1] * 3 if size else 0)


class _SizeLimit:
    """
    A subscription's callback that refuses images over max_bytes before anything else.

    The frames it lets through are counted by size (frame_memory.FrameStream): the process
    keeps the memory of a stream's frames for the next ones.
    """

    def __init__(self, node, callback, max_bytes: float):
        self._callback = callback
        self._max_bytes = max_bytes
        self._log = ThrottledLog(node.get_logger())
        self._frames = FrameStream()
        self.subscription: Optional[ImageSubscription] = None

    def __call__(self, msg):
        size = image_bytes(msg)
        if size <= self._max_bytes:
            self._frames.frame(size)
            self._callback(msg)
            return
        what = '%dx%d %s' % (msg.width, msg.height, msg.encoding) if isinstance(
            msg, Image) else msg.format
        self._log.warning('too large', 'refused a %s image of %.1f MB on %s: over max_image_mb '
                          '(%g MB)' % (what[:40], size / 1e6, self.subscription.topic_name,
                                       self._max_bytes / 1e6))
        self.subscription.renew()


def subscribe(node, base_topic: str, transport: str, callback, depth: int = 10,
              max_image_mb: float = MAX_IMAGE.default) -> ImageSubscription:
    """
    Subscribe to base_topic's frames as `transport` says: raw Images or CompressedImages.

    With a video transport (VIDEO_TRANSPORTS) it reads the camera's own access units:
    CompressedVideo on ``T/foxglove``, CompressedImage on ``T/h264`` or ``T/h265``; ValueError
    when foxglove is asked for and foxglove_msgs is not installed. The subscription hears
    reliable and best-effort publishers alike (qos.ImageSubscription) and takes its frames on
    a thread of its own, where callback runs (not the executor's); close() it before the node
    is destroyed. An image over max_image_mb (of pixels, or of compressed data) never reaches
    callback: it is one rate-limited warning, and the subscription is made anew so that the
    memory the middleware took for it is given back.
    """
    limit = _SizeLimit(node, callback, max_image_mb * 1e6)
    if transport in VIDEO_TRANSPORTS:
        topic = node.resolve_topic_name(base_topic) + '/' + transport
        msg_type = CompressedImage
        if transport == 'foxglove':
            if CompressedVideo is None:
                raise ValueError(
                    'image_transport foxglove reads foxglove_msgs/CompressedVideo, and '
                    'foxglove_msgs 3.0 or newer is not installed here; a py_vision camera '
                    'without it publishes on %s/h264 (image_transport:=h264)' % (
                        node.resolve_topic_name(base_topic)))
            msg_type = CompressedVideo
        subscription = ImageSubscription(node, msg_type, topic, limit, depth=depth)
    elif transport == 'compressed':
        subscription = ImageSubscription(node, CompressedImage,
                                         compressed_topic(node, base_topic), limit, depth=depth)
    else:
        subscription = ImageSubscription(node, Image, base_topic, limit, depth=depth)
    limit.subscription = subscription
    return subscription


@dataclass(frozen=True)
class VideoTopic:
    """The message a camera's access units go out in, and the topic's last name."""

    msg_type: type
    transport: str       # 'foxglove', or the codec's format ('h264', 'h265') on the fallback

    @property
    def fallback(self) -> bool:
        """Return True when the chosen message (CompressedVideo) is not installed here."""
        return self.msg_type is CompressedImage

    def message(self, header, data, video_format: str):
        """Return the message of one access unit (bytes or 1-D uint8) with header's stamp."""
        if self.fallback:
            msg = CompressedImage(header=header, format=video_format)
        else:
            msg = self.msg_type(timestamp=header.stamp, frame_id=header.frame_id,
                                format=video_format)
        fill_message_data(msg, np.frombuffer(data, np.uint8))
        return msg


def video_topic(video_format: str, compressed_video=CompressedVideo) -> VideoTopic:
    """Return where access units of video_format ('h264', 'h265') go with what is installed."""
    if compressed_video is None:
        return VideoTopic(CompressedImage, video_format)
    return VideoTopic(compressed_video, 'foxglove')


def video_fields(msg):
    """Return (stamp, frame_id, format) of a CompressedVideo or a CompressedImage."""
    if isinstance(msg, CompressedImage):
        return msg.header.stamp, msg.header.frame_id, msg.format
    return msg.timestamp, msg.frame_id, msg.format


class VideoPublisher:
    """A camera's own H.264 or HEVC access units, published untouched while someone listens."""

    def __init__(self, parameters: Parameters, base_topic: str, qos, video_format: str,
                 compressed_video=CompressedVideo):
        node = parameters.node
        self.format = video_format
        self.topic = video_topic(video_format, compressed_video)
        self.name = node.resolve_topic_name(base_topic) + '/' + self.topic.transport
        self.publisher = create_publisher(parameters, self.topic.msg_type, self.name, qos)
        if self.topic.fallback:
            node.get_logger().warning(
                "foxglove_msgs 3.0 or newer (CompressedVideo) is not installed: the camera's "
                '%s goes out as sensor_msgs/CompressedImage (format %s) on %s; Foxglove and '
                "image_transport's foxglove plugin read foxglove_msgs/CompressedVideo on "
                '%s/foxglove (install ros-$ROS_DISTRO-foxglove-msgs)' % (
                    video_format.upper(), video_format, self.name,
                    node.resolve_topic_name(base_topic)))

    def wants(self) -> bool:
        """Return True while the video topic has subscribers."""
        return self.publisher.get_subscription_count() > 0

    def publish(self, header, data) -> None:
        """Publish one access unit (the camera's bytes) with the frame's header."""
        self.publisher.publish(self.topic.message(header, data, self.format))
