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

"""usbcam_subscriber on a camera's H.264: the viewer forwards it untouched, decodes on demand."""

import json
import struct
import urllib.error
import urllib.request

import cv2
import numpy as np
from py_vision.capture.synthetic_picture import read_frame_index
from py_vision.transport import CompressedVideo
import pytest
from ros_harness import wait_until
from sensor_msgs.msg import CompressedImage
from video_clip import access_units, ClipPublisher, FRAMES, HEIGHT, KEYINT, WIDTH

URL_LINE = r'viewer at (http://[^\s/]+:\d+/)'


def get(url, timeout=5):
    with urllib.request.urlopen(url, timeout=timeout) as reply:
        return reply.read()


def stats(url):
    return json.loads(get(url + 'stats'))


@pytest.fixture
def viewer(launch):
    subscriber = launch('usbcam_subscriber', {'display': 'web', 'web_port': 0,
                                              'stats_period': 1.0, 'image_transport': 'h264'})
    url = subscriber.wait_for_output(URL_LINE, 30).group(1)
    return subscriber, url


def read_units(url, count):
    """Read `count` framed units from GET /video: [(start flag, bytes)], and the codec."""
    units = []
    with urllib.request.urlopen(url + 'video', timeout=10) as reply:
        codec = reply.headers['X-Video-Codec']
        while len(units) < count:
            length, start = struct.unpack('>IB', reply.read(5))
            units.append((start, reply.read(length)))
    return units, codec


def test_the_viewer_forwards_the_cameras_units_untouched_from_a_keyframe(viewer, peer):
    subscriber, url = viewer
    # The camera is mid-way between two keyframes when the viewer joins (as it is whenever
    # discovery takes a while): the size is known from the first keyframe's SPS on.
    clip = ClipPublisher(peer, first=KEYINT // 2, when_subscribed=True)
    wait_until(lambda: stats(url).get('frames', 0) >= 5, 20, interval=0.2,
               what='units received by the subscriber')
    wait_until(lambda: stats(url)['width'] > 0, 20, interval=0.2,
               what="a keyframe's size at the subscriber")
    s = stats(url)
    assert (s['encoding'], s['width'], s['height']) == ('h264', WIDTH, HEIGHT)
    assert s['video_codec'] == 'avc1.42c01e'
    units, codec = read_units(url, KEYINT + 5)
    assert codec == 'avc1.42c01e'
    clip_units = access_units()
    # A browser that joins gets the newest keyframe first, then every unit after it, as sent.
    first = clip_units.index(units[0][1])
    assert first % KEYINT == 0 and units[0][0] == 1
    for offset, (start, data) in enumerate(units):
        index = (first + offset) % FRAMES
        assert data == clip_units[index], "unit %d is not the clip's unit %d" % (offset, index)
        assert start == (index % KEYINT == 0)
    # Nobody needed pixels: nothing was decoded or encoded here.
    assert stats(url)['encoded_frames'] == 0
    clip.stop()
    assert 'Traceback' not in subscriber.output()


def test_a_snapshot_is_decoded_here_when_asked_for(viewer, peer):
    subscriber, url = viewer
    ClipPublisher(peer)
    wait_until(lambda: stats(url).get('frames', 0) >= 1, 20, interval=0.2, what='units')

    def snapshot_index():
        try:
            jpeg = get(url + 'snapshot.jpg')
        except urllib.error.HTTPError as error:
            assert error.code == 503      # nothing decoded yet
            return None
        picture = cv2.imdecode(np.frombuffer(jpeg, np.uint8), cv2.IMREAD_COLOR)
        assert picture.shape == (HEIGHT, WIDTH, 3)
        return read_frame_index(picture)
    first = wait_until(snapshot_index, 20, interval=0.2, what='a decoded snapshot')
    assert 0 <= first < FRAMES
    wait_until(lambda: snapshot_index() not in (None, first), 20, interval=0.2,
               what='the next snapshot to show another frame')
    assert stats(url)['video_decoder_missing'] is None
    assert 'Traceback' not in subscriber.output()


def test_a_message_that_is_not_h264_gets_one_error_and_the_stream_goes_on(viewer, peer):
    subscriber, url = viewer
    publisher = peer.node.create_publisher(CompressedImage, 'usb_camera/image/h264', 10)
    wait_until(lambda: publisher.get_subscription_count() >= 1, 20, what='the subscriber')
    for _ in range(20):
        publisher.publish(CompressedImage(format='h264', data=b'\xff\xd8not a video'))
    subscriber.wait_for_output(r'ERROR.*video message \(format "h264", 13 bytes\): it holds no '
                               r'NAL unit', 20)
    ClipPublisher(peer)
    wait_until(lambda: stats(url).get('width') == WIDTH, 20, interval=0.2,
               what='the clip after the bad messages')
    assert subscriber.proc.poll() is None
    assert 'Traceback' not in subscriber.output()


@pytest.mark.skipif(CompressedVideo is not None, reason='foxglove_msgs is installed here')
def test_foxglove_without_foxglove_msgs_is_one_error_naming_the_fallback(launch):
    subscriber = launch('usbcam_subscriber', {'display': 'none',
                                              'image_transport': 'foxglove'})
    assert subscriber.wait_exit(20) == 1
    assert 'foxglove_msgs 3.0 or newer is not installed here' in subscriber.output()
    assert '/usb_camera/image/h264 (image_transport:=h264)' in subscriber.output()
    assert 'Traceback' not in subscriber.output()
