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
/diagnostics as a monitor (diagnostic_aggregator, rqt_robot_monitor) reads it.

Every node's statuses: the publisher's camera through an unplug (OK, ERROR while lost, OK
when back) and at a rate it cannot reach (WARN), the subscriber's stream and the frames it
cannot show, cv_bridge_test falling behind (WARN) and keeping up.
"""

from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus
from fake_clock import FakeClock
from param_client import set_parameter
from py_vision.stats import StreamStats
from py_vision.usbcam_subscriber import stream_status
from rclpy.qos import QoSProfile, ReliabilityPolicy
from ros_harness import wait_until
from sensor_msgs.msg import Image

RELIABLE = QoSProfile(depth=100, reliability=ReliabilityPolicy.RELIABLE)
OK, WARN, ERROR = DiagnosticStatus.OK, DiagnosticStatus.WARN, DiagnosticStatus.ERROR
LEVELS = {OK: 'OK', WARN: 'WARN', ERROR: 'ERROR', DiagnosticStatus.STALE: 'STALE'}
# The keys the browser panel reads from the camera's status (the contract with it).
CAMERA_KEYS = {'device', 'pixel format', 'size', 'frame rate', 'requested rate', 'frames',
               'lost', 'corrupt', 'reconnects', 'device present',
               'subscribers usb_camera/image', 'subscribers usb_camera/image/compressed',
               'subscribers usb_camera/camera_info'}


class Monitor:
    """Collects /diagnostics and waits for statuses, each wait after the one before."""

    def __init__(self, peer):
        self.arrays = peer.collect(DiagnosticArray, '/diagnostics', RELIABLE)
        self._next = {}  # status name -> index of the first status the next wait looks at

    def statuses(self, name):
        return [status for array in list(self.arrays) for status in array.status
                if status.name == name]

    def wait_for(self, name, level, condition=lambda values: True, timeout=30):
        """Wait for the next status `name` at `level` whose values satisfy condition."""
        def found():
            statuses = self.statuses(name)
            for index in range(self._next.get(name, 0), len(statuses)):
                status = statuses[index]
                values = {kv.key: kv.value for kv in status.values}
                if status.level == level and condition(values):
                    self._next[name] = index + 1
                    return status, values
            return None
        try:
            return wait_until(found, timeout, 0.1, '%s %s' % (name, LEVELS[level]))
        except AssertionError as error:
            seen = self.statuses(name)
            last = ('%s "%s"' % (LEVELS[seen[-1].level], seen[-1].message)) if seen else 'none'
            raise AssertionError('%s; last status: %s' % (error, last)) from None


def test_camera_status_goes_ok_error_ok_through_an_unplug(launch, peer):
    monitor = Monitor(peer)
    device = 'synthetic?stop_after=50&unplugged_for=3'
    publisher = launch('usbcam_publisher', {'video_device': device, 'framerate': 10.0,
                                            'image_width': 160, 'image_height': 120})
    name = 'usbcam_publisher: camera'
    ok, values = monitor.wait_for(name, OK, lambda v: v['device present'] == 'true')
    assert ok.hardware_id == device
    assert CAMERA_KEYS <= set(values), CAMERA_KEYS - set(values)
    assert values['device'] == device and values['pixel format'] == 'YUYV'
    assert values['size'] == '160x120' and values['requested rate'] == '10.0'
    error, values = monitor.wait_for(name, ERROR, lambda v: v['device present'] == 'false')
    assert 'lost' in error.message
    publisher.wait_for_output('is back after')
    ok, values = monitor.wait_for(
        name, OK, lambda v: v['device present'] == 'true' and v['reconnects'] == '1')
    # Each wait looks only at statuses after the one before: OK, then ERROR, then OK. Once
    # back, the rate is measured again.
    ok, values = monitor.wait_for(name, OK, lambda v: float(v['frame rate']) > 0)
    assert abs(float(values['frame rate']) - 10.0) <= 1.0
    assert int(values['frames']) > 50


def test_camera_status_warns_below_the_requested_rate(launch, peer):
    monitor = Monitor(peer)
    # YUYV at 1280x720 is limited by USB 2.0 to 10 fps: 30 cannot be reached.
    launch('usbcam_publisher', {'video_device': 'synthetic', 'framerate': 30.0,
                                'image_width': 1280, 'image_height': 720,
                                'pixel_format': 'yuyv'})
    warn, values = monitor.wait_for('usbcam_publisher: camera', WARN)
    assert 'requested 30.0' in warn.message
    # The camera was set to the 10 fps it offers; the rate measured depends on the machine's
    # load too (a loaded machine reads frames late), so it is only below the request.
    assert float(values['camera rate']) == 10.0
    assert 0 < float(values['frame rate']) < 30.0 * 0.9


def test_subscriber_status_shows_rate_latency_and_frames_it_cannot_show(launch, peer):
    monitor = Monitor(peer)
    name = 'usbcam_subscriber: stream'
    launch('usbcam_subscriber', {'display': 'none', 'stats_period': 2.0})
    waiting, _ = monitor.wait_for(name, WARN)
    assert 'waiting for frames on /usb_camera/image' in waiting.message
    launch('usbcam_publisher', {'video_device': 'synthetic', 'framerate': 10.0,
                                'image_width': 160, 'image_height': 120})
    # The first OK may come with one frame received, before a rate can be measured.
    ok, values = monitor.wait_for(name, OK, lambda v: float(v['frame rate']) > 0)
    # Never an OK that claims no rate ('receiving 0.0 fps'); '10.0 fps' is fine.
    assert not [s.message for s in monitor.statuses(name) if s.message == 'receiving 0.0 fps']
    assert ok.hardware_id == '/usb_camera/image'
    assert float(values['frame rate']) > 0 and float(values['latency p50 ms']) >= 0
    assert float(values['latency p99 ms']) >= float(values['latency p50 ms'])
    assert values['size'] == '160x120' and values['encoding'] == 'bgr8'
    bad = peer.node.create_publisher(Image, 'usb_camera/image', RELIABLE)
    wait_until(lambda: bad.get_subscription_count() > 0, 20, what='the subscriber')
    for _ in range(3):
        bad.publish(Image(height=4, width=4, encoding='nonsense', step=4, data=bytes(16)))
    warn, values = monitor.wait_for(name, WARN, lambda v: v['not shown'] == '3')
    assert 'could not be shown' in warn.message


def test_one_frame_received_is_no_rate_of_zero():
    # With one frame in the window there is no rate yet: the status must not say "0.0 fps".
    clock = FakeClock(100.0)
    stats = StreamStats(window_s=2.0, clock=clock)
    assert stream_status(stats.snapshot(), 0, '/cam').message == 'waiting for frames on /cam'
    stats.add(0.002, 160, 120, 'bgr8')
    clock.t += 0.05
    first = stream_status(stats.snapshot(), 0, '/cam')
    assert first.level == OK and 'rate not measured yet' in first.message, first.message
    assert 'fps' not in first.message
    clock.t += 0.05
    stats.add(0.002, 160, 120, 'bgr8')
    clock.t += 0.1
    second = stream_status(stats.snapshot(), 0, '/cam')
    assert second.level == OK and second.message == 'receiving 5.0 fps', second.message
    clock.t += 5.0  # the stream stopped: both frames leave the window
    assert stream_status(stats.snapshot(), 0, '/cam').message == 'no frames on /cam lately'


def test_cv_bridge_test_warns_when_it_cannot_keep_up(launch, peer):
    monitor = Monitor(peer)
    name = 'cv_bridge_test: processing'
    launch('usbcam_publisher', {'video_device': 'synthetic', 'framerate': 10.0,
                                'image_width': 160, 'image_height': 120})
    launch('cv_bridge_test')
    ok, values = monitor.wait_for(name, OK, lambda v: v['processing p50 ms'] != '')
    assert 'keeping up' in ok.message
    assert float(values['output age p50 ms']) >= float(values['processing p50 ms'])
    # Its step runs no model: all of a frame's time is the rest.
    assert 'no model ran' in ok.message, ok.message
    assert (values['models p50 ms'], values['frames running models']) == ('0.0', '0'), values
    assert values['rest p50 ms'] == values['processing p50 ms'], values
    assert values['models CPU ms'] == '0', values
    # 300 ms a frame at 10 fps: two frames of three are skipped.
    assert set_parameter(peer, 'cv_bridge_test', 'simulated_work_ms', 300.0).successful
    warn, values = monitor.wait_for(name, WARN)
    assert 'cannot keep up' in warn.message
    assert int(values['skipped']) > 0 and float(values['processing p99 ms']) >= 290
    assert set_parameter(peer, 'cv_bridge_test', 'simulated_work_ms', 0.0).successful
    monitor.wait_for(name, OK, lambda v: float(v['processing p50 ms'] or 1e9) < 100)


def test_a_renamed_node_reports_under_its_real_name(launch, peer):
    monitor = Monitor(peer)
    launch('usbcam_subscriber', {'display': 'none'}, remaps={'__node': 'front_viewer'})
    status, _ = monitor.wait_for('front_viewer: stream', WARN)
    assert not monitor.statuses('usbcam_subscriber: stream')
