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
cdr_image against rclpy's own serialisation, and serialized_take against a real subscription.

Every message is serialized by rclpy (the middleware's type support, Humble's or Jazzy's) and
read back by cdr_image, which must give the same fields and the same pixels, without copying
them; a buffer that is not a whole, well-formed Image raises CdrError, never a wrong image.
"""

import struct
import time

import numpy as np
from py_vision.cdr_image import CdrError, image_message
from py_vision.cv_bridge import CvBridge
from py_vision.receive_thread import OwnThread
from py_vision.serialized_take import SerializedTake
import pytest
from rclpy.qos import QoSProfile, ReliabilityPolicy
from rclpy.serialization import deserialize_message, serialize_message
from ros_harness import wait_until
from sensor_msgs.msg import Image


def image(width, height, encoding, step, frame_id='camera', sec=1700000000, nanosec=123,
          is_bigendian=0, data=None):
    msg = Image(width=width, height=height, encoding=encoding, step=step,
                is_bigendian=is_bigendian)
    msg.header.frame_id = frame_id
    msg.header.stamp.sec = sec
    msg.header.stamp.nanosec = nanosec
    if data is None:
        data = np.random.default_rng(width * 7 + height).integers(
            0, 256, height * step, np.uint8).tobytes()
    msg.data = data
    return msg


CASES = [
    image(640, 480, 'bgr8', 1920),
    image(3, 2, 'mono8', 3, frame_id=''),             # empty string: alignment after it
    image(5, 3, 'rgb8', 16, frame_id='a'),            # a padded row, odd lengths everywhere
    image(4, 4, 'mono16', 8, frame_id='tiefe', is_bigendian=1),
    image(2, 2, '32FC1', 8, frame_id='caméra/ü', sec=-5, nanosec=999999999),
    image(7, 1, 'yuv422_yuy2', 14, frame_id='x' * 63),
    image(1, 1, 'bgr8', 3, frame_id='', sec=0, nanosec=0, data=b'\x01\x02\x03'),
    image(0, 0, '', 0, frame_id='', data=b''),
]


def fields(msg):
    return (msg.header.stamp.sec, msg.header.stamp.nanosec, msg.header.frame_id, msg.height,
            msg.width, msg.encoding, msg.is_bigendian, msg.step, bytes(msg.data))


def case_name(msg):
    return '%dx%d %s' % (msg.width, msg.height, msg.encoding or 'empty')


@pytest.mark.parametrize('msg', CASES, ids=case_name)
def test_every_field_reads_as_rclpy_deserialises_it(msg):
    serialized = serialize_message(msg)
    expected = deserialize_message(serialized, Image)
    got = image_message(np.frombuffer(serialized, np.uint8).copy())
    assert isinstance(got, Image)
    assert fields(got) == fields(expected) == fields(msg)


def big_endian(msg):
    """Return msg serialized as big-endian CDR (what a big-endian machine's middleware sends)."""
    out = bytearray(b'\x00\x00\x00\x00')

    def align(size):
        out.extend(b'\x00' * (-(len(out) - 4) % size))

    def u32(value, code='>I'):
        align(4)
        out.extend(struct.pack(code, value))

    def string(text):
        raw = text.encode() + b'\x00'
        u32(len(raw))
        out.extend(raw)
    u32(msg.header.stamp.sec, '>i')
    u32(msg.header.stamp.nanosec)
    string(msg.header.frame_id)
    u32(msg.height)
    u32(msg.width)
    string(msg.encoding)
    out.append(msg.is_bigendian)
    u32(msg.step)
    u32(len(msg.data))
    out.extend(bytes(msg.data))
    return bytes(out)


@pytest.mark.parametrize('msg', CASES[:5], ids=lambda m: m.encoding)
def test_big_endian_cdr_reads_the_same(msg):
    assert fields(image_message(big_endian(msg))) == fields(msg)


def test_the_pixels_are_a_view_of_the_buffer_writable_where_it_is():
    buffer = np.frombuffer(serialize_message(CASES[0]), np.uint8).copy()
    msg = image_message(buffer)
    assert np.shares_memory(msg.data, buffer)
    frame = CvBridge().imgmsg_to_cv2(msg)
    assert np.shares_memory(frame, buffer), 'the bridge copied a writable frame'
    frame[0, 0] = (1, 2, 3)
    assert tuple(buffer[-640 * 480 * 3:][:3]) == (1, 2, 3)
    # From bytes (read-only) the bridge gives a copy the caller may draw on.
    read_only = image_message(serialize_message(CASES[0]))
    assert not read_only.data.flags.writeable
    assert CvBridge().imgmsg_to_cv2(read_only).flags.writeable


def test_every_truncation_is_an_error_never_an_image():
    serialized = serialize_message(CASES[2])
    for length in range(len(serialized)):
        with pytest.raises(CdrError, match='truncated'):
            image_message(serialized[:length])


def corrupted(offset, value):
    serialized = bytearray(serialize_message(CASES[2]))
    struct.pack_into('<I', serialized, offset, value)
    return bytes(serialized)


# CASES[2]: frame_id 'a' (length at 12), encoding (length at 28), data length at 44.
@pytest.mark.parametrize('offset, value, error', [
    (12, 1000, 'header.frame_id needs 1000 bytes'),
    (12, 0xFFFFFFFF, 'header.frame_id needs 4294967295 bytes'),
    (28, 10**6, 'encoding needs 1000000 bytes'),
    (44, 49, 'data needs 49 bytes'),
    (44, 0xFFFFFFFF, 'data needs 4294967295 bytes'),
])
def test_a_length_past_the_end_is_an_error(offset, value, error):
    with pytest.raises(CdrError, match=error):
        image_message(corrupted(offset, value))


def test_a_string_without_its_nul_is_an_error():
    serialized = bytearray(serialize_message(CASES[2]))
    serialized[17] = ord('b')  # frame_id 'a\0' -> 'ab'
    with pytest.raises(CdrError, match='header.frame_id of 2 bytes does not end with NUL'):
        image_message(bytes(serialized))


@pytest.mark.parametrize('head', [b'\x00\x02', b'\x00\x07', b'\x01\x00', b'\xff\xff'])
def test_another_encapsulation_is_an_error(head):
    serialized = head + serialize_message(CASES[1])[2:]
    with pytest.raises(CdrError, match='not plain CDR'):
        image_message(serialized)


def test_not_bytes_is_an_error():
    with pytest.raises(CdrError, match='1-D array of bytes'):
        image_message(np.zeros((4, 4), np.uint8))
    with pytest.raises(CdrError, match='truncated'):
        image_message(b'')


def test_a_subscription_taken_serialized_gives_what_was_published(peer):
    assert SerializedTake.usable(), 'librcl.so / librcutils.so not found in this process'
    # A callback group the peer's executor leaves alone: only the take below takes.
    subscription = peer.node.create_subscription(
        Image, 'serialized_take', lambda msg: None,
        QoSProfile(depth=10, reliability=ReliabilityPolicy.RELIABLE),
        callback_group=OwnThread())
    publisher = peer.node.create_publisher(Image, 'serialized_take', 10)
    wait_until(lambda: publisher.get_subscription_count() > 0, 20, what='matching')
    taker = SerializedTake()
    with subscription.handle:
        assert taker.take(subscription.handle) is None  # nothing yet
    for msg in CASES[:4]:
        publisher.publish(msg)
        deadline = time.monotonic() + 20
        taken = None
        while taken is None and time.monotonic() < deadline:
            with subscription.handle:
                taken = taker.take(subscription.handle)
            time.sleep(0.01)
        assert taken is not None, 'nothing taken within 20 s'
        assert taken.flags.writeable
        # The same message as rclpy serialises it (its padding bytes are whatever they were).
        assert len(taken) == len(serialize_message(msg))
        assert fields(image_message(taken)) == fields(msg)
    peer.node.destroy_subscription(subscription)
