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

"""The installed cv_bridge_test node end to end: images in, images with the red circle out."""

import json
import re
import signal
import urllib.request

import cv2
import numpy as np
from param_client import set_parameter
from py_vision.capture.synthetic_picture import read_frame_index
import pytest
from rclpy.qos import QoSProfile, ReliabilityPolicy
from ros_harness import wait_until
from sensor_msgs.msg import Image

RED = (0, 0, 255)  # BGR


def image_msg(image, encoding, stamp_sec, frame_id='cam'):
    msg = Image()
    msg.header.stamp.sec = stamp_sec
    msg.header.frame_id = frame_id
    msg.height, msg.width = image.shape[:2]
    if encoding == 'nv21':   # its chroma rows below its luma rows: half as many
        msg.height = image.shape[0] * 2 // 3
    msg.encoding = encoding
    msg.step = image.shape[1] * (image.shape[2] if image.ndim == 3 else 1)
    msg.data = np.ascontiguousarray(image).tobytes()
    return msg


def as_bgr(msg):
    assert msg.encoding == 'bgr8' and msg.step == msg.width * 3
    return np.frombuffer(bytes(msg.data), np.uint8).reshape(msg.height, msg.width, 3)


def distance_to_circle_center(height, width):
    ys, xs = np.mgrid[:height, :width]
    return np.hypot(xs - 60, ys - 60)


class Probe:
    """Publishes to usb_camera/image and collects cv_bridge_image, on the test's domain."""

    def __init__(self, peer, depth=10):
        qos = QoSProfile(depth=depth, reliability=ReliabilityPolicy.RELIABLE)
        self.publisher = peer.node.create_publisher(Image, 'usb_camera/image', qos)
        self.received = peer.collect(Image, 'cv_bridge_image',
                                     QoSProfile(depth=100, reliability=ReliabilityPolicy.RELIABLE))

    def wait_connected(self, node):
        """Publish a warm-up image until its result comes back (discovery is done)."""
        warm_up = np.zeros((8, 8, 3), np.uint8)

        def answered():
            self.publisher.publish(image_msg(warm_up, 'bgr8', 999))
            return any(m.header.stamp.sec == 999 for m in self.received)
        wait_until(answered, 20.0, interval=0.2, what='cv_bridge_test to answer')

    def result_for(self, stamp_sec, timeout=10.0):
        def find():
            return next((m for m in self.received if m.header.stamp.sec == stamp_sec), None)
        return wait_until(find, timeout, what='the output for stamp %d' % stamp_sec)


def test_circle_is_drawn_on_large_images_and_the_rest_is_unchanged(launch, peer):
    node = launch('cv_bridge_test', params={'display': 'web', 'web_port': 0})
    url = node.wait_for_output(r'viewer at (http://\S+:\d+/)').group(1)
    probe = Probe(peer)
    probe.wait_connected(node)
    rng = np.random.default_rng(7)
    cases = [  # (the image as published, its encoding, what it is in BGR)
        (rng.integers(0, 256, (240, 320, 3), np.uint8), 'bgr8', None),
        (rng.integers(0, 256, (480, 640, 3), np.uint8), 'bgr8', None),
        (rng.integers(0, 256, (61, 61, 3), np.uint8), 'bgr8', None),
        (rng.integers(0, 256, (100, 90, 3), np.uint8), 'rgb8', cv2.COLOR_RGB2BGR),
        # What usbcam_publisher's output_encoding native sends from YUV cameras.
        (rng.integers(0, 256, (100, 90, 2), np.uint8), 'yuv422_yuy2', cv2.COLOR_YUV2BGR_YUY2),
        (rng.integers(0, 256, (100, 90, 2), np.uint8), 'yuv422', cv2.COLOR_YUV2BGR_UYVY),
        (rng.integers(0, 256, (150, 90), np.uint8), 'nv21', cv2.COLOR_YUV2BGR_NV21),
        (rng.integers(0, 256, (120, 160), np.uint8), 'mono8', cv2.COLOR_GRAY2BGR),
    ]
    for stamp, (image, encoding, to_bgr) in enumerate(cases, start=1):
        # One at a time: images published faster than they are processed would be skipped.
        probe.publisher.publish(image_msg(image, encoding, stamp, 'frame_%d' % stamp))
        out = probe.result_for(stamp)
        assert out.header.frame_id == 'frame_%d' % stamp
        assert out.header.stamp.nanosec == 0
        expected = image if to_bgr is None else cv2.cvtColor(image, to_bgr)
        result = as_bgr(out)
        assert result.shape == expected.shape
        distance = distance_to_circle_center(*result.shape[:2])
        inside, outside = distance <= 29, distance >= 31  # the rim is up to the rasteriser
        assert (result[inside] == RED).all(), 'the circle is not filled pure red'
        assert (result[outside] == expected[outside]).all(), 'pixels outside the circle changed'
        changed = (result != expected).any(axis=2)
        disc = (distance <= 30).sum()  # clipped by the border on a small image
        assert abs(changed.sum() - disc) < 0.1 * disc
    # The browser viewer shows the processed frames.
    with urllib.request.urlopen(url + 'snapshot.jpg', timeout=5) as answer:
        shown = cv2.imdecode(np.frombuffer(answer.read(), np.uint8), cv2.IMREAD_COLOR)
    assert shown.shape == (120, 160, 3)
    assert np.abs(shown[50:70, 50:70].astype(int) - RED).max() < 40
    assert node.stop(signal.SIGINT) == 0
    assert 'Traceback' not in node.output()


