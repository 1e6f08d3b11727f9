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
Nothing a user or a neighbour sends ends a node (issue 28).

A node ends on Ctrl-C, SIGTERM or SIGHUP (cleanly, with its `stopped by` line) or on its own
start-up error; nothing that arrives over ROS ends it: malformed service requests, a clock that
jumps, calibration files that are not files, images too large to hold.
"""

import os
import re
import signal

from param_client import get_parameters, set_parameter
import pytest
from rcl_interfaces.msg import Parameter as ParameterMsg, ParameterValue
from rcl_interfaces.srv import SetParameters
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
from ros_harness import wait_until
from sensor_msgs.msg import CameraInfo, Image
from sensor_msgs.srv import SetCameraInfo

RELIABLE = QoSProfile(depth=100, reliability=ReliabilityPolicy.RELIABLE)
SYNTHETIC = {'video_device': 'synthetic', 'framerate': 20.0}


def call(peer, service_type, name, request, timeout=20.0):
    """Call a service; return its answer, or None when none came within timeout."""
    client = peer.node.create_client(service_type, name)
    try:
        assert client.wait_for_service(timeout_sec=20), 'no service %s' % name
        future = client.call_async(request)
        try:
            wait_until(future.done, timeout, what='the answer of %s' % name)
        except AssertionError:
            client.remove_pending_request(future)
            return None
        return future.result()
    finally:
        peer.node.destroy_client(client)


def alive(node):
    assert node.proc.poll() is None, node.tail()
    assert 'Traceback' not in node.output(), node.tail()


@pytest.fixture
def ros_home(ros_env, tmp_path):
    """Keep the nodes' default calibration folder in the test's own directory."""
    ros_env['ROS_HOME'] = str(tmp_path / 'ros_home')
    return tmp_path / 'ros_home'


def calibration(valid):
    info = CameraInfo(width=640, height=480, distortion_model='plumb_bob')
    info.k = [500.0, 0.0, 320.0, 0.0, 501.0 if valid else 0.0, 240.0, 0.0, 0.0, 1.0]
    info.d = [0.1, -0.2, 0.001, 0.002, 0.0]
    info.r = [1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0]
    info.p = [505.0, 0.0, 321.0, 0.0, 0.0, 506.0, 241.0, 0.0, 0.0, 0.0, 1.0, 0.0]
    return info


def test_a_calibration_session_with_a_failed_commit_keeps_the_camera(launch, peer, ros_home):
    # cameracalibrator commits with set_camera_info; one refused commit, then a good one (or
    # the other way round) must be two answers, not the end of the camera.
    publisher = launch('usbcam_publisher', SYNTHETIC)
    answers = []
    for valid in (False, False, True, False, True):
        answer = call(peer, SetCameraInfo, '/usb_camera/set_camera_info',
                      SetCameraInfo.Request(camera_info=calibration(valid)))
        assert answer is not None, 'no answer to set_camera_info:\n' + publisher.tail()
        answers.append(answer.success)
    assert answers == [False, False, True, False, True]
    alive(publisher)


@pytest.mark.parametrize('executable', ['usbcam_publisher', 'usbcam_subscriber'])
def test_a_malformed_set_parameters_ends_no_node(launch, peer, executable):
    # Any member of the domain can send a SetParameters whose value has a type rclpy does
    # not know: rclpy's own parameter service raises on it.
    node = launch(executable, SYNTHETIC if executable == 'usbcam_publisher' else {
        'display': 'none'})
    bad = SetParameters.Request(parameters=[ParameterMsg(
        name='jpeg_quality' if executable == 'usbcam_publisher' else 'stats_period',
        value=ParameterValue(type=99))])
    for _ in range(5):
        call(peer, SetParameters, '/%s/set_parameters' % executable, bad, timeout=2.0)
    node.wait_for_output(r'99 is not a valid Parameter.Type')
    alive(node)
    # It still answers its parameter services, and says once what it threw away.
    assert get_parameters(peer, executable, ['use_sim_time'])[0].bool_value is False
    assert node.output().count('99 is not a valid Parameter.Type') == 1, node.tail()
    assert node.stop(signal.SIGINT) == 0
    assert 'stopped by SIGINT' in node.output()


def test_stamps_follow_the_node_clock_whatever_it_is(launch, peer):
    # Simulation or a replayed bag: /clock drives the node's clock, starting at 0 and jumping
    # back when the bag loops.
    from builtin_interfaces.msg import Time
    from rosgraph_msgs.msg import Clock
    clock = peer.node.create_publisher(Clock, '/clock', 10)
    images = peer.collect(Image, 'usb_camera/image', RELIABLE)
    infos = peer.collect(CameraInfo, 'usb_camera/camera_info', RELIABLE)
    publisher = launch('usbcam_publisher', dict(SYNTHETIC, use_sim_time=True))

    def stamps_at(sec):
        def check():
            clock.publish(Clock(clock=Time(sec=sec)))
            recent = images[-3:]
            return len(recent) == 3 and all(m.header.stamp.sec == sec for m in recent)
        images.clear()
        wait_until(check, 30, interval=0.05, what="image stamps at the clock's %d s" % sec)
    stamps_at(0)
    stamps_at(1000)
    stamps_at(500)   # the clock jumps back
    assert infos and infos[-1].header.stamp.sec in (500, 1000)
    alive(publisher)


def test_sim_time_switched_on_live_is_followed(launch, peer):
    from builtin_interfaces.msg import Time
    from rosgraph_msgs.msg import Clock
    clock = peer.node.create_publisher(Clock, '/clock', 10)
    images = peer.collect(Image, 'usb_camera/image', RELIABLE)
    publisher = launch('usbcam_publisher', SYNTHETIC)
    wait_until(lambda: images, 30, what='frames')
    assert set_parameter(peer, 'usbcam_publisher', 'use_sim_time', True).successful

    def at_clock():
        clock.publish(Clock(clock=Time(sec=7)))
        return images[-1].header.stamp.sec == 7
    wait_until(at_clock, 20, interval=0.05, what='stamps from the simulated clock')
    alive(publisher)


@pytest.mark.parametrize('kind', ['/dev/zero', '/dev/urandom', 'fifo', 'directory'])
def test_a_calibration_url_that_is_no_file_is_one_warning(launch, peer, ros_home, tmp_path,
                                                          kind):
    path = kind
    if kind == 'fifo':
        path = str(tmp_path / 'calibration.yaml')
        os.mkfifo(path)   # nobody ever writes to it: open() would wait for ever
    elif kind == 'directory':
        path = str(tmp_path)
    images = peer.collect(Image, 'usb_camera/image', RELIABLE)
    infos = peer.collect(CameraInfo, 'usb_camera/camera_info', RELIABLE)
    publisher = launch('usbcam_publisher', dict(SYNTHETIC, camera_info_url='file://' + path))
    wait_until(lambda: len(images) >= 3 and infos, 30, what='frames despite the URL')
    assert not any(infos[-1].k)
    warnings = [line for line in publisher.output().splitlines() if 'WARN' in line]
    assert len(warnings) == 1 and path in warnings[0], publisher.tail()
    assert 'not a regular file' in warnings[0]
    alive(publisher)


def test_a_frame_id_that_cannot_be_a_frame_is_refused(launch, peer):
    bad = launch('usbcam_publisher', dict(SYNTHETIC, frame_id='cam\nera'), name='bad_frame_id')
    assert bad.wait_exit(20) == 1
    assert 'frame_id' in bad.output() and 'Traceback' not in bad.output()
    images = peer.collect(Image, 'usb_camera/image', RELIABLE)
    publisher = launch('usbcam_publisher', dict(SYNTHETIC, frame_id='camera_1'))
    wait_until(lambda: images, 30, what='frames')
    # (A NUL cannot even arrive: ROS strings end at the first one.)
    for value in ('x' * 1000000, 'cam\tera', 'two words', ''):
        result = set_parameter(peer, 'usbcam_publisher', 'frame_id', value)
        assert not result.successful, repr(value[:20])
        assert 'frame_id' in result.reason and len(result.reason) < 300, result.reason[:300]
    images.clear()
    wait_until(lambda: len(images) >= 3, 20, what='frames after the refusals')
    assert {m.header.frame_id for m in images} == {'camera_1'}
    alive(publisher)


def test_a_zero_stamp_has_no_latency(launch, peer):
    # A publisher that does not stamp its images (stamp 0): the subscriber cannot say how old
    # they are, and says so instead of a latency of 56 years.
    images = peer.node.create_publisher(Image, 'usb_camera/image', RELIABLE)
    subscriber = launch('usbcam_subscriber', {'display': 'none', 'stats_period': 1.0})

    def said():
        images.publish(Image(width=4, height=2, encoding='mono8', step=4, data=bytes(8)))
        return re.search(r'received [1-9]\d* frames .*(without a stamp|no stamp)',
                         subscriber.output())
    try:
        wait_until(said, 30, interval=0.1, what='a statistics line about the frames')
    except AssertionError as error:
        subscriber.fail(str(error))
    assert 'latency p50' not in subscriber.output(), subscriber.tail()
    alive(subscriber)


@pytest.mark.parametrize('executable', ['usbcam_publisher', 'usbcam_subscriber',
                                        'cv_bridge_test'])
def test_sighup_stops_a_node_cleanly(launch, executable):
    # A closed terminal (or ssh session) sends SIGHUP.
    node = launch(executable, SYNTHETIC if executable == 'usbcam_publisher' else {})
    node.wait_for_output(r'opened synthetic|no frames|waiting|received|INFO', timeout=30)
    assert node.stop(signal.SIGHUP, timeout=10) == 0
    assert 'stopped by SIGHUP' in node.output(), node.tail()
    assert 'Traceback' not in node.output()


def test_the_token_is_never_published_on_rosout(launch, peer, ros_env):
    from rcl_interfaces.msg import Log
    rosout = peer.collect(Log, '/rosout', QoSProfile(
        depth=1000, reliability=ReliabilityPolicy.RELIABLE,
        durability=DurabilityPolicy.TRANSIENT_LOCAL))
    subscriber = launch('usbcam_subscriber', {'display': 'web', 'web_port': 0,
                                              'web_host': '0.0.0.0'})
    token = subscriber.wait_for_output(r'viewer at http://\S+/\?token=([\w.~-]+)').group(1)
    # The log line without the token is on /rosout: everything up to it has arrived.
    wait_until(lambda: any('browser viewer on' in m.msg for m in rosout), 20,
               what='the viewer line on /rosout')
    assert not [m.msg for m in rosout if token in m.msg]
    assert subscriber.output().count(token) == 1
    # Nor is it in the node's log file.
    for folder, _, files in os.walk(ros_env['ROS_LOG_DIR']):
        for name in files:
            with open(os.path.join(folder, name), errors='replace') as log:
                assert token not in log.read(), name
    alive(subscriber)


# Times the 201 MB image is published, 30 s apart, before its refusal is missed.
HUGE_ATTEMPTS = 3


def resident_mb(node):
    with open('/proc/%d/status' % node.proc.pid) as status:
        return int(re.search(r'VmRSS:\s+(\d+)', status.read()).group(1)) / 1024


@pytest.mark.parametrize('executable, params', [
    ('usbcam_subscriber', {'display': 'web', 'web_port': 0, 'stats_period': 1.0}),
    ('cv_bridge_test', {}),
])
def test_an_image_over_the_limit_is_refused_and_its_memory_returns(launch, peer, executable,
                                                                   params):
    # Any member of the domain can publish one 8192x8192 image (201 MB) on the topic.
    images = peer.node.create_publisher(Image, 'usb_camera/image', QoSProfile(
        depth=1, reliability=ReliabilityPolicy.RELIABLE))
    node = launch(executable, dict(params, max_image_mb=50.0))
    small = Image(width=64, height=48, encoding='bgr8', step=192, data=bytes(64 * 48 * 3))

    def matched():
        images.publish(small)
        return images.get_subscription_count() > 0
    wait_until(matched, 30, interval=0.1, what='the node to subscribe')
    before = resident_mb(node)
    huge = Image(width=8192, height=8192, encoding='bgr8', step=8192 * 3,
                 data=bytes(8192 * 8192 * 3))
    # The image crosses the middleware in some 3,200 fragments. On a loaded machine Fast DDS
    # 2.6.0 (Humble) once delivered none of it in 60 s, the small frame before it delivered:
    # it is published again (the publisher keeps only the newest) until the node refuses it.
    for attempt in range(1, HUGE_ATTEMPTS + 1):
        images.publish(huge)
        try:
            line = node.wait_for_output(r'WARN.*refused .*8192x8192.*', timeout=30).group(0)
            break
        except AssertionError:
            if attempt == HUGE_ATTEMPTS:
                raise
    assert 'max_image_mb' in line
    # What the middleware held for it is given back.
    try:
        wait_until(lambda: resident_mb(node) < before + 60, 20, interval=0.2,
                   what='the memory to come back (it was %.0f MB before)' % before)
    except AssertionError as error:
        node.fail('%s: %.0f MB' % (error, resident_mb(node)))
    # Frames within the limit still arrive.
    processed = peer.collect(Image, 'cv_bridge_image', RELIABLE)
    offset = len(node.output())

    def arriving():
        images.publish(small)
        if executable == 'cv_bridge_test':
            return processed
        return re.search(r'received \d+ frames .*64x48', node.output()[offset:])
    wait_until(arriving, 30, interval=0.1, what='small frames after the refusal')
    alive(node)
