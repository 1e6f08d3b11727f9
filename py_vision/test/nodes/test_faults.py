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

"""Faults and bad input: nothing kills a node, nothing is lost silently."""

import json
import os
from pathlib import Path
import random
import re
import shutil
import signal
import socket
import subprocess
import sys
import time

import cv2
import numpy as np
from param_client import set_parameter
from py_vision.capture.synthetic_picture import read_frame_index, synthetic_frame
import pytest
from rclpy.qos import QoSProfile, ReliabilityPolicy
import ros_harness
from ros_harness import wait_until
from sensor_msgs.msg import Image

RELIABLE = QoSProfile(depth=100, reliability=ReliabilityPolicy.RELIABLE)


def as_image(msg):
    return np.frombuffer(msg.data, np.uint8).reshape(msg.height, msg.width, 3)


def rss_kib(pid):
    status = Path('/proc/%d/status' % pid).read_text()
    return int(re.search(r'VmRSS:\s+(\d+) kB', status).group(1))


def test_unplugged_camera_is_reopened_and_publishing_resumes(launch, peer):
    received = peer.collect(Image, 'usb_camera/image', RELIABLE)
    subscriber = launch('usbcam_subscriber', {'display': 'none', 'stats_period': 1.0})
    publisher = launch('usbcam_publisher', {
        'video_device': 'synthetic?stop_after=80&unplugged_for=2.5', 'framerate': 20.0})
    # 80 frames (4 s) leave discovery time to match the peer before the unplug.
    wait_until(lambda: received, 30, what='frames before the unplug')
    publisher.wait_for_output(r'WARN.*lost synthetic', 30)
    count_at_unplug = len(received)
    publisher.wait_for_output(r'synthetic.* is back after \d+ attempt', 30)
    wait_until(lambda: len(received) >= count_at_unplug + 10, 30, what='frames after reopen')
    out = publisher.output()
    assert out.count('lost synthetic') == 1, 'the unplug is reported once'
    attempts = re.findall(r'reopen attempt \d+ failed', out)
    # 2.5 s of back-off is several attempts; the log stays at one line per few seconds.
    assert 1 <= len(attempts) <= 2, out
    indexes = [read_frame_index(as_image(m)) for m in received]
    jumps = [b - a for a, b in zip(indexes, indexes[1:])]
    assert max(jumps) >= 20 * 2, 'the 2.5 s outage shows as missing frame indexes'
    assert indexes == sorted(indexes)
    # The subscriber's statistics show the outage as a gap: at least the 2.5 s unplugged (the
    # back-off and a loaded machine may add to it).
    gap = subscriber.wait_for_output(r'gap of (\d+\.\d+) s', 20)
    assert float(gap.group(1)) >= 2.0, subscriber.output()
    assert publisher.proc.poll() is None and subscriber.proc.poll() is None


def test_transient_read_failures_do_not_interrupt_the_stream(launch, peer):
    received = peer.collect(Image, 'usb_camera/image', RELIABLE)
    publisher = launch('usbcam_publisher', {'video_device': 'synthetic?fail_every=3',
                                            'framerate': 30.0})
    wait_until(lambda: len(received) >= 30, 30, what='30 frames')
    assert 'lost' not in publisher.output()


def test_deleted_video_file_is_retried_until_it_is_back(launch, peer, tmp_path):
    path = tmp_path / 'clip.avi'
    writer = cv2.VideoWriter(str(path), cv2.VideoWriter_fourcc(*'MJPG'), 25.0, (96, 64))
    for i in range(5):
        writer.write(np.full((64, 96, 3), i * 40, np.uint8))
    writer.release()
    saved = tmp_path / 'saved.avi'
    shutil.copy(path, saved)
    received = peer.collect(Image, 'usb_camera/image', RELIABLE)
    publisher = launch('usbcam_publisher', {'video_device': str(path), 'framerate': 50.0})
    wait_until(lambda: len(received) >= 5, 30, what='frames from the file')
    path.unlink()
    publisher.wait_for_output(r'WARN.*lost .*clip\.avi', 30)
    shutil.copy(saved, path)
    publisher.wait_for_output(r'clip\.avi is back', 30)
    count = len(received)
    wait_until(lambda: len(received) >= count + 5, 30, what='frames after the file is back')
    assert 'Traceback' not in publisher.output()


