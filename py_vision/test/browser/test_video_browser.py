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

"""The browser viewer's page decodes a camera's H.264 itself (WebCodecs in Chromium)."""

import base64
import json
import urllib.request

import cv2
import numpy as np
from py_vision.capture.synthetic_picture import read_frame_index
from ros_harness import wait_until
from video_clip import ClipPublisher, FRAMES, HEIGHT, KEYINT, WIDTH

URL_LINE = r'viewer at (http://[^\s/]+:\d+/)'


def shown_picture(page):
    """Return what the page's canvas holds now (BGR), or None before its first picture."""
    data_url = page.evaluate("""() => {
        const canvas = document.getElementById('canvas');
        return canvas.width > 0 && !canvas.hidden ? canvas.toDataURL('image/png') : null;
    }""")
    if data_url is None:
        return None
    png = base64.b64decode(data_url.split(',', 1)[1])
    return cv2.imdecode(np.frombuffer(png, np.uint8), cv2.IMREAD_COLOR)


def viewer_stats(url):
    with urllib.request.urlopen(url + 'stats', timeout=5) as reply:
        return json.loads(reply.read())


def shown_index(page):
    picture = shown_picture(page)
    return None if picture is None else read_frame_index(picture)


def test_the_page_decodes_the_cameras_h264_and_the_node_decodes_nothing(
        launch, peer, browser):
    subscriber = launch('usbcam_subscriber', params={'display': 'web', 'web_port': 0,
                                                     'image_transport': 'h264'})
    url = subscriber.wait_for_output(URL_LINE).group(1)
    ClipPublisher(peer)
    wait_until(lambda: 'video_codec' in viewer_stats(url), 20.0, interval=0.1,
               what='the subscriber to receive the clip')
    page = browser.new_page()
    page.goto(url)
    first = wait_until(lambda: shown_index(page) is not None and shown_index(page), 20.0,
                       interval=0.1, what='the first decoded picture on the canvas')
    assert shown_picture(page).shape == (HEIGHT, WIDTH, 3)
    assert page.locator('#video').is_hidden()
    # The picture moves on: the clip's frame index, read from what the page drew, changes.
    wait_until(lambda: shown_index(page) not in (None, first), 10.0, interval=0.1,
               what='the canvas to show another frame of the clip')
    assert 0 <= shown_index(page) < FRAMES
    stats = viewer_stats(url)
    assert stats['encoded_frames'] == 0, 'the node encoded JPEG: it decoded the video'
    assert stats['clients'] == 1
    wait_until(lambda: page.locator('#stat-encoding').inner_text() == 'h264', 10.0,
               interval=0.2, what="h264 in the page's stats")
    assert 'Traceback' not in subscriber.output()


def test_a_page_opened_before_the_camera_sends_turns_to_its_h264_when_it_comes(
        launch, peer, browser):
    subscriber = launch('usbcam_subscriber', params={'display': 'web', 'web_port': 0,
                                                     'image_transport': 'h264'})
    url = subscriber.wait_for_output(URL_LINE).group(1)
    page = browser.new_page()
    page.goto(url)
    wait_until(lambda: page.locator('#status').inner_text() == 'waiting for frames', 10.0,
               interval=0.1, what='the page to wait for frames')
    ClipPublisher(peer)
    first = wait_until(lambda: shown_index(page) is not None and shown_index(page), 20.0,
                       interval=0.1, what='the first decoded picture on the canvas')
    assert page.locator('#video').is_hidden()
    # Once the page decodes, the node does not: the page leaves the MJPEG stream it took
    # while nothing came (the server sees it gone at its next write), and the JPEG count stops.
    wait_until(lambda: viewer_stats(url)['mjpeg_clients'] == 0, 10.0, interval=0.1,
               what='the page to leave the MJPEG stream')
    encoded = viewer_stats(url)['encoded_frames']
    wait_until(lambda: shown_index(page) not in (None, first), 10.0, interval=0.1,
               what='the canvas to show another frame of the clip')
    wait_until(lambda: viewer_stats(url)['frames'] > 60, 20.0, interval=0.2,
               what='two seconds of the clip')
    assert viewer_stats(url)['encoded_frames'] == encoded
    assert 'Traceback' not in subscriber.output()


def test_a_page_opened_before_the_first_keyframe_waits_for_it_and_the_node_decodes_nothing(
        launch, peer, browser):
    # A camera joined mid-stream: units come, but no keyframe yet (the clip's next is unit
    # KEYINT, 14 s after the first at 1 a second), so nobody knows the codec yet.
    subscriber = launch('usbcam_subscriber', params={'display': 'web', 'web_port': 0,
                                                     'image_transport': 'h264'})
    url = subscriber.wait_for_output(URL_LINE).group(1)
    clip = ClipPublisher(peer, rate=1.0, first=1, when_subscribed=True)
    wait_until(lambda: viewer_stats(url).get('video_codec') == '', 20.0, interval=0.1,
               what='units before any keyframe')
    page = browser.new_page()
    page.goto(url)
    wait_until(lambda: page.locator('#overlay').inner_text() ==
               'waiting for the camera\u2019s next keyframe', 10.0, interval=0.1,
               what='the page to say it waits for the keyframe')
    wait_until(lambda: shown_index(page) is not None, 30.0, interval=0.1,
               what='the first decoded picture on the canvas')
    assert clip.sent[0] == 1 and KEYINT in clip.sent
    assert page.locator('#video').is_hidden()
    # The page waited for the keyframe instead of taking the node's JPEG stream meanwhile.
    assert viewer_stats(url)['encoded_frames'] == 0, 'the node decoded the video for the page'
    assert 'Traceback' not in subscriber.output()
