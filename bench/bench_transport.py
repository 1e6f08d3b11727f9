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
What compressed streams, lazy publishing and CameraInfo cost the publisher, and what crosses.

  .venv/bin/python bench/bench_transport.py [--window S] [--repeat N] [--only cpu|bytes|hosts]

cpu    usbcam_publisher's CPU with the synthetic MJPEG camera at 1920x1080@30: compressed
       subscribers only, against a bare rclpy publisher of the same prebuilt JPEG bytes at the
       same rate (the reference, same run); one and two raw subscribers (JPEG decodes counted
       by the node); nothing subscribed. Then CameraInfo on against off (bench/pyv_nodes.py's
       publisher-noinfo) at 640x480@30 and 1920x1080@30, compressed subscriber.
bytes  bytes per second on usb_camera/image and usb_camera/image/compressed at 640x480,
       1280x720 and 1920x1080 at 30 fps (pixel_format auto).
hosts  two network namespaces joined by a veth pair (root only): py_vision's publisher on one,
       a bare subscriber with Fast DDS defaults (no profile, best effort) on the other;
       delivered frames of the compressed and the raw topic at 640x480@30 and 1280x720@30.

CPU is utime+stime from /proc over the window, after the first frame and a settling second.
Cases are interleaved over --repeat rounds; medians are reported. Writes
bench/results/transport.json and prints Markdown tables.
"""

import argparse
import functools
import re
import statistics
import sys
import tempfile
import time

from bench_common import (announce_first_frame, BENCH, CLK_TCK, cpu_ticks, FIRST_FRAME_MARK,
                          monotonic, read_results, save_results, start_helper, StopFlag,
                          write_json)
import ros_harness
from ros_harness import DomainId


# ----------------------------------------------------------------------- helper processes

def run_subscriber(kind, topic, out):
    """Run a bare subscriber: ROS defaults (reliable, keep last 10) or best effort."""
    import rclpy
    from rclpy.qos import QoSProfile, ReliabilityPolicy
    from rclpy.signals import SignalHandlerOptions
    from sensor_msgs.msg import CompressedImage, Image
    rclpy.init(signal_handler_options=SignalHandlerOptions.NO)
    stop = StopFlag()
    node = rclpy.create_node('bench_transport_subscriber')
    records = []

    def received(msg):
        if not records:
            announce_first_frame()
        stamp = msg.header.stamp.sec + msg.header.stamp.nanosec * 1e-9
        records.append((monotonic(), stamp, len(msg.data)))
    reliability = ReliabilityPolicy.BEST_EFFORT if kind.endswith('_be') else \
        ReliabilityPolicy.RELIABLE
    msg_type = CompressedImage if kind.startswith('compressed') else Image
    node.create_subscription(msg_type, topic, received,
                             QoSProfile(depth=10, reliability=reliability))
    print('subscribed', flush=True)
    while not stop.is_set():
        rclpy.spin_once(node, timeout_sec=0.1)
    write_json(out, {'received': records})
    node.destroy_node()
    rclpy.try_shutdown()


def run_reference(width, height, fps, out):
    """Run a bare rclpy publisher of prebuilt JPEG frames (what the camera sends), paced."""
    import rclpy
    from rclpy.signals import SignalHandlerOptions
    from sensor_msgs.msg import CompressedImage
    from py_vision.capture.synthetic_picture import synthetic_jpeg
    rclpy.init(signal_handler_options=SignalHandlerOptions.NO)
    stop = StopFlag()
    node = rclpy.create_node('bench_transport_reference')
    publisher = node.create_publisher(CompressedImage, 'usb_camera/image/compressed', 10)
    frames = [synthetic_jpeg(i, width, height) for i in range(64)]
    clock = node.get_clock()
    start, index = monotonic(), 0
    while not stop.is_set():
        delay = start + index / fps - monotonic()
        if delay > 0:
            time.sleep(delay)
        msg = CompressedImage(format='bgr8; jpeg compressed bgr8')
        msg.header.stamp = clock.now().to_msg()
        msg.data = frames[index % len(frames)]
        publisher.publish(msg)
        index += 1
    write_json(out, {'published': index})
    node.destroy_node()
    rclpy.try_shutdown()


def run_camera(width, height, fps, pixel_format, out):
    """Read the synthetic camera alone, as the publisher does: what the camera costs."""
    import cv2
    from py_vision.capture import Camera
    cv2.setNumThreads(1)  # as usbcam_publisher runs it
    stop = StopFlag()
    camera = Camera.open('synthetic', width, height, fps, pixel_format)
    print('opened synthetic', flush=True)
    frames = 0
    while not stop.is_set():
        frames += camera.read() is not None
    camera.release()
    write_json(out, {'frames': frames})


# ----------------------------------------------------------------------- one measurement

class Case:
    """One publisher and its subscribers, measured over a window."""

    def __init__(self, args, env, workdir):
        self.args, self.env, self.workdir = args, env, workdir
        self.procs = []

    def start(self, name, cmd, wrap=None):
        proc = start_helper(name, cmd, self.env, self.workdir, wrap)
        self.procs.append(proc)
        return proc

    def subscriber(self, kind, topic, wrap=None):
        proc = self.start('sub%d' % len(self.procs), [
            sys.executable, __file__, '--role', 'sub', kind, topic, '{out}'], wrap)
        proc.wait_for_output('subscribed', 60.0)
        return proc

    def publisher(self, params, role='publisher', wrap=None):
        args = ['--ros-args'] + [a for k, v in params.items() for a in ('-p', '%s:=%s' % (k, v))]
        return self.start('pub%d' % len(self.procs), [
            sys.executable, str(BENCH / 'pyv_nodes.py'), role, '{out}'] + args, wrap)

    def camera(self, width, height, fps, pixel_format):
        return self.start('cam%d' % len(self.procs), [
            sys.executable, __file__, '--role', 'cam', str(width), str(height), str(fps),
            pixel_format, '{out}'])

    def reference(self, width, height, fps):
        return self.start('ref%d' % len(self.procs), [
            sys.executable, __file__, '--role', 'ref', str(width), str(height), str(fps),
            '{out}'])

    def measure_cpu(self, proc):
        """Settle, then return the CPU % of proc over the window."""
        # The synthetic MJPEG camera encodes each of its 64 scene positions once, in the
        # first 64 frames: the window starts after them.
        time.sleep(2.5)
        ticks, t0 = cpu_ticks(proc.pid), time.monotonic()
        time.sleep(self.args.window)
        return 100.0 * (cpu_ticks(proc.pid) - ticks) / CLK_TCK / (time.monotonic() - t0)

    def stop(self):
        """Stop every process (Ctrl-C), return {name: (results, log text)}."""
        results = {}
        for proc in reversed(self.procs):
            proc.end(timeout=20.0)
            results[proc.name] = (read_results(proc) or {}, proc.output())
        return results


def counters(log):
    """Return what the publisher's last line counts: frames, raw, compressed, encoded, decoded."""
    match = re.search(r'after (\d+) frames \((\d+) raw, (\d+) compressed published; (\d+) '
                      r'JPEG encoded, (\d+) decoded\)', log)
    return [int(v) for v in match.groups()] if match else None