def malformed_images(count, seed=7):
    """Yield messages that are wrong in the ways other nodes' images go wrong."""
    rng = random.Random(seed)
    for i in range(count):
        msg = Image()
        msg.height, msg.width = rng.choice([(4, 4), (48, 64), (0, 10), (10, 0), (70000, 3)])
        msg.encoding = rng.choice(['bgr8', 'mono16', '', 'nonsense', '32FC1', 'rgb8'])
        bpp = {'bgr8': 3, 'rgb8': 3, 'mono16': 2, '32FC1': 4}.get(msg.encoding, 1)
        msg.step = max(0, rng.choice([msg.width * bpp, msg.width * bpp - 1, 0, 7]))
        size = msg.height * msg.step + rng.choice([-5, -1, 1, 13]) if i % 5 else 0
        msg.data = bytes(rng.getrandbits(8) for _ in range(max(0, min(size, 4096))))
        msg.is_bigendian = rng.choice([0, 1])
        yield msg


def test_malformed_images_are_reported_without_flooding_and_valid_frames_still_show(
        launch, peer):
    subscriber = launch('usbcam_subscriber', {'display': 'none', 'stats_period': 1.0})
    processor = launch('cv_bridge_test')
    subscriber.wait_for_output('no frames', 20)
    publisher = peer.node.create_publisher(Image, 'usb_camera/image', RELIABLE)
    wait_until(lambda: publisher.get_subscription_count() >= 2, 20, what='both nodes')
    rss_before = rss_kib(subscriber.proc.pid)
    bad = list(malformed_images(3000))
    started = time.monotonic()
    for msg in bad:
        publisher.publish(msg)
    burst_s = time.monotonic() - started
    subscriber.wait_for_output(r'ERROR.*malformed image\(s\) dropped', 20)
    processed = peer.collect(Image, 'cv_bridge_image', RELIABLE)
    good = synthetic_frame(5, 160, 120)
    valid = Image(height=120, width=160, encoding='bgr8', step=480, data=good.tobytes())

    def valid_frame_seen():
        publisher.publish(valid)
        return bool(processed) and subscriber.output().count('160x120 bgr8') > 0
    wait_until(valid_frame_seen, 30, interval=0.2, what='a valid frame after the garbage')
    for proc in (subscriber, processor):
        assert proc.proc.poll() is None, proc.output()
        assert 'Traceback' not in proc.output()
    # Rate-limited: a few lines for thousands of bad messages, not one per message.
    seconds = time.monotonic() - started + burst_s
    sub_errors = [line for line in subscriber.output().splitlines() if 'ERROR' in line]
    assert 1 <= len(sub_errors) <= seconds / 1.0 + 3, sub_errors
    proc_errors = [line for line in processor.output().splitlines()
                   if 'ERROR' in line or 'WARN' in line]
    assert 1 <= len(proc_errors) <= seconds / 1.0 + 5, proc_errors[:10]
    assert rss_kib(subscriber.proc.pid) - rss_before < 50 * 1024, 'memory must stay flat'


@pytest.mark.parametrize('executable,params,named', [
    ('usbcam_publisher', {'image_width': -640}, 'image_width'),
    ('usbcam_publisher', {'image_height': 0}, 'image_height'),
    ('usbcam_publisher', {'framerate': 0}, 'framerate'),
    ('usbcam_publisher', {'framerate': -5.0}, 'framerate'),
    ('usbcam_publisher', {'framerate': 'fast'}, 'framerate'),
    ('usbcam_publisher', {'reliability': 'sometimes'}, 'reliability'),
    ('usbcam_publisher', {'depth': 0}, 'depth'),
    ('usbcam_publisher', {'video_device': 'synthetic?speed=9'}, 'speed'),
    ('usbcam_subscriber', {'display': 'tv'}, 'display'),
    ('usbcam_subscriber', {'stats_period': 0}, 'stats_period'),
    ('usbcam_subscriber', {'web_port': 70000}, 'web_port'),
])
def test_bad_parameters_are_one_clear_error(launch, executable, params, named):
    params = dict(params)
    if executable == 'usbcam_publisher':
        params.setdefault('video_device', 'synthetic')
    node = launch(executable, params)
    assert node.wait_exit(20) == 1
    out = node.output()
    assert 'Traceback' not in out
    errors = [line for line in out.splitlines() if 'ERROR' in line]
    assert len(errors) == 1 and named in errors[0], out