@pytest.mark.parametrize('height, width', [(60, 60), (60, 200), (200, 60), (10, 10), (1, 1)])
def test_images_of_60_pixels_or_less_pass_unchanged(launch, peer, height, width):
    node = launch('cv_bridge_test')
    probe = Probe(peer)
    probe.wait_connected(node)
    image = np.random.default_rng(height * width).integers(0, 256, (height, width, 3), np.uint8)
    probe.publisher.publish(image_msg(image, 'bgr8', 1))
    assert (as_bgr(probe.result_for(1)) == image).all()
    assert node.stop(signal.SIGTERM) == 0
    assert 'Traceback' not in node.output()


def bad_messages(count):
    good = np.zeros((100, 100, 3), np.uint8)
    makers = [
        lambda m: setattr(m, 'data', m.data[:-10]),       # data too short
        lambda m: setattr(m, 'encoding', 'fancy42'),      # unknown encoding
        lambda m: setattr(m, 'step', 10),                 # step shorter than a row
        lambda m: setattr(m, 'encoding', '32FC1'),        # 4 bytes a pixel: data too short
    ]
    for i in range(count):
        msg = image_msg(good, 'bgr8', 5000 + i)
        makers[i % len(makers)](msg)
        yield msg


ERROR_LINE = re.compile(
    r'cannot convert a \d+x\d+ "[^"]+" image to bgr8.*\((\d+) skipped so far\)')


def test_bad_messages_are_logged_rate_limited_and_the_node_keeps_going(launch, peer):
    node = launch('cv_bridge_test')
    probe = Probe(peer, depth=200)
    probe.wait_connected(node)
    # One image 10 bytes short: the line says which image and what is wrong with it.
    probe.publisher.publish(next(bad_messages(1)))
    first = node.wait_for_output(ERROR_LINE.pattern).group(0)
    assert '100x100 "bgr8"' in first and '29990' in first, first
    for msg in bad_messages(200):
        probe.publisher.publish(msg)
    good = np.random.default_rng(3).integers(0, 256, (120, 160, 3), np.uint8)
    probe.publisher.publish(image_msg(good, 'bgr8', 1))
    assert (as_bgr(probe.result_for(1))[100:, 100:] == good[100:, 100:]).all()
    assert not any(5000 <= m.header.stamp.sec < 5200 for m in probe.received)
    assert len(ERROR_LINE.findall(node.output())) == 1

    # Bad messages keep coming at 20 Hz (slow enough that none is lost on the way): only when
    # the rate-limit period is over does one more line come, with the running count.
    def second_error_line():
        if len(ERROR_LINE.findall(node.output())) >= 2:
            return True
        probe.publisher.publish(next(bad_messages(1)))
        return False
    wait_until(second_error_line, 15.0, interval=0.05, what='a second, later error line')
    counts = [int(count) for count in ERROR_LINE.findall(node.output())]
    assert len(counts) == 2, node.output()
    assert counts[0] == 1 and counts[1] > 20, 'the error lines are not rate-limited'
    assert node.stop(signal.SIGINT) == 0
    assert 'Traceback' not in node.output()


