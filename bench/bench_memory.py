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
Resident memory of py_vision's three nodes against bare rclpy nodes doing the same work.

  .venv/bin/python bench/bench_memory.py [--quick] [--repeat N] [--fps F]

Per image size (640x480 and 1920x1080; --quick: 640x480 only) two pipelines run one after
the other, each three processes on one ROS domain of their own:
  py_vision  usbcam_publisher (synthetic camera) -> cv_bridge_test -> usbcam_subscriber
             (display:=none), the installed executables with the packaged Fast DDS profile
  bare       bare_image_publisher.py -> bare_image_processor.py -> bare_image_subscriber.py,
             plain rclpy with Fast DDS' defaults, importing the same numpy, OpenCV and
             py_vision.capture.synthetic_picture, passing frames of the same size at the same rate
Once frames reach the last node, after a settling time, each process' VmRSS (and its anonymous,
file and shared-memory parts) and PSS are sampled for a window; the peak of each counts. RSS
counts shared pages (libraries, Fast DDS' shared-memory segments) in every process that
touches them; PSS divides them among the processes, so the PSS total is what the pipeline
really takes from the board's RAM. Prints a Markdown table, writes bench/results/memory.json.
"""

import argparse
from pathlib import Path
import re
import shutil
import statistics
import sys
import tempfile
import time

from bench_common import BENCH, FIRST_FRAME_MARK, read_results, save_results, start_helper
import ros_harness
from ros_harness import DomainId, EXECUTABLES
SIZES = ((640, 480), (1920, 1080))
CAMERA_DEFAULT_SIZE = (640, 480)  # usbcam_publisher's image_width, image_height
ROLES = ('publisher', 'processor', 'subscriber')
STATUS_FIELDS = ('VmRSS', 'RssAnon', 'RssFile', 'RssShmem')
PYV_RECEIVED = re.compile(r'received (\d+) frames')


def commands(kind, width, height, fps):
    """Return the three (role, command) of a pipeline; '{out}' is a results file."""
    python = sys.executable
    if kind == 'bare':
        return [
            ('publisher', [python, str(BENCH / 'bare_image_publisher.py'), '{out}',
                           str(width), str(height), repr(fps), 'reliable']),
            ('processor', [python, str(BENCH / 'bare_image_processor.py')]),
            ('subscriber', [python, str(BENCH / 'bare_image_subscriber.py'), '{out}',
                            'reliable', '--ros-args', '-r', 'usb_camera/image:=cv_bridge_image']),
        ]
    return [
        ('publisher', [str(EXECUTABLES / 'usbcam_publisher'), '--ros-args',
                       '-p', 'video_device:=synthetic', '-p', 'image_width:=%d' % width,
                       '-p', 'image_height:=%d' % height, '-p', 'framerate:=%r' % fps]),
        # As `ros2 run py_vision cv_bridge_test` starts it: told the camera's size only where
        # it is not the camera's default (as pipeline.launch.py tells it, through params.yaml).
        ('processor', [str(EXECUTABLES / 'cv_bridge_test'), '--ros-args'] + (
            [] if (width, height) == CAMERA_DEFAULT_SIZE else
            ['-p', 'image_width:=%d' % width, '-p', 'image_height:=%d' % height])),
        ('subscriber', [str(EXECUTABLES / 'usbcam_subscriber'), '--ros-args',
                        '-p', 'display:=none', '-p', 'stats_period:=1.0',
                        '-r', 'usb_camera/image:=cv_bridge_image']),
    ]


def memory_kib(pid):
    """Return VmRSS, RssAnon, RssFile, RssShmem and Pss of a process in KiB, or None."""
    try:
        status = Path('/proc/%d/status' % pid).read_text()
        rollup = Path('/proc/%d/smaps_rollup' % pid).read_text()
    except OSError:
        return None
    values = {}
    for field in STATUS_FIELDS:
        found = re.search(r'^%s:\s+(\d+) kB' % field, status, re.M)
        values[field] = int(found.group(1)) if found else 0
    found = re.search(r'^Pss:\s+(\d+) kB', rollup, re.M)
    values['Pss'] = int(found.group(1)) if found else 0
    return values


def frames_received(kind, subscriber):
    """Return how many frames the last node has received so far (None: not known yet)."""
    if kind == 'bare':
        return None
    counts = PYV_RECEIVED.findall(subscriber.output())
    return int(counts[-1]) if counts else 0


def run_pipeline(kind, env, width, height, fps, settle, window, log=print):
    """Start a pipeline, measure its memory once frames flow; return per-role peaks."""
    workdir = Path(tempfile.mkdtemp(prefix='pyv_mem_'))
    procs = []
    result = {'kind': kind, 'width': width, 'height': height, 'fps': fps}
    try:
        # The last node first, so that it is there when the first frames arrive.
        for role, cmd in reversed(commands(kind, width, height, fps)):
            procs.insert(0, (role, start_helper('%s_%s' % (kind, role), cmd, env, workdir)))
        subscriber = procs[-1][1]

        def flowing():
            if any(proc.proc.poll() is not None for _, proc in procs):
                return 'ended'
            out = subscriber.output()
            return FIRST_FRAME_MARK in out or bool(frames_received(kind, subscriber))
        try:
            state = ros_harness.wait_until(flowing, 60, 0.2, 'frames')
        except AssertionError:
            state = None
        if state is not True:
            result['error'] = ('a process ended early' if state == 'ended'
                               else 'no frame reached the last node within 60 s')
            return result
        time.sleep(settle)
        peaks = {role: {} for role, _ in procs}
        first = frames_received(kind, subscriber)
        start = time.monotonic()
        while time.monotonic() - start < window:
            for role, proc in procs:
                sample = memory_kib(proc.pid)
                if sample is None:
                    result['error'] = '%s ended during the measurement' % role
                    return result
                for field, value in sample.items():
                    peaks[role][field] = max(peaks[role].get(field, 0), value)
            time.sleep(0.25)
        last = frames_received(kind, subscriber)
        result['nodes'] = peaks
        if first is not None:
            result['delivered_fps'] = round((last - first) / window, 1)
    finally:
        for role, proc in procs:
            proc.end(timeout=15.0)
        if 'error' in result:
            for role, proc in procs:
                log('--- %s %s:\n%s' % (kind, role, proc.output()[-1500:]))
        bare_sub = dict(procs).get('subscriber') if kind == 'bare' else None
        if bare_sub is not None and read_results(bare_sub) and 'nodes' in result:
            events = read_results(bare_sub)['received']
            span = events[-1][0] - events[0][0] if len(events) > 1 else 0
            result['delivered_fps'] = round((len(events) - 1) / span, 1) if span else 0.0
        shutil.rmtree(workdir, ignore_errors=True)
    return result


def combine(runs):
    """Median over repeats of each role's peak values; None when every run failed."""
    ok = [r for r in runs if 'nodes' in r]
    if not ok:
        return None
    return {role: {field: statistics.median([r['nodes'][role][field] for r in ok])
                   for field in ok[0]['nodes'][role]} for role in ROLES}


def mib(kib):
    return kib / 1024.0


def table(rows):
    lines = ['| size | node | bare RSS MiB | py_vision RSS MiB | difference MiB | ratio | '
             'py_vision shm MiB | bare PSS MiB | py_vision PSS MiB |',
             '|---|---|---:|---:|---:|---:|---:|---:|---:|']
    for row in rows:
        lines.append('| %dx%d | %s | %.1f | %.1f | %+.1f | %.3f | %.1f | %.1f | %.1f |' % (
            row['width'], row['height'], row['node'], row['bare_rss_mib'],
            row['pyv_rss_mib'], row['pyv_rss_mib'] - row['bare_rss_mib'], row['rss_ratio'],
            row['pyv_shmem_mib'], row['bare_pss_mib'], row['pyv_pss_mib']))
    return '\n'.join(lines)


def summarise(width, height, bare, pyv):
    """Return the table rows of one size: one per node and the pipeline's total."""
    rows = []
    for role in ROLES + ('total',):
        if role == 'total':
            pick = {kind: {field: sum(nodes[r][field] for r in ROLES)
                           for field in ('VmRSS', 'RssShmem', 'Pss')}
                    for kind, nodes in (('bare', bare), ('pyv', pyv))}
            name = 'three nodes'
        else:
            pick = {'bare': bare[role], 'pyv': pyv[role]}
            name = {'publisher': 'usbcam_publisher', 'processor': 'cv_bridge_test',
                    'subscriber': 'usbcam_subscriber'}[role]
        rows.append({
            'width': width, 'height': height, 'node': name,
            'bare_rss_mib': round(mib(pick['bare']['VmRSS']), 1),
            'pyv_rss_mib': round(mib(pick['pyv']['VmRSS']), 1),
            'rss_ratio': round(pick['pyv']['VmRSS'] / pick['bare']['VmRSS'], 3),
            'pyv_shmem_mib': round(mib(pick['pyv']['RssShmem']), 1),
            'bare_pss_mib': round(mib(pick['bare']['Pss']), 1),
            'pyv_pss_mib': round(mib(pick['pyv']['Pss']), 1),
            'pss_ratio': round(pick['pyv']['Pss'] / pick['bare']['Pss'], 3),
        })
    return rows


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split('\n\n')[0])
    parser.add_argument('--quick', action='store_true', help='640x480 only')
    parser.add_argument('--repeat', type=int, default=1,
                        help='runs per pipeline and size, alternating; medians (1)')
    parser.add_argument('--fps', type=float, default=15.0, help='frame rate (15)')
    parser.add_argument('--settle', type=float, default=3.0,
                        help='seconds of frames before sampling (3)')
    parser.add_argument('--window', type=float, default=6.0, help='sampling window, s (6)')
    args = parser.parse_args(argv)
    base = ros_harness.plain_env()
    domain = DomainId()
    base.update(ROS_DOMAIN_ID=str(domain.value), ROS_AUTOMATIC_DISCOVERY_RANGE='LOCALHOST',
                PYTHONPATH=str(BENCH) + ':' + base.get('PYTHONPATH', ''))
    rows, runs = [], []
    try:
        for width, height in SIZES[:1] if args.quick else SIZES:
            by_kind = {'bare': [], 'pyv': []}
            for _ in range(max(1, args.repeat)):
                for kind in ('bare', 'pyv'):
                    run = run_pipeline(kind, base, width, height, args.fps, args.settle,
                                       args.window)
                    runs.append(run)
                    by_kind[kind].append(run)
                    print('%-4s %dx%d: %s' % (kind, width, height, run.get('error') or ', '.join(
                        '%s %.1f MiB' % (role, mib(run['nodes'][role]['VmRSS']))
                        for role in ROLES)), flush=True)
            bare, pyv = combine(by_kind['bare']), combine(by_kind['pyv'])
            if bare and pyv:
                rows.extend(summarise(width, height, bare, pyv))
    finally:
        domain.release()
    print()
    print(table(rows))
    save_results('memory', {'fps': args.fps, 'repeat': args.repeat, 'rows': rows,
                            'runs': runs})
    return 0 if rows else 1


if __name__ == '__main__':
    sys.exit(main())