def test_web_port_in_use_is_a_clear_error(launch):
    with socket.socket() as taken:
        taken.bind(('127.0.0.1', 0))
        taken.listen()
        port = taken.getsockname()[1]
        node = launch('usbcam_subscriber', {'display': 'web', 'web_port': port})
        assert node.wait_exit(20) == 1
    out = node.output()
    assert 'Traceback' not in out and 'web_port' in out and str(port) in out


def test_runtime_parameter_changes_are_applied_or_refused_with_a_reason(launch, peer):
    received = peer.collect(Image, 'usb_camera/image', RELIABLE)
    launch('usbcam_publisher', {'video_device': 'synthetic', 'framerate': 20.0})
    wait_until(lambda: received, 30, what='a frame')
    result = set_parameter(peer, 'usbcam_publisher', 'frame_id', 'left_camera')
    assert result.successful
    wait_until(lambda: received[-1].header.frame_id == 'left_camera', 10, what='new frame_id')
    result = set_parameter(peer, 'usbcam_publisher', 'image_width', 320)
    assert not result.successful and 'read-only' in result.reason
    assert received[-1].width == 640

    launch('usbcam_subscriber', {'display': 'none'})
    result = set_parameter(peer, 'usbcam_subscriber', 'stats_period', -1.0)
    assert not result.successful and 'stats_period' in result.reason
    # A double parameter takes doubles, as every statically typed ROS 2 parameter does.
    result = set_parameter(peer, 'usbcam_subscriber', 'stats_period', 2)
    assert not result.successful and 'type' in result.reason.lower()
    assert set_parameter(peer, 'usbcam_subscriber', 'stats_period', 2.0).successful


@pytest.mark.parametrize('executable', ['usbcam_publisher', 'usbcam_subscriber',
                                        'cv_bridge_test'])
def handles_sigterm(pid):
    """Return True once the process has its own SIGTERM handler (py_vision is importing)."""
    status = Path('/proc/%d/status' % pid).read_text()
    caught = int(re.search(r'SigCgt:\s*([0-9a-f]+)', status).group(1), 16)
    return bool(caught & (1 << (signal.SIGTERM - 1)))


# From the moment the interpreter imports py_vision: during the imports of rclpy, numpy and
# OpenCV, rclpy.init(), node creation and opening the device or the viewer's port.
@pytest.mark.parametrize('executable', ['usbcam_publisher', 'usbcam_subscriber',
                                        'cv_bridge_test'])
@pytest.mark.parametrize('delay', [0.0, 0.3, 1.0])
def test_signal_during_start_up_exits_cleanly(launch, executable, delay):
    params = {'video_device': 'synthetic'} if executable == 'usbcam_publisher' else {}
    if executable == 'usbcam_subscriber':
        params = {'display': 'web', 'web_port': 0}
    node = launch(executable, params)
    wait_until(lambda: handles_sigterm(node.proc.pid), 20, 0.005, 'py_vision to start')
    time.sleep(delay)  # deliberately not a synchronisation: the signal must land mid start-up
    assert node.stop(signal.SIGINT, timeout=3) == 0, node.output()
    assert 'Traceback' not in node.output()


@pytest.mark.parametrize('device', ['synthetic', 'file'])
def test_slow_stream_stops_at_once_and_releases_the_camera(launch, peer, tmp_path, device):
    if device == 'file':
        device = str(tmp_path / 'clip.avi')
        writer = cv2.VideoWriter(device, cv2.VideoWriter_fourcc(*'MJPG'), 5.0, (64, 48))
        writer.write(np.zeros((48, 64, 3), np.uint8))
        writer.release()
    received = peer.collect(Image, 'usb_camera/image', RELIABLE)
    # One frame every 5 s: the capture thread spends nearly all its time waiting for a frame.
    publisher = launch('usbcam_publisher', {'video_device': device, 'framerate': 0.2})
    wait_until(lambda: received, 30, what='the first frame')
    assert publisher.stop(signal.SIGINT, timeout=2) == 0
    out = publisher.output()
    assert 'Traceback' not in out and re.search(r'camera released after [1-9]\d* frames', out)


