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
Measure how soon hand_signs stops the robot: after the camera's last frame, and after SIGINT.

  .venv/bin/python bench/bench_command_stop.py [--rounds 100] [--sigint-rounds 20] [--load N]

The node is vision_step running hand_signs with its tracker replaced by one that sees a
thumbs-up in every frame the bench marks so (the real step, gate and publishers; the models are
loaded but not run), and `--work-ms` of work a frame in their place (`--work opencv`: outside
Python's GIL, as a model's invoke; `python`: a Python loop holding it). The bench publishes
the frames (640x480 bgr8, 30 fps) and subscribes to the commands, in this process.

- camera stop: frames until a moving command arrives, then none; the time from the last frame
  sent to the first zero received, `--rounds` times, with command_timeout 0.5 s. What the
  watchdog adds is that time less command_timeout.
- SIGINT: a node started, frames until a moving command, SIGINT while the frames go on and a
  frame is being processed (`--sigint-work-ms` a frame: the stop does not wait for it); the
  time from the signal to the first zero received, `--sigint-rounds` times.

Each runs first with the machine as it is, then under load: `--load` busy processes (one per
CPU by default) beside the node. Prints a Markdown table (p50, p99, max) and writes
bench/results/command_stop.json.
"""

import argparse
import os
from pathlib import Path
import signal
import subprocess
import sys
import tempfile
import threading
import time

from bench_common import local_node_env, save_results, stopped_after, TESTS
import ros_harness

COMMAND_TIMEOUT = 0.5
FPS = 30.0
WIDTH, HEIGHT = 640, 480
CMD_VEL = '/turtle1/cmd_vel'
STEP = 'bench_signs:BenchSigns'
BUSY = 'import os\nos.nice(0)\nwhile True:\n    pass\n'

# The step double: hand_signs with a tracker that sees a thumbs-up where the frame's first
# pixel's blue is 1, after `work_ms` of work in the models' place: OpenCV filtering, which like
# a model's invoke runs outside Python's GIL (BENCH_WORK=python: a busy Python loop instead,
# which holds it, the worst case for the node's other threads).
STEP_MODULE = """
import os
import time

import cv2
import numpy as np
from hand_poses import thumb_up
from py_vision.models.hands import Hand
from py_vision.steps.hand_signs import HandSigns

WORK_S = float(os.environ.get('BENCH_WORK_MS', '0')) / 1e3
IN_PYTHON = os.environ.get('BENCH_WORK') == 'python'


def work(seconds):
    end = time.perf_counter() + seconds
    pixels = np.zeros((240, 320, 3), np.uint8)
    while time.perf_counter() < end:
        if not IN_PYTHON:
            cv2.blur(pixels, (15, 15), dst=pixels)


class Thumbs:
    def find(self, image):
        work(WORK_S)
        return [Hand(thumb_up(), 'right', 0.9)] if image[0, 0, 0] == 1 else []


class BenchSigns(HandSigns):
    def start(self, context):
        note = super().start(context)
        self.tracker = Thumbs()
        return note
