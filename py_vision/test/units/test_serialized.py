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
Messages kept serialized (py_vision.serialized) and published as they are.

rclpy is the oracle, of this run's ROS (Humble's rclpy 3.3.2 or Jazzy's): the bytes
SerializedImage writes deserialize (rclpy.serialization.deserialize_message) to the Image
rclpy would have sent, and are as long as rclpy's own serialization of it, for every encoding
name the bridge knows and odd sizes, frame_ids and steps (which move the fields' alignment and
padding); a CameraInfo's bytes follow its stamp and frame_id. Published through rcl
(SerializedPublisher), and by ImagePublisher frame after frame, with and without a conversion
written into the message, they reach a subscriber as the Image the bridge makes of the pixels.
"""

import ctypes
import threading
import time
from types import SimpleNamespace

from hypothesis import given, HealthCheck, settings, strategies as st
import numpy as np
from py_vision.capture.pixel_formats import FORMATS
from py_vision.capture.source import Frame
from py_vision.cv_bridge import CvBridge
from py_vision.params import Parameters
from py_vision.rcl_c import error_text
from py_vision.serialized import SerializedImage, SerializedStamped
from py_vision.serialized_publisher import SerializedPublisher, StampedPublisher
from py_vision.transport import ImagePublisher
import pytest
import rclpy
from rclpy.context import Context
from rclpy.executors import SingleThreadedExecutor
from rclpy.qos import QoSProfile, ReliabilityPolicy
from rclpy.serialization import deserialize_message, serialize_message
import ros_harness
from sensor_msgs.msg import CameraInfo, Image
from std_msgs.msg import Header

SETTINGS = settings(max_examples=200, deadline=None,
                    suppress_health_check=[HealthCheck.function_scoped_fixture])
# Every encoding sensor_msgs/image_encodings names (and the bridge reads), of every length.
ENCODINGS = (
    ['rgb8', 'rgba8', 'rgb16', 'rgba16', 'bgr8', 'bgra8', 'bgr16', 'bgra16', 'mono8', 'mono16',
     'yuv422', 'yuv422_yuy2', 'uyvy', 'yuyv', 'nv21', 'nv24', '']
    + ['bayer_%s%d' % (pattern, bits) for pattern in ('rggb', 'bggr', 'gbrg', 'grbg')
       for bits in (8, 16)]
    + ['%s%s' % (depth, suffix) for depth in ('8UC', '8SC', '16UC', '16SC', '32SC', '32FC',
                                              '64FC') for suffix in ('1', '2', '3', '4', '')])
RELIABLE = QoSProfile(depth=10, reliability=ReliabilityPolicy.RELIABLE)


def header(frame_id='camera', sec=1700000000, nanosec=123456789):
    msg = Header(frame_id=frame_id)
    msg.stamp.sec, msg.stamp.nanosec = sec, nanosec
    return msg


def reference(head, height, width, encoding, step, is_bigendian, data):
    return Image(header=head, height=height, width=width, encoding=encoding,
                 is_bigendian=is_bigendian, step=step, data=bytes(data))


def written(serialized, head, height, width, encoding, step, is_bigendian, data):
    serialized.prepare(head, height, width, encoding, step, is_bigendian, len(data))
    serialized.data()[:] = np.frombuffer(data, np.uint8)
    return serialized.message().tobytes()


@SETTINGS
@given(encoding=st.sampled_from(ENCODINGS),
       frame_id=st.text(st.characters(blacklist_categories=('Cs',), blacklist_characters='\0'),
                        max_size=9),
       height=st.integers(0, 5), width=st.integers(0, 7), pixel_bytes=st.integers(1, 8),
       padding=st.integers(0, 5), is_bigendian=st.booleans(),
       sec=st.integers(-2 ** 31, 2 ** 31 - 1), nanosec=st.integers(0, 2 ** 32 - 1))
def test_an_image_deserializes_to_what_rclpy_sends(
        encoding, frame_id, height, width, pixel_bytes, padding, is_bigendian, sec, nanosec):
    step = width * pixel_bytes + padding
    data = bytes(np.random.default_rng(height * 7 + width).integers(
        0, 256, step * height, np.uint8))
    head = header(frame_id, sec, nanosec)
    ours = written(SerializedImage(), head, height, width, encoding, step, is_bigendian, data)
    expected = reference(head, height, width, encoding, step, is_bigendian, data)
    assert deserialize_message(ours, Image) == expected
    assert len(ours) == len(serialize_message(expected))


def test_every_encoding_at_odd_sizes_in_one_buffer_as_the_layout_changes():
    serialized = SerializedImage()
    rng = np.random.default_rng(5)
    for index, encoding in enumerate(ENCODINGS):
        for width, height, frame_id in ((1, 1, ''), (3, 5, 'a'), (7, 2, 'ab'), (5, 3, 'abc'),
                                        (641, 3, 'camera_é')):
            step = width * (1 + index % 4) + index % 3
            data = rng.integers(0, 256, step * height, np.uint8).tobytes()
            head = header(frame_id, index, width)
            ours = written(serialized, head, height, width, encoding, step, index % 2, data)
            expected = reference(head, height, width, encoding, step, index % 2, data)
            assert deserialize_message(ours, Image) == expected, (encoding, width, frame_id)
            assert len(ours) == len(serialize_message(expected))


def test_a_message_of_the_same_layout_changes_its_stamp_and_pixels_only():
    serialized = SerializedImage()
    first = written(serialized, header(sec=1), 2, 3, 'rgb8', 9, False, bytes(range(18)))
    before = serialized.message()
    second = written(serialized, header(sec=2, nanosec=5), 2, 3, 'rgb8', 9, False,
                     bytes(range(18, 36)))
    assert serialized.message().ctypes.data == before.ctypes.data, 'the same bytes, reused'
    assert deserialize_message(second, Image) == reference(
        header(sec=2, nanosec=5), 2, 3, 'rgb8', 9, False, bytes(range(18, 36)))
    changed = [i for i, (a, b) in enumerate(zip(first, second)) if a != b]
    data_at = len(second) - 18
    assert all(4 <= i < 12 or i >= data_at for i in changed), changed


def test_the_pixels_start_on_a_cache_line_whatever_the_frame_id():
    serialized = SerializedImage()
    for frame_id in ('', 'a', 'ab', 'abc', 'abcd', 'camera_optical_frame'):
        serialized.prepare(header(frame_id), 480, 640, 'bgr8', 1920)
        assert serialized.data().ctypes.data % 64 == 0
        assert serialized.data().size == 480 * 1920


def test_a_stamp_or_size_out_of_range_is_refused():
    # Humble's messages refuse such a stamp themselves; Jazzy's take it unless told to check.
    for sec, nanosec in ((2 ** 31, 0), (0, -1), (0, 2 ** 32)):
        stamp = SimpleNamespace(sec=sec, nanosec=nanosec)
        with pytest.raises(ValueError):
            SerializedImage().prepare(SimpleNamespace(frame_id='', stamp=stamp), 1, 1, 'mono8',
                                      1)
    with pytest.raises(ValueError):
        SerializedImage().prepare(header(), 2 ** 32, 1, 'mono8', 1)


def test_a_camera_info_follows_its_stamp_frame_id_and_replacement():
    info = CameraInfo(header=header('cam'), width=640, height=480, distortion_model='plumb_bob',
                      d=[0.1, -0.2, 0.0, 0.001, 0.3], k=[500.0, 0, 320, 0, 500, 240, 0, 0, 1],
                      binning_x=2)
    serialized = SerializedStamped()
    for sec, frame_id in ((1, 'cam'), (2, 'cam'), (3, 'a_longer_frame_id'), (4, '')):
        info.header = header(frame_id, sec, sec * 10)
        ours = serialized.message(info).tobytes()
        assert deserialize_message(ours, CameraInfo) == info
        assert len(ours) == len(serialize_message(info))
    replaced = CameraInfo(header=header('', 5), width=320, height=240)
    assert deserialize_message(serialized.message(replaced).tobytes(), CameraInfo) == replaced


def test_pixels_given_a_capacity_stay_in_place_through_every_layout():
    """A camera writes into pixels() once; every layout's message is still rclpy's."""
    serialized = SerializedImage(64 * 48 * 2)
    pixels, address = serialized.pixels(), serialized.pixels_address
    assert address % 4096 == 0 and pixels.size == 64 * 48 * 2
    rng = np.random.default_rng(3)
    for frame_id, (width, height), encoding, step in (
            ('cam', (64, 48), 'yuv422_yuy2', 128),
            ('a_much_longer_frame_id', (64, 48), 'yuv422_yuy2', 128),
            ('', (32, 16), 'mono8', 33), ('camera_é', (64, 48), 'rgb8', 64)):
        data = rng.integers(0, 256, step * height, np.uint8)
        pixels[:data.size] = data          # the camera's bytes, where it wrote them
        head = header(frame_id, width, height)
        serialized.prepare(head, height, width, encoding, step)
        assert serialized.data().ctypes.data == address, 'the pixels moved'
        assert serialized.where()[0] + serialized.where()[1] == address + data.size
        expected = reference(head, height, width, encoding, step, False, data.tobytes())
        assert deserialize_message(serialized.message().tobytes(), Image) == expected


def test_a_layout_that_does_not_fit_around_the_pixels_is_refused():
    serialized = SerializedImage(100)
    with pytest.raises(ValueError, match='does not fit'):
        serialized.prepare(header(), 11, 10, 'mono8', 10)        # 110 bytes of pixels
    with pytest.raises(ValueError, match='does not fit'):
        serialized.prepare(header('f' * 5000), 10, 10, 'mono8', 10)   # fields over a page
    serialized.prepare(header('f' * 4000), 10, 10, 'mono8', 10)
    assert serialized.data().ctypes.data == serialized.pixels_address


@pytest.fixture(scope='module')
def node():
    """Give the tests a node of their own on a ROS domain of their own."""
    domain = ros_harness.DomainId()
    context = Context()
    rclpy.init(args=[], context=context, domain_id=domain.value)
    made = rclpy.create_node('serialized_tests', context=context, enable_rosout=False)
    executor = SingleThreadedExecutor(context=context)
    executor.add_node(made)
    made.test_executor = executor
    yield made
    executor.shutdown()
    made.destroy_node()
    rclpy.shutdown(context=context)
    domain.release()


def receive(node, topic, count, publish, msg_type=Image):
    """Publish with publish(index) until count messages of topic came back; return them."""
    got = []
    subscription = node.create_subscription(msg_type, topic, got.append, RELIABLE)
    try:
        # Published once the subscription is matched, each message then waited for.
        ros_harness.wait_until(lambda: node.count_subscribers(topic) > 0, 10,
                               what='the subscription matched')
        for index in range(count):
            publish(index)
            deadline = time.monotonic() + 10
            while len(got) <= index and time.monotonic() < deadline:
                node.test_executor.spin_once(timeout_sec=0.05)
            assert len(got) == index + 1, 'message %d did not come' % index
    finally:
        node.destroy_subscription(subscription)
    return got


def test_a_serialized_message_goes_out_through_rcl_as_it_is(node):
    publisher = node.create_publisher(Image, 'serialized_image', RELIABLE)
    sender = SerializedPublisher(publisher)
    assert sender.available, "this rclpy's publishers give their rcl publisher"
    serialized, sent = SerializedImage(), []

    def publish(index):
        data = bytes((index + i) % 256 for i in range(3 * 5 * 2))
        written(serialized, header('cam', index), 3, 5, 'yuv422_yuy2', 10, False, data)
        sent.append(reference(header('cam', index), 3, 5, 'yuv422_yuy2', 10, False, data))
        sender.publish(serialized.message())
    assert receive(node, 'serialized_image', 3, publish) == sent
    node.destroy_publisher(publisher)
    with pytest.raises(Exception):   # rclpy's InvalidHandle: no message sent on a dead handle
        sender.publish(serialized.message())


def frame_of(fourcc, width, height, index):
    """Return a Frame of the synthetic picture as a camera of that format sends it."""
    from py_vision.capture.synthetic_picture import synthetic_yuyv
    pixel_format = FORMATS[fourcc]
    data = np.ascontiguousarray(pixel_format.from_yuyv(synthetic_yuyv(index, width, height)))
    return Frame(index, None, pixel_format, width, height, data.reshape(-1).view(np.uint8))


@pytest.mark.parametrize('fourcc,output', [
    ('YUYV', 'bgr8'), ('YUYV', 'native'), ('YUYV', 'mono16'), ('NV21', 'native'),
    ('Y16', 'native'), ('GREY', 'rgb8'), ('BA81', 'native')])
def test_image_publisher_sends_what_the_bridge_makes_of_the_frames(node, fourcc, output):
    """Frames of one size, then another, then the first again, then a new frame_id."""
    topic = 'frames_%s_%s' % (fourcc.lower(), output)
    images = ImagePublisher(Parameters(node), topic, RELIABLE, CvBridge())
    bridge, sent, written_in_place = CvBridge(), [], []
    sizes = [(64, 48), (64, 48), (32, 16), (64, 48), (64, 48)]

    def publish(index):
        width, height = sizes[index]
        frame = frame_of(fourcc, width, height, index)
        head = header('cam' if index < 4 else 'camera_frame', index)
        encoding = frame.encoding(output)
        expected = bridge.cv2_to_imgmsg(frame.image(output).copy(), encoding)
        expected.header = head
        sent.append(expected)
        fresh = frame_of(fourcc, width, height, index)  # nothing converted yet

        def into(out):
            image = fresh.image(output, out)
            written_in_place.append(image is out)
            return image
        assert images.publish(head, lambda: fresh.image(output), None, encoding, None,
                              into) == (True, False)
    assert receive(node, topic, len(sizes), publish) == sent
    # Converted into the message when the frame has the last one's size (a new frame_id moves
    # the pixels, not their shape); into an array of its own, then copied, when not.
    assert written_in_place == [True, False, False, True]


def test_frames_captured_into_the_publishers_messages_go_out_as_they_are(node):
    """The camera's writing into frame_buffers() (USERPTR): published without a copy."""
    images = ImagePublisher(Parameters(node), 'in_place', RELIABLE, CvBridge())
    nbytes = 32 * 16 * 2
    buffers = images.frame_buffers(4, nbytes)
    assert len(buffers) == 4 and all(b.size == nbytes and b.flags.writeable for b in buffers)
    assert images.frame_buffers(4, nbytes)[2].ctypes.data == buffers[2].ctypes.data, \
        'the same messages handed out again'
    bridge, sent, copies = CvBridge(), [], []

    def publish(index):
        frame = frame_of('YUYV', 32, 16, index)
        buffer = index % 4
        buffers[buffer][:] = frame.data       # where the camera wrote the frame
        if index == 5:    # a frame in a buffer that is not one of the messages' any more
            captured = Frame(index, None, frame.pixel_format, 32, 16, frame.data)
        else:
            captured = Frame(index, None, frame.pixel_format, 32, 16, buffers[buffer],
                             user_buffer=buffer)
        expected = bridge.cv2_to_imgmsg(frame.image('native').copy(), 'yuv422_yuy2')
        expected.header = header('cam' if index < 3 else 'camera_frame', index)
        sent.append(expected)

        def into(out):
            copies.append(index)
            return captured.image('native', out)
        assert images.publish(expected.header, lambda: captured.image('native'), None,
                              'yuv422_yuy2', None, into, captured.user_buffer) == (True, False)
    assert receive(node, 'in_place', 6, publish) == sent
    assert copies == [5], 'only the frame outside the messages was copied'