def test_every_frame_is_processed_in_order_when_processing_keeps_up(launch, peer):
    node = launch('cv_bridge_test')
    probe = Probe(peer)
    probe.wait_connected(node)
    image = np.zeros((120, 160, 3), np.uint8)
    for stamp in range(1, 31):  # each one arrives when the previous one is done
        probe.publisher.publish(image_msg(image, 'bgr8', stamp))
        probe.result_for(stamp)
    stamps = [m.header.stamp.sec for m in probe.received if m.header.stamp.sec != 999]
    assert stamps == list(range(1, 31))
    assert node.stop(signal.SIGINT) == 0


STATS_LINE = re.compile(
    r'frames in (\d+), processed (\d+), skipped (\d+), processing p50 ([\d.]+) ms '
    r'p99 ([\d.]+) ms \(([^)]*)\), output age p50 ([\d.]+) ms p99 ([\d.]+) ms')
CAMERA = {'video_device': 'synthetic', 'image_width': 320, 'image_height': 240}


def stamp_ns(msg):
    return msg.header.stamp.sec * 10**9 + msg.header.stamp.nanosec


def test_a_slow_step_works_on_the_newest_frame_and_counts_the_skipped_ones(launch, peer):
    # What the probe receives from the camera and from the node, in the order it arrives.
    events = []
    peer.node.create_subscription(
        Image, 'usb_camera/image', lambda m: events.append(('camera', stamp_ns(m), m)),
        QoSProfile(depth=5, reliability=ReliabilityPolicy.RELIABLE))
    peer.node.create_subscription(
        Image, 'cv_bridge_image', lambda m: events.append(('output', stamp_ns(m), m)),
        QoSProfile(depth=100, reliability=ReliabilityPolicy.RELIABLE))
    node = launch('cv_bridge_test', params={'simulated_work_ms': 600})
    camera = launch('usbcam_publisher', params=dict(CAMERA, framerate=10.0))

    def outputs():
        return [event for event in list(events) if event[0] == 'output']

    def lags():
        # When output k is published the worker takes the newest frame it has, so output
        # k + 1 comes from a frame at least as new as the newest one the probe had seen before
        # output k arrived (give or take frames still on their way). Working through the
        # subscription's queue of 10 instead would lag about nine frames (900 ms) behind it.
        newest_seen, previous, found = None, None, []
        for kind, stamp, msg in list(events):
            if kind == 'camera':
                newest_seen = max(stamp, newest_seen or stamp)
                continue
            if previous is not None:
                found.append((previous - stamp) / 1e9)
            previous = newest_seen
        return found
    # Six outputs, each after the probe had seen camera frames (discovery is not timed).
    wait_until(lambda: len(outputs()) >= 6 and len(lags()) >= 5, 60.0, interval=0.1,
               what='six processed frames after the first camera frame')
    found = lags()
    assert max(found) <= 0.35, 'outputs lag the newest frame by %s s' % found
    indices = [read_frame_index(as_bgr(event[2])) for event in outputs()]
    assert None not in indices and indices == sorted(indices), indices
    line = node.wait_for_output(STATS_LINE.pattern, timeout=15.0)
    frames_in, processed, skipped = (int(v) for v in line.groups()[:3])
    assert skipped > 0 and processed > 0, line.group(0)
    # Every frame is accounted for: processed, skipped, or waiting / in progress.
    assert 0 <= frames_in - processed - skipped <= 2, line.group(0)
    assert float(line.group(4)) >= 600.0, 'the simulated work did not take 600 ms'
    # The simulated work is no model: the line says none ran rather than a model time.
    assert line.group(6) == 'no model ran', line.group(0)
    assert camera.stop(signal.SIGINT) == 0
    assert node.stop(signal.SIGINT) == 0
    assert 'Traceback' not in node.output()


