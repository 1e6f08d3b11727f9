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
Where a received frame's CPU goes, in one receiver of bench_receive.py: threads and functions.

  .venv/bin/python bench/profile_receive.py RECEIVER [--size 640x480] [--seconds 20]
      [--py-spy PATH]

RECEIVER is one of bench_receive.py's (bare, usbcam_subscriber, 'vision_step nothing', ...),
fed by the same bare publisher at 30 fps. Over the window: each thread's CPU (user and kernel)
a frame, from /proc/PID/task, the Python threads named by `py-spy dump`, the others (Fast
DDS') grouped; and, from `py-spy record --native` samples of the Python threads, what their
CPU went to: the executor's own Python, the middleware's take and deserialisation, rclpy's
conversion of the C message to Python, the node's callback, the receive thread's loop.
py-spy is not a dependency of the project: `pip install py-spy` (a PyPI wheel), or give its
path. Frames are counted at the publisher's rate (bench_receive.py shows every receiver
gets them all).
"""

import argparse
import collections
import os
import re
import shutil
import subprocess
import sys
import tempfile
import time

from bench_common import BENCH, CLK_TCK, FIRST_FRAME_MARK, local_node_env, start_helper
from bench_receive import parse_sizes, receiver_command, RECEIVERS
import ros_harness

FPS = 30.0
# Leaf frames of a thread that waits (py-spy's native stacks see waiting threads too).
IDLE = ('rcl_wait', 'pthread_cond_wait', 'pthread_cond_timedwait', 'pthread_cond_clockwait',
        'epoll_wait', 'sem_wait', 'sem_timedwait', 'select', 'poll', 'os_read', 'nanosleep',
        'lock_PyThread_acquire_lock', 'take_gil')
# What a sample's stack is doing, the first that matches (outermost to innermost frames).
CATEGORIES = (
    ('take: to Python (rosidl convert_to_py)', ('convert_to_py',)),
    ('take: middleware (rcl_take, deserialise)', ('rcl_take',)),
    ('callback (the node: stats, bridge, worker, step)', (
        'usbcam_subscriber.py', 'vision_step.py', 'transport.py', 'cv_bridge.py',
        'latest_frame.py', 'bare_image_subscriber.py', 'circle.py', 'display.py')),
    ('receive thread loop (wait set)', ('receive_thread.py',)),
    ('executor (wait set, tasks, handlers)', ('executors.py', 'task.py')),
)


def thread_ticks(pid):
    """Return {tid: (comm, utime, stime)} of a process' threads."""
    out = {}
    for tid in os.listdir('/proc/%d/task' % pid):
        try:
            with open('/proc/%d/task/%s/stat' % (pid, tid)) as stream:
                text = stream.read()
        except OSError:
            continue
        comm = text[text.index('(') + 1:text.rindex(')')]
        fields = text.rsplit(')', 1)[1].split()
        out[int(tid)] = (comm, int(fields[11]), int(fields[12]))
    return out


def python_threads(py_spy, pid):
    """Return {tid: thread name} of the Python threads, from py-spy dump."""
    done = subprocess.run([py_spy, 'dump', '--pid', str(pid)], capture_output=True, text=True,
                          timeout=60)
    return {int(tid): name for tid, name in re.findall(
        r'^Thread (?:0x)?(\d+) \([^)]*\): "([^"]*)"', done.stdout, re.M)}