"""


class Bench:
    """The frames the bench sends and the commands it receives, on a ROS peer of its own."""

    def __init__(self, peer):
        import numpy as np
        from geometry_msgs.msg import Twist
        from rclpy.qos import QoSProfile, ReliabilityPolicy
        from sensor_msgs.msg import Image
        reliable = QoSProfile(depth=100, reliability=ReliabilityPolicy.RELIABLE)
        self.peer = peer
        self.commands = []   # (arrival, moving)
        self._lock = threading.Lock()
        peer.node.create_subscription(Twist, CMD_VEL, self._received, reliable)
        self.publisher = peer.node.create_publisher(Image, 'usb_camera/image', reliable)
        image = np.zeros((HEIGHT, WIDTH, 3), np.uint8)
        image[0, 0, 0] = 1
        self.frame = Image(height=HEIGHT, width=WIDTH, encoding='bgr8', step=WIDTH * 3,
                           data=image.tobytes())
        self.sending = threading.Event()
        self.last_sent = 0.0
        self._closed = False
        self._thread = threading.Thread(target=self._camera, daemon=True)
        self._thread.start()

    def _received(self, msg):
        with self._lock:
            self.commands.append((time.monotonic(), msg.linear.x != 0.0))

    def _camera(self):
        period = 1.0 / FPS
        next_at = time.monotonic()
        while not self._closed:
            if self.sending.is_set():
                self.publisher.publish(self.frame)
                self.last_sent = time.monotonic()
            next_at += period
            time.sleep(max(0.0, next_at - time.monotonic()))

    def count(self):
        with self._lock:
            return len(self.commands)

    def moving_since(self, index, timeout=30.0):
        """Wait for a moving command among those from the index-th on."""
        def found():
            with self._lock:
                return any(moving for _, moving in self.commands[index:])
        ros_harness.wait_until(found, timeout, 0.005, 'a moving command')

    def zero_after(self, moment):
        """Return the arrival of the first zero command after moment, or None."""
        with self._lock:
            return next((at for at, moving in self.commands if at > moment and not moving),
                        None)

    def close(self):
        self._closed = True
        self._thread.join(2.0)


def start_node(env, work_ms):
    # command_timeout longer than a frame's work (the SIGINT cases' frames take longer than
    # COMMAND_TIMEOUT: the watchdog would stop the robot between every two of them).
    timeout = max(COMMAND_TIMEOUT, 3 * work_ms / 1e3)
    node = ros_harness.NodeProcess('vision_step', ros_harness.ros_args({
        'step': STEP, 'command_timeout': timeout, 'max_frame_age': timeout}),
        dict(env, BENCH_WORK_MS=str(work_ms)))
    node.wait_for_output('running step %s' % STEP, timeout=120.0)
    return node


def camera_stops(env, work_ms, rounds):
    """Return the seconds from the last frame to the first zero, once per round."""
    domain = ros_harness.DomainId()
    env = dict(env, ROS_DOMAIN_ID=str(domain.value))
    node = start_node(env, work_ms)
    peer = ros_harness.RosPeer(domain.value, name='bench_commands')
    bench = Bench(peer)
    times = []
    with stopped_after(domain, peer, node):
        try:
            for _ in range(rounds):
                start = bench.count()
                bench.sending.set()
                bench.moving_since(start)
                bench.sending.clear()
                time.sleep(2.0 / FPS)   # the frame being sent is out (last_sent is final)
                last = bench.last_sent
                zero = ros_harness.wait_until(lambda: bench.zero_after(last), 30.0, 0.005,
                                              'the zero')
                times.append(zero - last)
        finally:
            bench.close()
    return times


def sigint_stops(env, work_ms, rounds):
    """Return the seconds from SIGINT to the first zero, once per round (a node each)."""
    times = []
    for _ in range(rounds):
        domain = ros_harness.DomainId()
        round_env = dict(env, ROS_DOMAIN_ID=str(domain.value))
        node = start_node(round_env, work_ms)
        peer = ros_harness.RosPeer(domain.value, name='bench_commands')
        bench = Bench(peer)
        try:
            bench.sending.set()
            bench.moving_since(0)
            # Into a frame's processing: a moving command arrives as its frame ends.
            count = bench.count()
            ros_harness.wait_until(lambda: bench.count() > count, 30.0, 0.001, 'a command')
            time.sleep(min(work_ms / 2e3, 0.1))
            signalled = time.monotonic()
            os.kill(node.pid, signal.SIGINT)
            zero = ros_harness.wait_until(lambda: bench.zero_after(signalled), 30.0, 0.001,
                                          'the stop')
            times.append(zero - signalled)
            status = node.wait_exit(30.0)
            log = node.output()
        finally:
            bench.close()
            peer.close()
            node.kill()
            domain.release()
        if status != 0 or 'Traceback' in log:
            raise SystemExit('vision_step ended with %s:\n%s' % (status, log))
    return times


def summary(times):
    from py_vision.stats import percentile
    values = sorted(times)
    return {'n': len(values), 'p50_ms': round(percentile(values, 0.5) * 1e3, 1),
            'p99_ms': round(percentile(values, 0.99) * 1e3, 1),
            'max_ms': round(values[-1] * 1e3, 1)}


class Load:
    """Busy processes beside the node, one per CPU unless told."""

    def __init__(self, count):
        self.procs = [subprocess.Popen([sys.executable, '-c', BUSY]) for _ in range(count)]

    def close(self):
        for proc in self.procs:
            proc.kill()
            proc.wait()


def main():
    parser = argparse.ArgumentParser(description=__doc__.split('\n\n')[1])
    parser.add_argument('--rounds', type=int, default=100, help='camera stops a case')
    parser.add_argument('--sigint-rounds', type=int, default=20, help='SIGINTs a case')
    parser.add_argument('--load', type=int, default=os.cpu_count(),
                        help='busy processes in the loaded cases (default: one per CPU)')
    parser.add_argument('--work-ms', type=float, default=20.0,
                        help="busy work a frame in the models' place (camera stops)")
    parser.add_argument('--sigint-work-ms', type=float, default=500.0,
                        help='busy work a frame in the SIGINT cases (a frame under way)')
    parser.add_argument('--work', choices=('opencv', 'python'), default='opencv',
                        help="the work in the models' place: OpenCV (outside the GIL, as a "
                             "model's invoke) or a Python loop (holding it)")
    options = parser.parse_args()

    env = dict(local_node_env(), BENCH_WORK=options.work)
    workdir = Path(tempfile.mkdtemp(prefix='bench_command_stop_'))
    (workdir / 'bench_signs.py').write_text(STEP_MODULE)
    env['PYTHONPATH'] = os.pathsep.join(p for p in (str(workdir), str(TESTS),
                                                    env.get('PYTHONPATH', '')) if p)
    cases = []
    for loaded in (False, True):
        load = Load(options.load) if loaded else None
        try:
            label = 'under load (%d busy)' % options.load if loaded else 'as it is'
            print('camera stops, %s ...' % label, flush=True)
            stops = summary(camera_stops(env, options.work_ms, options.rounds))
            stops['beyond_timeout_p50_ms'] = round(stops['p50_ms'] - COMMAND_TIMEOUT * 1e3, 1)
            cases.append(dict(stops, what='last frame to zero', loaded=loaded,
                              load_average=round(os.getloadavg()[0], 1)))
            print('  %s' % cases[-1], flush=True)
            print('SIGINT, %s ...' % label, flush=True)
            cases.append(dict(summary(sigint_stops(env, options.sigint_work_ms,
                                                   options.sigint_rounds)),
                              what='SIGINT to zero', loaded=loaded,
                              load_average=round(os.getloadavg()[0], 1)))
            print('  %s' % cases[-1], flush=True)
        finally:
            if load is not None:
                load.close()

    import rclpy
    print('\nvision_step hand_signs, command_timeout %g s, work %s (%g ms a frame, %g ms in '
          'the SIGINT cases), on Python %s (rclpy from %s), %d CPUs' % (
              COMMAND_TIMEOUT, options.work, options.work_ms, options.sigint_work_ms,
              sys.version.split()[0], rclpy.__file__.split('/lib/python')[0], os.cpu_count()))
    print('\n| what | machine | load average | rounds | p50 | p99 | max |')
    print('|---|---|---:|---:|---:|---:|---:|')
    for case in cases:
        print('| %s | %s | %.1f | %d | %.1f ms | %.1f ms | %.1f ms |' % (
            case['what'], 'loaded (%d busy)' % options.load if case['loaded'] else 'as it is',
            case['load_average'], case['n'], case['p50_ms'], case['p99_ms'], case['max_ms']))
    save_results('command_stop', {
        'command_timeout_s': COMMAND_TIMEOUT, 'fps': FPS, 'work_ms': options.work_ms,
        'work': options.work,
        'sigint_work_ms': options.sigint_work_ms, 'load_processes': options.load,
        'cpus': os.cpu_count(), 'cases': cases})


if __name__ == '__main__':
    main()