def test_simulated_work_can_be_changed_while_running(launch, peer):
    received = peer.collect(Image, 'cv_bridge_image',
                            QoSProfile(depth=100, reliability=ReliabilityPolicy.RELIABLE))
    node = launch('cv_bridge_test')
    launch('usbcam_publisher', params=dict(CAMERA, framerate=10.0))
    wait_until(lambda: received, 30.0, interval=0.1, what='a processed frame')
    result = set_parameter(peer, 'cv_bridge_test', 'simulated_work_ms', 300.0)
    assert result.successful, result.reason
    node.wait_for_output('simulated work is now 300 ms a frame')

    def slow_steps_reported():
        # Once the 5 s window holds only slow steps, the busy 300 ms show in the median.
        return any(float(m.group(4)) >= 300.0 for m in STATS_LINE.finditer(node.output()))
    wait_until(slow_steps_reported, 30.0, interval=0.2, what='processing p50 >= 300 ms')
    refused = set_parameter(peer, 'cv_bridge_test', 'simulated_work_ms', 20000.0)
    assert not refused.successful
    assert '10000' in refused.reason and 'simulated_work_ms' in refused.reason
    assert node.stop(signal.SIGINT) == 0


def test_ctrl_c_during_a_long_processing_step_ends_cleanly(launch, peer):
    node = launch('cv_bridge_test', params={
        'simulated_work_ms': 10000, 'display': 'web', 'web_port': 0})
    url = node.wait_for_output(r'viewer at (http://\S+:\d+/)').group(1)
    launch('usbcam_publisher', params=dict(CAMERA, framerate=10.0))

    def step_in_progress():
        # What the browser page shows: the first frame is in its 10 s step, later ones skip.
        with urllib.request.urlopen(url + 'stats', timeout=5) as answer:
            stats = json.loads(answer.read())
        return stats if stats.get('skipped', 0) >= 1 else None
    in_step = wait_until(step_in_progress, 30.0, interval=0.2,
                         what='a frame in processing and one skipped')
    assert in_step['processed'] == 0 and in_step['frames_in'] >= 2, in_step
    assert node.stop(signal.SIGINT, timeout=5.0) == 0
    assert 'Traceback' not in node.output(), node.output()


def test_the_browser_page_shows_what_was_processed_and_skipped(launch, browser):
    node = launch('cv_bridge_test', params={
        'simulated_work_ms': 300, 'display': 'web', 'web_port': 0})
    url = node.wait_for_output(r'viewer at (http://\S+:\d+/)').group(1)
    launch('usbcam_publisher', params=dict(CAMERA, framerate=10.0))
    page = browser.new_page()
    page.goto(url)
    names = ('in', 'processed', 'skipped', 'processing', 'processing-p99', 'age', 'age-p99')

    def filled():
        # All the stats in one read: the page replaces them together once a second, and reads
        # one by one could mix two updates (frames in from one, skipped from the next).
        shown = page.evaluate(
            'names => Object.fromEntries(names.map('
            'name => [name, document.getElementById("stat-" + name).innerText]))', names)
        everything = all(value not in ('', '-') for value in shown.values())
        return shown if everything and shown['skipped'] != '0' else None
    shown = wait_until(filled, 30.0, interval=0.2, what='the processing stats on the page')
    assert all(page.locator('#stat-' + name).is_visible() for name in names)
    assert int(shown['in']) >= int(shown['processed']) + int(shown['skipped']), shown
    assert float(shown['processing'].split()[0]) >= 300.0, shown
    assert float(shown['age-p99'].split()[0]) >= float(shown['age'].split()[0]), shown
    assert node.stop(signal.SIGINT) == 0


def test_frames_larger_than_its_shared_memory_are_one_warning_naming_the_fix(launch, peer):
    # Started on its own, it sizes its shared memory for the camera's default 640x480.
    node = launch('cv_bridge_test')
    probe = Probe(peer)
    probe.wait_connected(node)
    vga = np.zeros((480, 640, 3), np.uint8)
    probe.publisher.publish(image_msg(vga, 'bgr8', 1))
    probe.result_for(1)
    assert 'do not fit the shared memory' not in node.output()
    large = np.zeros((720, 1280, 3), np.uint8)
    for stamp in (2, 3):
        probe.publisher.publish(image_msg(large, 'bgr8', stamp))
        probe.result_for(stamp, timeout=20.0)
    warnings = [line for line in node.output().splitlines()
                if 'do not fit the shared memory' in line]
    assert len(warnings) == 1 and 'WARN' in warnings[0], node.output()
    assert '-p image_width:=1280 -p image_height:=720' in warnings[0]
    assert node.stop(signal.SIGINT) == 0
