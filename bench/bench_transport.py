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
import json
import os
from pathlib import Path
import re
import statistics
import subprocess
import sys
import tempfile
import time

BENCH = Path(__file__).resolve().parent
REPO = BENCH.parent
INSTALL = Path(os.environ.get('PY_VISION_INSTALL', REPO / 'install')).resolve()
CLK_TCK = os.sysconf('SC_CLK_TCK')
NETNS = ('pyvt_pub', 'pyvt_sub')
VETH = ('pyvt_a', 'pyvt_b')
ADDRESSES = ('10.78.0.1', '10.78.0.2')
PRIVATE_SHM = 'mount -t tmpfs -o size=1g pyvt_shm /dev/shm && exec "$@"'

sys.path.insert(0, str(REPO / 'py_vision' / 'test'))
from ros_harness import DomainId  # noqa: E402,I100 (the tests' domain reservations)
FIRST_FRAME_MARK = 'BENCH first frame'  # what bench_common.announce_first_frame prints


def installed_env(domain):
    """Return the environment of `source install/setup.bash`, without any DDS profile."""
    out = subprocess.run(['bash', '-c', 'source "$0" && env -0', str(INSTALL / 'setup.bash')],
                         check=True, capture_output=True).stdout
    env = dict(item.split('=', 1) for item in out.decode().split('\0') if '=' in item)
    for name in ('FASTRTPS_DEFAULT_PROFILES_FILE', 'FASTDDS_DEFAULT_PROFILES_FILE',
                 'RMW_IMPLEMENTATION', 'ROS_LOCALHOST_ONLY', 'ROS_STATIC_PEERS'):
        env.pop(name, None)
    env.update(ROS_DOMAIN_ID=str(domain), PYTHONUNBUFFERED='1',
               ROS_AUTOMATIC_DISCOVERY_RANGE='SUBNET')
    return env


def cpu_ticks(pid):
    """Return utime + stime of a process in clock ticks."""
    with open('/proc/%d/stat' % pid) as stream:
        fields = stream.read().rsplit(')', 1)[1].split()
    return int(fields[11]) + int(fields[12])


# ----------------------------------------------------------------------- helper processes

def run_subscriber(kind, topic, out):
    """Run a bare subscriber: ROS defaults (reliable, keep last 10) or best effort."""
    import rclpy
    from rclpy.qos import QoSProfile, ReliabilityPolicy
    from rclpy.signals import SignalHandlerOptions
    from sensor_msgs.msg import CompressedImage, Image
    from bench_common import announce_first_frame, monotonic, StopFlag, write_json
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
    from bench_common import monotonic, StopFlag, write_json
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
    from bench_common import StopFlag, write_json
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

    def start(self, name, cmd, netns=None):
        if netns:
            cmd = ['ip', 'netns', 'exec', netns, 'unshare', '-m', 'sh', '-c',
                   PRIVATE_SHM, 'sh'] + cmd
        log = open(Path(self.workdir) / (name + '.log'), 'w')
        proc = subprocess.Popen(cmd, env=self.env, stdout=log, stderr=subprocess.STDOUT,
                                cwd=str(BENCH), start_new_session=True)
        proc.name, proc.log, proc.out = name, log.name, str(Path(self.workdir) / (name + '.json'))
        self.procs.append(proc)
        return proc

    def subscriber(self, kind, topic, netns=None):
        name = 'sub%d' % len(self.procs)
        proc = self.start(name, [sys.executable, __file__, '--role', 'sub', kind, topic,
                                 str(Path(self.workdir) / (name + '.json'))], netns)
        self.wait_log(proc, 'subscribed')
        return proc

    def publisher(self, params, role='publisher', netns=None):
        name = 'pub%d' % len(self.procs)
        args = ['--ros-args'] + [a for k, v in params.items() for a in ('-p', '%s:=%s' % (k, v))]
        return self.start(name, [sys.executable, str(BENCH / 'pyv_nodes.py'), role,
                                 str(Path(self.workdir) / (name + '.json'))] + args, netns)

    def camera(self, width, height, fps, pixel_format):
        name = 'cam%d' % len(self.procs)
        return self.start(name, [sys.executable, __file__, '--role', 'cam', str(width),
                                 str(height), str(fps), pixel_format,
                                 str(Path(self.workdir) / (name + '.json'))])

    def reference(self, width, height, fps):
        name = 'ref%d' % len(self.procs)
        return self.start(name, [sys.executable, __file__, '--role', 'ref', str(width),
                                 str(height), str(fps),
                                 str(Path(self.workdir) / (name + '.json'))])

    def wait_log(self, proc, text, timeout=60.0):
        deadline = time.monotonic() + timeout
        while text not in Path(proc.log).read_text(errors='replace'):
            if proc.poll() is not None or time.monotonic() > deadline:
                raise RuntimeError('%s never printed %r:\n%s' % (
                    proc.name, text, Path(proc.log).read_text(errors='replace')))
            time.sleep(0.05)

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
            if proc.poll() is None:
                proc.send_signal(2)
            try:
                proc.wait(20)
            except subprocess.TimeoutExpired:
                os.killpg(proc.pid, 9)
                proc.wait()
            data = json.loads(Path(proc.out).read_text()) if Path(proc.out).exists() else {}
            results[proc.name] = (data, Path(proc.log).read_text(errors='replace'))
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
            case.wait_log(sub, FIRST_FRAME_MARK)
        if not subs:
            case.wait_log(pub, 'opened synthetic')
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
                case.wait_log(sub, FIRST_FRAME_MARK)
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


def netns_setup():
    commands = [
        'ip netns add %s' % NETNS[0], 'ip netns add %s' % NETNS[1],
        'ip link add %s type veth peer name %s' % VETH,
        'ip link set %s netns %s' % (VETH[0], NETNS[0]),
        'ip link set %s netns %s' % (VETH[1], NETNS[1])]
    for ns, dev, addr in zip(NETNS, VETH, ADDRESSES):
        commands += ['ip -n %s addr add %s/24 dev %s' % (ns, addr, dev),
                     'ip -n %s link set %s up' % (ns, dev), 'ip -n %s link set lo up' % ns,
                     'ip -n %s route add 224.0.0.0/4 dev %s' % (ns, dev)]
    for command in commands:
        subprocess.run(command.split(), check=True)


def netns_teardown():
    for ns in NETNS:
        subprocess.run(['ip', 'netns', 'del', ns], capture_output=True)


def hosts_cases(args, env):
    if os.geteuid() != 0:
        print('hosts: needs root for network namespaces; skipped')
        return []
    rows = []
    netns_teardown()
    netns_setup()
    try:
        for width, height in ((640, 480), (1280, 720)):
            for topic, kind in (('usb_camera/image/compressed', 'compressed_be'),
                                ('usb_camera/image', 'raw_be')):
                with tempfile.TemporaryDirectory(prefix='pyv_transport_') as workdir:
                    case = Case(args, env, workdir)
                    sub = case.subscriber(kind, topic, NETNS[1])
                    case.publisher({'video_device': 'synthetic', 'image_width': width,
                                    'image_height': height, 'framerate': 30.0,
                                    'reliability': 'best_effort'}, netns=NETNS[0])
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
        netns_teardown()
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
    sys.path.insert(0, str(BENCH))
    from bench_common import save_results
    domain = DomainId()
    env = installed_env(domain.value)
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