# ----------------------------------------------------------------------- the benchmarks

def cpu_cases(args, env):
    camera = {'video_device': 'synthetic', 'image_width': 1920, 'image_height': 1080,
              'framerate': 30.0, 'pixel_format': 'mjpeg'}
    vga = {'video_device': 'synthetic', 'framerate': 30.0}
    return [
        ('reference: bare publisher of the same JPEG bytes, compressed subscriber',
         None, ['compressed'], 'ref'),
        ('the synthetic 1080p MJPEG camera alone (no ROS)', camera, [], 'cam'),
        ('1080p MJPEG, compressed subscriber', camera, ['compressed'], 'publisher'),
        ('1080p MJPEG, 1 raw subscriber', camera, ['raw'], 'publisher'),
        ('1080p MJPEG, 2 raw subscribers', camera, ['raw', 'raw'], 'publisher'),
        ('1080p MJPEG, nothing subscribed', camera, [], 'publisher'),
        ('1080p MJPEG, compressed subscriber, CameraInfo off', camera, ['compressed'],
         'publisher-noinfo'),
        ('VGA auto, raw subscriber, CameraInfo on', vga, ['raw'], 'publisher'),
        ('VGA auto, raw subscriber, CameraInfo off', vga, ['raw'], 'publisher-noinfo'),
    ]