def test_frames_published_from_two_threads_at_once_each_go_out_whole(node):
    """One buffer, one frame at a time: a frame's stamp never goes out with another's pixels."""
    # (A camera's old video decoder thread, ending, while the next one starts publishing.)
    images = ImagePublisher(Parameters(node), 'two_threads', RELIABLE, CvBridge())
    got = []
    subscription = node.create_subscription(Image, 'two_threads', got.append, RELIABLE)
    ros_harness.wait_until(lambda: node.count_subscribers('two_threads') > 0, 10,
                           what='the subscription matched')
    yuyv = FORMATS['YUYV']

    def publish(first):
        for index in range(first, first + 200, 2):
            # A grey of its own per frame: YUYV (Y, 128, Y, 128), converted while the GIL
            # is released (OpenCV), as a camera's frame is.
            data = np.tile(np.array([40 + index % 150, 128], np.uint8), 640 * 480)
            frame = Frame(index, None, yuyv, 640, 480, data)
            images.publish(header('cam', index), lambda: frame.image('bgr8'), None, 'bgr8',
                           None, lambda out: frame.image('bgr8', out))
    threads = [threading.Thread(target=publish, args=(first,)) for first in (0, 1)]
    try:
        for thread in threads:
            thread.start()
        deadline = time.monotonic() + 30
        while any(t.is_alive() for t in threads) and time.monotonic() < deadline:
            node.test_executor.spin_once(timeout_sec=0.01)
        for _ in range(50):
            node.test_executor.spin_once(timeout_sec=0.01)
    finally:
        for thread in threads:
            thread.join(30)
        node.destroy_subscription(subscription)
    assert len(got) >= 20, 'only %d frames came' % len(got)
    for msg in got:
        pixels = np.frombuffer(msg.data, np.uint8)
        luma = 40 + msg.header.stamp.sec % 150
        grey = yuyv.convert(np.array([[[luma, 128], [luma, 128]]], np.uint8), 'bgr8')[0, 0, 0]
        assert pixels.min() == pixels.max() == grey, \
            'frame %d went out with other pixels (%d to %d)' % (
                msg.header.stamp.sec, pixels.min(), pixels.max())