def classify(stack):
    """Return a sample's category, or None when its thread waits."""
    frames = stack.split(';')
    leaf = ';'.join(frames[-3:])
    if any(name in leaf for name in IDLE):
        return None
    for category, marks in CATEGORIES:
        if any(mark in frame for frame in frames for mark in marks):
            return category
    return 'other'


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split('\n\n')[0])
    parser.add_argument('receiver', choices=RECEIVERS)
    parser.add_argument('--size', type=parse_sizes, default=parse_sizes('640x480'))
    parser.add_argument('--seconds', type=float, default=20.0)
    parser.add_argument('--py-spy', default=shutil.which('py-spy'),
                        help='py-spy executable (pip install py-spy)')
    args = parser.parse_args(argv)
    if not args.py_spy:
        parser.error('py-spy not found: pip install py-spy, or give --py-spy PATH')
    size = args.size[0]
    env = local_node_env()
    env['PYTHONPATH'] = str(BENCH) + os.pathsep + env.get('PYTHONPATH', '')
    domain = ros_harness.DomainId()
    env['ROS_DOMAIN_ID'] = str(domain.value)
    workdir = tempfile.mkdtemp(prefix='pyv_profile_')
    publisher = start_helper('publisher', [
        sys.executable, str(BENCH / 'bare_image_publisher.py'), '{out}', str(size[0]),
        str(size[1]), repr(FPS), 'reliable', '--py-vision-profile'], env, workdir)
    receiver = start_helper('receiver', receiver_command(args.receiver, size, sys.executable),
                            env, workdir)
    samples = os.path.join(workdir, 'samples.txt')
    keep = os.environ.get('PROFILE_SAMPLES')  # where to leave the raw samples, if anywhere
    try:
        if args.receiver == 'bare':
            receiver.wait_for_output(FIRST_FRAME_MARK, 60)
        else:
            receiver.wait_for_output(r'received|frames in|running step|drawing on', 60)
        time.sleep(5.0)
        names = python_threads(args.py_spy, receiver.pid)
        # The threads' CPU first, then the samples: py-spy's own work is not counted.
        before = thread_ticks(receiver.pid)
        time.sleep(args.seconds)
        after = thread_ticks(receiver.pid)
        subprocess.run([args.py_spy, 'record', '--native', '--idle', '--rate', '1000',
                        '--duration', str(int(args.seconds)), '--format', 'raw', '--output',
                        samples, '--pid', str(receiver.pid)], capture_output=True,
                       timeout=args.seconds + 60)
        seconds = args.seconds
    finally:
        receiver.end(timeout=15.0)
        publisher.end(timeout=15.0)
        domain.release()
    frames = FPS * seconds
    groups = collections.defaultdict(lambda: [0, 0])
    for tid, (comm, user, system) in after.items():
        if tid not in before:
            continue
        if tid == receiver.pid:
            group = 'main thread (executor)'
        elif tid in names:
            group = 'Python thread %r' % names[tid]
        else:
            group = 'other threads (Fast DDS)'
        groups[group][0] += user - before[tid][1]
        groups[group][1] += system - before[tid][2]
    print('%s, %dx%d at %g fps, %g s' % (args.receiver, size[0], size[1], FPS, seconds))
    print('\n| thread | user ms a frame | kernel ms a frame |\n|---|---:|---:|')
    total = [0, 0]
    for group, (user, system) in sorted(groups.items()):
        total[0] += user
        total[1] += system
        print('| %s | %.3f | %.3f |' % (
            group, 1e3 * user / CLK_TCK / frames, 1e3 * system / CLK_TCK / frames))
    print('| all | %.3f | %.3f |' % (
        1e3 * total[0] / CLK_TCK / frames, 1e3 * total[1] / CLK_TCK / frames))
    counts = collections.Counter()
    with open(samples) as stream:
        for line in stream:
            stack, _, count = line.rstrip('\n').rpartition(' ')
            category = classify(stack)
            if category is not None and count.isdigit():
                counts[category] += int(count)
    busy = sum(counts.values())
    print('\nPython threads, samples while not waiting (%d):\n' % busy)
    print('| what | share |\n|---|---:|')
    for category, count in counts.most_common():
        print('| %s | %.0f%% |' % (category, 100.0 * count / max(1, busy)))
    if keep:
        shutil.copy(samples, keep)
    shutil.rmtree(workdir, ignore_errors=True)
    return 0


if __name__ == '__main__':
    sys.exit(main())
