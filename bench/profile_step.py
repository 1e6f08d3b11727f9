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
Where vision_step's CPU a frame goes with hand_signs: its threads, and its worker's stages.

  .venv/bin/python bench/profile_step.py ['no hand'|hand|circle] [--size 640x480]
      [--seconds 30] [--hand-photo PATH]
  (. scripts/board_env.sh && python bench/profile_step.py hand)    # the board versions

bench_step_cpu.py's node, camera and cases (usbcam_publisher at 10 fps on the synthetic
picture or the looping clip of a hand, vision_step with `threads` 1, nobody watching its
image). Over one window, each thread's CPU a frame from /proc/PID/task (the worker that runs
the step, the thread that receives the frames, the executor, the rest: Fast DDS' and the
command gate's); over the next, py-spy's samples of the worker (`py-spy record`, on-CPU
samples only, the process paused for each: a stack read while it runs may be torn) say which
stage its CPU went to: the models' invokes, making their inputs (the
palm detector's letterboxed frame, the landmark model's rotated crop), decoding, the landmarks
and the next region, the sign, publishing the sign and the command through the gate, the
bridge and the node's own bookkeeping. A stage's milliseconds are its share of the samples
times the worker's CPU a frame. py-spy is not a dependency of the project (pip install
py-spy); without it only the threads are shown. Frames are counted at the camera's rate (the
node's statistics line, printed at the end, says whether it skipped any).
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

from bench_common import CLK_TCK, local_node_env, print_shares
from bench_hand_signs import hand_photo_path, make_clip
from bench_step_cpu import camera_process, START_S
from profile_receive import thread_ticks
import ros_harness

FPS = 10.0
SETTLE_S = 3.0
# The worker's stages, by the first of these found in a sample's stack (innermost first).
STAGES = (
    ('model invoke', r'Interpreter\.invoke|\.Invoke'),
    ('model run: input check, set and get tensors, timing', r'RuntimeModel\.run|_invoke'),
    ('palm input: letterbox (resize, RGB float tensor)', r'letterbox'),
    ('landmark input: rotated crop (warp, RGB float tensor)', r'rotated_crop'),
    ('palm decode, NMS, boxes to the frame', r'SsdDetector\.detections|PalmDetector'),
    ('landmarks to the frame, next region', r'HandTracker'),
    ('sign (classify)', r'models/signs\.py'),
    ('drawing', r'hand_signs\.py:\d+\);draw'),
    ('publishing the sign and the command (gate)',
     r'HandSigns\.process.*(publish|CommandGate|_send)'),
    ('the rest of the step', r'HandSigns\.process|circle\.py'),
    ('bridge (message to image)', r'cv_bridge'),
    ('the node: statistics, checks, the worker loop', r'vision_step|latest_frame'),
)
WORKER = 'processing'


def py_spy():
    """Return py-spy's path: beside this Python, or on PATH; None where there is none."""
    beside = os.path.join(os.path.dirname(sys.executable), 'py-spy')
    return beside if os.access(beside, os.X_OK) else shutil.which('py-spy')


def thread_names(pid):
    """Return {tid: Python thread name} from py-spy dump ({} without py-spy)."""
    spy = py_spy()
    if spy is None:
        return {}
    dump = subprocess.run([spy, 'dump', '-p', str(pid)], capture_output=True, text=True,
                          timeout=60).stdout
    return {int(tid, 0): name for tid, name in re.findall(
        r'Thread (0x[0-9A-Fa-f]+|\d+) \(\w+\): "([^"]+)"', dump)}


def stage_shares(pid, seconds):
    """Return {stage: share of the worker's on-CPU samples} from py-spy, or None."""
    spy = py_spy()
    if spy is None:
        return None
    with tempfile.TemporaryDirectory() as folder:
        out = os.path.join(folder, 'samples.txt')
        subprocess.run([spy, 'record', '-p', str(pid), '-d', str(int(seconds)), '-r', '200',
                        '--format', 'raw', '--threads', '-o', out],
                       capture_output=True, timeout=seconds + 60)
        with open(out) as stream:
            lines = stream.read().splitlines()
    counts = collections.Counter()
    for line in lines:
        stack, _, count = line.rpartition(' ')
        if ': %s;' % WORKER not in stack or not count.isdigit():
            continue
        if re.search(r'Condition\.wait|_run \(py_vision/latest_frame\.py:\d+\)$', stack):
            continue  # waiting for the next frame
        stage = next((name for name, pattern in STAGES if re.search(pattern, stack)), 'other')
        counts[stage] += int(count)
    total = sum(counts.values())
    return {stage: count / total for stage, count in counts.items()} if total else None


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split('\n\n')[0])
    parser.add_argument('case', nargs='?', default='hand', choices=('no hand', 'hand', 'circle'))
    parser.add_argument('--size', default='640x480')
    parser.add_argument('--seconds', type=float, default=30.0)
    parser.add_argument('--hand-photo', default='')
    args = parser.parse_args(argv)
    size = tuple(int(value) for value in args.size.split('x'))
    env = local_node_env()
    domain = ros_harness.DomainId()
    env['ROS_DOMAIN_ID'] = str(domain.value)
    workdir = tempfile.mkdtemp(prefix='pyv_profile_step_')
    device = (make_clip(hand_photo_path(args.hand_photo), workdir, size)
              if args.case == 'hand' else 'synthetic')
    processes = []
    try:
        processes.append(camera_process(size, FPS, device, env))
        node = ros_harness.NodeProcess('vision_step', ros_harness.ros_args({
            'step': 'circle' if args.case == 'circle' else 'hand_signs', 'threads': 1}),
            env, name='step')
        processes.append(node)
        node.wait_for_output('first image', START_S)
        time.sleep(SETTLE_S)
        names = thread_names(node.pid)
        # The threads' CPU first, then py-spy's samples: its own work is not counted.
        before = thread_ticks(node.pid)
        time.sleep(args.seconds)
        after = thread_ticks(node.pid)
        shares = stage_shares(node.pid, args.seconds)
        stats = [line for line in node.output().splitlines() if 'processed' in line]
    finally:
        for proc in reversed(processes):
            proc.stop(timeout=15.0)
        for proc in processes:
            proc.kill()
        domain.release()
        shutil.rmtree(workdir, ignore_errors=True)
    frames = FPS * args.seconds
    groups = collections.Counter()
    for tid, (comm, user, system) in after.items():
        if tid in before:
            name = names.get(tid) or ('the executor' if tid == node.pid else 'native')
            groups[name] += user + system - before[tid][1] - before[tid][2]
    last = stats[-1].split(']: ')[-1] if stats else ''
    print('%s, %dx%d at %g fps, %g s; %s' % (
        args.case, size[0], size[1], FPS, args.seconds, last))
    print('\n| thread | CPU ms a frame |\n|---|---:|')
    for name, ticks in groups.most_common():
        print('| %s | %.2f |' % (name, 1e3 * ticks / CLK_TCK / frames))
    print('| all | %.2f |' % (1e3 * sum(groups.values()) / CLK_TCK / frames))
    if shares is None:
        print('\n(no py-spy here: pip install py-spy for the worker by stage)')
        return 0
    worker_ms = 1e3 * groups.get(WORKER, 0) / CLK_TCK / frames
    print_shares('worker by stage', shares, worker_ms)
    return 0


if __name__ == '__main__':
    sys.exit(main())
