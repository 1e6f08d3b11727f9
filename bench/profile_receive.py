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
Where a received frame's CPU goes, in one receiver of bench_receive.py: threads and code.

  .venv/bin/python bench/profile_receive.py RECEIVER [--size 640x480] [--seconds 20]

RECEIVER is one of bench_receive.py's (bare, usbcam_subscriber, 'vision_step nothing', ...),
fed by the same bare publisher at 30 fps. Over one window, each thread's CPU a frame, user and
kernel, from /proc/PID/task (the main thread, Python's others by `threading` name where the
process says, Fast DDS' together); over the next, `perf record` (on-CPU samples, user space)
says which code the user time went to: copies (libc's memmove, memset), the allocator, the
Python interpreter (the executor's and the node's Python), rclpy and rcl, the message type's
generated code (rosidl), Fast DDS. perf is not a dependency of the project (Debian:
linux-perf); without it only the threads are shown. The kernel's time is mostly page faults
(bench_receive.py counts them). Frames are counted at the publisher's rate (bench_receive.py
shows every receiver gets them all).
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

from bench_common import (BENCH, CLK_TCK, FIRST_FRAME_MARK, local_node_env, print_shares,
                          start_helper)
from bench_receive import parse_sizes, receiver_command, RECEIVERS
import ros_harness

FPS = 30.0
# Where user-space samples are, by the library (and, in libc, the function) they fall in.
CODE = (
    ('copies (memmove, memcpy, memset)', lambda dso, sym: 'libc' in dso and (
        'memmove' in sym or 'memcpy' in sym or 'memset' in sym)),
    ('allocator, locks (the rest of libc)', lambda dso, sym: 'libc' in dso),
    ('Python interpreter (executor, callbacks)', lambda dso, sym: 'python' in dso),
    ('rclpy, rcl, rmw', lambda dso, sym: any(
        name in dso for name in ('rclpy', 'librcl', 'librmw', 'librcutils', 'librcpputils'))),
    ('message code (rosidl)', lambda dso, sym: 'rosidl' in dso),
    ('Fast DDS', lambda dso, sym: 'fastrtps' in dso or 'fastcdr' in dso or 'fastdds' in dso),
    ('numpy, OpenCV', lambda dso, sym: 'numpy' in dso or 'multiarray' in dso or 'cv2' in dso),
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


def code_shares(pid, seconds):
    """Return {what: share of user-space samples} from perf over seconds, or None."""
    perf = shutil.which('perf')
    if perf is None:
        return None
    with tempfile.TemporaryDirectory() as folder:
        data = os.path.join(folder, 'perf.data')
        subprocess.run([perf, 'record', '-e', 'cpu-clock', '-F', '999', '-o', data, '-p',
                        str(pid), '--', 'sleep', str(seconds)], capture_output=True,
                       timeout=seconds + 60)
        report = subprocess.run([perf, 'report', '-i', data, '--no-children', '--sort',
                                 'dso,sym', '--stdio', '-g', 'none'], capture_output=True,
                                text=True, timeout=120).stdout
    shares = collections.Counter()
    for line in report.splitlines():
        found = re.match(r'\s*([\d.]+)%\s+(\S+)\s+\[(.)\]\s+(.*)', line)
        if not found or found.group(3) == 'k':
            continue
        share, dso, symbol = float(found.group(1)), found.group(2), found.group(4)
        what = next((name for name, test in CODE if test(dso, symbol)), 'other')
        shares[what] += share
    total = sum(shares.values())
    return {what: share / total for what, share in shares.items()} if total else None


def thread_group(pid, tid, comm):
    if tid == pid:
        return 'main thread (the executor)'
    if comm.startswith('dds.'):
        return "Fast DDS' threads"
    return "the others (receive, worker; Fast DDS' on 2.6, whose threads have no names)"


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split('\n\n')[0])
    parser.add_argument('receiver', choices=RECEIVERS)
    parser.add_argument('--size', type=parse_sizes, default=parse_sizes('640x480'))
    parser.add_argument('--seconds', type=float, default=20.0)
    args = parser.parse_args(argv)
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
    try:
        if args.receiver == 'bare':
            receiver.wait_for_output(FIRST_FRAME_MARK, 60)
        else:
            receiver.wait_for_output(r'received|frames in|running step|drawing on', 60)
        time.sleep(5.0)
        # The threads' CPU first, then perf's samples: perf's own work is not counted.
        before = thread_ticks(receiver.pid)
        time.sleep(args.seconds)
        after = thread_ticks(receiver.pid)
        shares = code_shares(receiver.pid, args.seconds)
    finally:
        receiver.end(timeout=15.0)
        publisher.end(timeout=15.0)
        domain.release()
        shutil.rmtree(workdir, ignore_errors=True)
    frames = FPS * args.seconds
    groups = collections.defaultdict(lambda: [0, 0])
    for tid, (comm, user, system) in after.items():
        if tid in before:
            group = groups[thread_group(receiver.pid, tid, comm)]
            group[0] += user - before[tid][1]
            group[1] += system - before[tid][2]
    print('%s, %dx%d at %g fps, %g s' % (args.receiver, size[0], size[1], FPS, args.seconds))
    print('\n| thread | user ms a frame | kernel ms a frame |\n|---|---:|---:|')
    user = system = 0
    for name, (group_user, group_system) in sorted(groups.items()):
        user += group_user
        system += group_system
        print('| %s | %.3f | %.3f |' % (
            name, 1e3 * group_user / CLK_TCK / frames, 1e3 * group_system / CLK_TCK / frames))
    user_ms = 1e3 * user / CLK_TCK / frames
    print('| all | %.3f | %.3f |' % (user_ms, 1e3 * system / CLK_TCK / frames))
    if shares is None:
        print('\n(no perf here: apt-get install linux-perf for the user time by code)')
        return 0
    print_shares('user time by code', shares, user_ms, digits=3)
    return 0


if __name__ == '__main__':
    sys.exit(main())