def test_image_publisher_copies_pixels_it_cannot_convert_into(node):
    """vision_step's way: image() alone, the pixels copied into the message once."""
    images = ImagePublisher(Parameters(node), 'drawn', RELIABLE, CvBridge())
    sent = []

    def publish(index):
        pixels = np.full((12, 10, 3), index * 40, np.uint8)
        expected = CvBridge().cv2_to_imgmsg(pixels, 'bgr8')
        expected.header = header('step', index)
        sent.append(expected)
        assert images.publish(header('step', index), lambda: pixels) == (True, False)
    assert receive(node, 'drawn', 3, publish) == sent


def test_where_rcl_cannot_be_reached_images_and_camera_infos_go_out_through_rclpy(node):
    """An rclpy whose publishers do not give their rcl publisher: the messages rclpy sends."""
    images = ImagePublisher(Parameters(node), 'fallback', RELIABLE, CvBridge())
    images._serialized.available = False
    bridge, sent = CvBridge(), []

    def publish(index):
        frame = frame_of('YUYV', 32, 16, index)
        expected = bridge.cv2_to_imgmsg(frame.image('bgr8').copy(), 'bgr8')
        expected.header = header('cam', index)
        sent.append(expected)
        assert images.publish(header('cam', index), lambda: frame.image('bgr8'), None, 'bgr8',
                              None, lambda out: frame.image('bgr8', out)) == (True, False)
    assert receive(node, 'fallback', 3, publish) == sent

    infos = StampedPublisher(node.create_publisher(CameraInfo, 'fallback_info', RELIABLE))
    infos._out.available = False
    info, stamps = CameraInfo(width=32, height=16), []

    def publish_info(index):
        info.header = header('cam', index)
        stamps.append(index)
        infos.publish(info)
    got = receive(node, 'fallback_info', 3, publish_info, CameraInfo)
    assert [msg.header.stamp.sec for msg in got] == stamps
    assert all(msg.width == 32 and msg.header.frame_id == 'cam' for msg in got)


def test_a_publish_rcl_refuses_says_rcls_error_and_leaves_none_behind(node):
    publisher = node.create_publisher(Image, 'refused', RELIABLE)
    sender = SerializedPublisher(publisher)
    serialized = SerializedImage()
    written(serialized, header('cam', 1), 2, 2, 'mono8', 2, False, bytes(4))
    # An rcl publisher whose implementation is gone: rcl refuses it and says why.
    empty = ctypes.create_string_buffer(64)
    sender._rcl_publisher = ctypes.c_void_p(ctypes.addressof(empty))
    with pytest.raises(RuntimeError, match=r'rcl_publish_serialized_message failed \(\d+\) on '
                                           r'/refused: .*publisher'):
        sender.publish(serialized.message())
    assert error_text() == 'no error text'   # read and cleared: the next failure is its own
    node.destroy_publisher(publisher)