def run_cpu_case(args, env, case_def):
    name, params, subscribers, role = case_def
    with tempfile.TemporaryDirectory(prefix='pyv_transport_') as workdir:
        case = Case(args, env, workdir)
        subs = [case.subscriber(kind, 'usb_camera/image' + (
            '/compressed' if kind == 'compressed' else '')) for kind in subscribers]
        if role == 'ref':
            pub = case.reference(1920, 1080, 30.0)
        elif role == 'cam':
            pub = case.camera(1920, 1080, 30.0, 'mjpg')
        else:
            pub = case.publisher(params, role)
        for sub in subs:
            sub.wait_for_output(FIRST_FRAME_MARK, 60.0)
        if not subs:
            pub.wait_for_output('opened synthetic', 60.0)
            time.sleep(1.0)
        cpu = case.measure_cpu(pub)
        results = case.stop()
    count = counters(results[pub.name][1]) if role not in ('ref', 'cam') else None
    return {'case': name, 'cpu_percent': cpu, 'counters': count}


def bytes_cases(args, env):
    rows = []
    for width, height in ((640, 480), (1280, 720), (1920, 1080)):
        with tempfile.TemporaryDirectory(prefix='pyv_transport_') as workdir:
            case = Case(args, env, workdir)
            raw = case.subscriber('raw', 'usb_camera/image')
            compressed = case.subscriber('compressed', 'usb_camera/image/compressed')
            pub = case.publisher({'video_device': 'synthetic', 'image_width': width,
                                  'image_height': height, 'framerate': 30.0})
            for sub in (raw, compressed):
                sub.wait_for_output(FIRST_FRAME_MARK, 60.0)
            case.measure_cpu(pub)
            results = case.stop()
        row = {'size': '%dx%d' % (width, height)}
        for label, proc in (('raw', raw), ('compressed', compressed)):
            records = results[proc.name][0].get('received', [])
            span = records[-1][0] - records[0][0] if len(records) > 1 else 0
            row[label + '_MBps'] = (sum(r[2] for r in records[1:]) / span / 1e6) if span else 0
            row[label + '_fps'] = (len(records) - 1) / span if span else 0
        row['format'] = 'MJPEG' if 'MJPEG' in results[pub.name][1] else 'YUYV'
        rows.append(row)
    return rows


def hosts_cases(args, env):
    why_not = ros_harness.two_hosts_unavailable()
    if why_not:
        print('hosts: %s; skipped' % why_not)
        return []
    rows = []
    hosts = ros_harness.TwoHosts(('publisher', 'subscriber'))
    try:
        for width, height in ((640, 480), (1280, 720)):
            for topic, kind in (('usb_camera/image/compressed', 'compressed_be'),
                                ('usb_camera/image', 'raw_be')):
                with tempfile.TemporaryDirectory(prefix='pyv_transport_') as workdir:
                    case = Case(args, env, workdir)
                    sub = case.subscriber(kind, topic,
                                          functools.partial(hosts.command, 'subscriber'))
                    case.publisher({'video_device': 'synthetic', 'image_width': width,
                                    'image_height': height, 'framerate': 30.0,
                                    'reliability': 'best_effort'},
                                   wrap=functools.partial(hosts.command, 'publisher'))
                    time.sleep(3.0 + args.window)
                    results = case.stop()
                records = results[sub.name][0].get('received', [])
                stamps = sorted({round(r[1], 4) for r in records})
                delivered = None
                if len(stamps) > 30:
                    # Frames are captured every 1/30 s exactly: the stamps say how many were
                    # published over the span the subscriber saw.
                    stamps = stamps[15:]
                    expected = round((stamps[-1] - stamps[0]) * 30.0) + 1
                    delivered = 100.0 * len(stamps) / expected
                rows.append({'size': '%dx%d' % (width, height), 'topic': topic,
                             'received': len(records), 'delivered_percent': delivered})
    finally:
        hosts.close()
    return rows