@pytest.mark.parametrize('sig', [signal.SIGINT, signal.SIGTERM])
def test_web_viewer_port_is_released_on_shutdown(launch, sig):
    with socket.socket() as probe:
        probe.bind(('127.0.0.1', 0))
        port = probe.getsockname()[1]
    node = launch('usbcam_subscriber', {'display': 'web', 'web_port': port})
    node.wait_for_output('browser viewer at http://127.0.0.1:%d/' % port, 20)
    assert node.stop(sig, timeout=3) == 0
    with socket.socket() as again:
        again.bind(('127.0.0.1', port))


NETNS_READY = os.geteuid() == 0 and shutil.which('ip') and shutil.which('unshare')


@pytest.mark.skipif(not NETNS_READY and not os.environ.get('CI'),
                    reason='network namespaces need root, ip and unshare (CI has them)')
def test_two_hosts_over_a_veth_pair(ros_env, domain_id, tmp_path):
    """Board and PC: publisher and subscriber in two network namespaces joined by veth."""
    tag = '%d%d' % (os.getpid() % 1000, domain_id)
    hosts = {'pvb%s' % tag: '10.213.%d.1' % (domain_id % 250),
             'pvp%s' % tag: '10.213.%d.2' % (domain_id % 250)}
    board, pc = hosts
    veth = ('vb%s' % tag, 'vp%s' % tag)

    def ip(*args):
        subprocess.run(['ip'] + list(args), check=True, capture_output=True)
    procs = []
    try:
        for ns in hosts:
            ip('netns', 'add', ns)
        ip('link', 'add', veth[0], 'netns', board, 'type', 'veth', 'peer', 'name', veth[1],
           'netns', pc)
        for ns, dev in zip(hosts, veth):
            ip('-n', ns, 'addr', 'add', hosts[ns] + '/24', 'dev', dev)
            ip('-n', ns, 'link', 'set', dev, 'up')
            ip('-n', ns, 'link', 'set', 'lo', 'up')

        def link_up(ns, dev):
            state = subprocess.run(['ip', '-n', ns, '-o', 'link', 'show', 'dev', dev],
                                   capture_output=True, text=True).stdout
            return 'state UP' in state
        # Fast DDS picks its interfaces at start-up: the veth must be up before the nodes are.
        for ns, dev in zip(hosts, veth):
            wait_until(lambda: link_up(ns, dev), 10, what='%s up in %s' % (dev, ns))
        env = ros_harness.with_discovery(dict(ros_env), 'subnet')

        def in_host(ns, cmd, log):
            # A private /dev/shm per host, so Fast DDS cannot take a shared-memory shortcut.
            shell = 'mount -t tmpfs tmpfs /dev/shm && exec "$@"'
            wrapped = ['ip', 'netns', 'exec', ns, 'unshare', '--mount', 'sh', '-c', shell,
                       'sh'] + cmd
            return subprocess.Popen(wrapped, env=env, stdout=log, stderr=subprocess.STDOUT,
                                    start_new_session=True)
        checker_log = open(tmp_path / 'checker.log', 'w+')
        publisher_log = open(tmp_path / 'publisher.log', 'w+')
        checker = str(Path(__file__).parents[1] / 'frame_checker.py')
        procs.append(in_host(pc, [sys.executable, checker, '30'], checker_log))
        procs.append(in_host(board, [str(ros_harness.EXECUTABLES / 'usbcam_publisher'),
                                     '--ros-args', '-p', 'video_device:=synthetic',
                                     '-p', 'framerate:=15.0'], publisher_log))
        try:
            procs[0].wait(60)
        except subprocess.TimeoutExpired:
            publisher_log.seek(0)
            checker_log.seek(0)
            raise AssertionError('no 30 frames across the veth pair in 60 s:\n%s\n%s' % (
                publisher_log.read(), checker_log.read()))
        checker_log.seek(0)
        result = json.loads(checker_log.read().strip().splitlines()[-1])
        assert result['frames'] == 30 and result['intact'] == 30, result
        assert result['indexes'] == sorted(result['indexes'])
    finally:
        for proc in procs:
            ros_harness.end_process_group(proc)
        for ns in hosts:
            subprocess.run(['ip', 'netns', 'del', ns], capture_output=True)
