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

"""usbcam_subscriber shows any encoding the bridge knows, and says so when it cannot."""

import json
import urllib.request

import cv2
import numpy as np
import pytest
from rclpy.qos import QoSProfile, ReliabilityPolicy
from ros_harness import wait_until
from sensor_msgs.msg import Image

RELIABLE = QoSProfile(depth=10, reliability=ReliabilityPolicy.RELIABLE)
W, H = 96, 64


def ramp(dtype, channels, top):
    """
    Return a horizontal ramp from 0 to top: visible structure after display scaling.

    In colour, the first channel rises and the third falls, so the channel order shows.
    """
    row = np.linspace(0, top, W).astype(dtype)
    image = np.tile(row, (H, 1))
    if channels == 1:
        return image
    falling = image[:, ::-1]
    planes = [image, np.full_like(image, top // 2), falling] + [np.full_like(image, top)] * (
        channels - 3)
    return np.dstack(planes)


# Where the ramp's first channel is: shown in red for rgb, in blue for bgr.
RED_RISES = {'rgb8': True, 'bgra8': False}
CASES = {
    'mono8': ramp(np.uint8, 1, 255),
    'mono16': ramp(np.uint16, 1, 65535),
    '32FC1': ramp(np.float32, 1, 4.5),  # a depth image in metres
    'rgb8': ramp(np.uint8, 3, 255),
    'bgra8': ramp(np.uint8, 4, 255),
    'bayer_rggb8': ramp(np.uint8, 1, 255),
    '16UC1': ramp(np.uint16, 1, 1000),  # a depth image in millimetres
}
# What usbcam_publisher's output_encoding native sends from YUV cameras: a luma ramp over
# neutral chroma, in each layout (a semi-planar one's chroma rows below its luma rows).
LUMA, NEUTRAL = ramp(np.uint8, 1, 235), np.full((H, W), 128, np.uint8)
CASES.update({
    'yuv422_yuy2': np.dstack([LUMA, NEUTRAL]),
    'yuv422': np.dstack([NEUTRAL, LUMA]),
    'nv21': np.vstack([LUMA, NEUTRAL[:H // 2]]),
    'nv24': np.vstack([LUMA, NEUTRAL, NEUTRAL]),
})


def message(encoding, image):
    channels = 1 if image.ndim == 2 else image.shape[2]
    return Image(height=H, width=W, encoding=encoding, is_bigendian=0,
                 step=W * channels * image.dtype.itemsize, data=image.tobytes())


def get(url):
    with urllib.request.urlopen(url, timeout=5) as reply:
        return reply.read()


@pytest.fixture
def viewer(launch, peer):
    subscriber = launch('usbcam_subscriber', {'display': 'web', 'web_port': 0,
                                              'stats_period': 1.0})
    url = subscriber.wait_for_output(r'viewer at (http://[^\s/]+:\d+/)', 30).group(1)
    publisher = peer.node.create_publisher(Image, 'usb_camera/image', RELIABLE)
    wait_until(lambda: publisher.get_subscription_count() >= 1, 20, what='the subscriber')
    return subscriber, url, publisher


def test_every_encoding_is_shown_as_a_colour_image(viewer):
    subscriber, url, publisher = viewer
    for encoding, image in CASES.items():
        msg = message(encoding, image)

        def shown():
            publisher.publish(msg)
            stats = json.loads(get(url + 'stats'))
            return stats.get('encoding') == encoding and stats
        wait_until(shown, 20, interval=0.2, what='%s on the viewer' % encoding)
        jpeg = cv2.imdecode(np.frombuffer(get(url + 'snapshot.jpg'), np.uint8),
                            cv2.IMREAD_COLOR)
        assert jpeg.shape == (H, W, 3), encoding
        if encoding in RED_RISES:
            # Colour order kept: the rising channel is on the right in red (rgb) or blue (bgr).
            blue, red = jpeg[:, -8:, 0].mean(), jpeg[:, -8:, 2].mean()
            assert (red > blue + 100) == RED_RISES[encoding], (encoding, red, blue)
        else:
            # The ramp survives display conversion: dark on the left, bright on the right.
            grey = cv2.cvtColor(jpeg, cv2.COLOR_BGR2GRAY).astype(int)
            assert grey[:, -8:].mean() - grey[:, :8].mean() > 100, encoding
    assert 'Traceback' not in subscriber.output()


def test_an_unshowable_encoding_gets_one_error_and_the_stream_goes_on(viewer):
    subscriber, url, publisher = viewer
    bad = message('8UC2', np.zeros((H, W, 2), np.uint8))
    for _ in range(50):
        publisher.publish(bad)
    subscriber.wait_for_output(r'ERROR.*8UC2', 20)
    good = message('mono8', CASES['mono8'])

    def shown():
        publisher.publish(good)
        return json.loads(get(url + 'stats')).get('encoding') == 'mono8'
    wait_until(shown, 20, interval=0.2, what='the next valid frame')
    subscriber.wait_for_output(r'ERROR.*malformed image\(s\) dropped', 20)
    errors = [line for line in subscriber.output().splitlines() if '8UC2' in line]
    assert 1 <= len(errors) <= 3, errors


def test_a_frame_stamped_before_1970_is_shown_and_the_node_stays_up(viewer):
    # header.stamp.sec is signed: a negative stamp (a bad clock upstream) is a huge latency,
    # not an exception in the subscription.
    subscriber, url, publisher = viewer
    msg = message('mono8', CASES['mono8'])
    msg.header.stamp.sec = -1

    def shown():
        publisher.publish(msg)
        return json.loads(get(url + 'stats')).get('frames', 0) >= 3
    wait_until(shown, 20, interval=0.2, what='frames stamped before 1970 on the viewer')
    assert subscriber.proc.poll() is None
    assert 'Traceback' not in subscriber.output()