def main():
    parser = argparse.ArgumentParser(description=__doc__.split('\n\n')[0])
    parser.add_argument('--window', type=float, default=8.0)
    parser.add_argument('--repeat', type=int, default=3)
    parser.add_argument('--only', choices=('cpu', 'bytes', 'hosts'))
    parser.add_argument('--role', nargs='+', help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.role:
        role, rest = args.role[0], args.role[1:]
        if role == 'sub':
            return run_subscriber(*rest)
        if role == 'cam':
            return run_camera(int(rest[0]), int(rest[1]), float(rest[2]), rest[3], rest[4])
        return run_reference(int(rest[0]), int(rest[1]), float(rest[2]), rest[3])
    domain = DomainId()
    env = dict(ros_harness.plain_env(), ROS_DOMAIN_ID=str(domain.value),
               ROS_AUTOMATIC_DISCOVERY_RANGE='SUBNET')
    result = {'window_s': args.window, 'repeat': args.repeat}
    if args.only in (None, 'cpu'):
        rounds = {}
        for _ in range(args.repeat):
            for case_def in cpu_cases(args, env):
                rounds.setdefault(case_def[0], []).append(run_cpu_case(args, env, case_def))
        names = [case_def[0] for case_def in cpu_cases(args, env)]
        reference = statistics.median(r['cpu_percent'] for r in rounds[names[0]])
        camera = statistics.median(r['cpu_percent'] for r in rounds[names[1]])
        rows = []
        print("\n| case | CPU % (median) | x reference | without the camera's own CPU, "
              'x reference | frames, raw, compressed, encoded, decoded (last round) |'
              '\n|---|---:|---:|---:|---|')
        for name, runs in rounds.items():
            cpu = statistics.median(r['cpu_percent'] for r in runs)
            driver = cpu - camera if '1080p MJPEG' in name else None
            rows.append({'case': name, 'cpu_percent': cpu, 'ratio': cpu / reference,
                         'without_camera_ratio': driver / reference if driver else None,
                         'counters': runs[-1]['counters'],
                         'all': [r['cpu_percent'] for r in runs]})
            print('| %s | %.1f | %.2f | %s | %s |' % (
                name, cpu, cpu / reference, '%.2f' % (driver / reference) if driver else '-',
                runs[-1]['counters'] or '-'))
        result['cpu'] = rows
    if args.only in (None, 'bytes'):
        rows = bytes_cases(args, env)
        print('\n| size | camera format | raw MB/s | raw fps | compressed MB/s | compressed fps |'
              '\n|---|---|---:|---:|---:|---:|')
        for row in rows:
            print('| %s | %s | %.1f | %.1f | %.2f | %.1f |' % (
                row['size'], row['format'], row['raw_MBps'], row['raw_fps'],
                row['compressed_MBps'], row['compressed_fps']))
        result['bytes'] = rows
    if args.only in (None, 'hosts'):
        rows = hosts_cases(args, env)
        if rows:
            print('\n| size | topic | frames received | delivered % |\n|---|---|---:|---:|')
            for row in rows:
                print('| %s | %s | %d | %s |' % (
                    row['size'], row['topic'], row['received'],
                    '-' if row['delivered_percent'] is None else
                    '%.1f' % row['delivered_percent']))
        result['hosts'] = rows
    domain.release()
    save_results('transport', result)


if __name__ == '__main__':
    main()
