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
Measure the hand_signs pipeline's CPU per frame, node by node: camera, step, viewer.

  .venv/bin/python bench/bench_hand_signs.py [--sizes 640x480,320x240] [--rates 10,15,30]
      [--window S] [--rounds N] [--threads 1,2] [--cases ...] [--hand-photo PATH]

The three nodes of hand_signs.launch.py, each the installed executable in its own process on a
ROS domain of its own: usbcam_publisher, vision_step with step:=hand_signs, and
usbcam_subscriber on vision_step/image with display:=web, one HTTP client (a thread of this
process) reading its MJPEG /stream as a browser does. Two cases:

- no hand: the synthetic camera; the step runs the palm detector on every frame;
- hand: a video file made here from the photograph of a hand (PY_VISION_HAND_PHOTO, else
  Debian's opencv-doc's handSrc.jpg; --hand-photo), the hand drifting a few pixels from frame
  to frame, looping, as video_device: the step follows the hand, the landmark model alone on
  each frame.

Two references, in the same rounds: `bare`, a bare rclpy publisher of prebuilt bgr8 frames of
the same size at the same rate (bench/bare_image_publisher.py) and a bare rclpy subscriber
(bench/bare_image_subscriber.py): what moving a frame from one process to another costs each
side; `circle`, the same three nodes with vision_step's trivial circle step: the pipeline
without the models. Each node's CPU is its utime + stime (/proc) over the window, divided by
the frames it handled in that window: the camera the frames it published (its CameraInfo, one
per frame, counted by a subscriber of this process), the step the frames it processed (its
hand_sign, one per processed frame; the circle step's: the frames the viewer got), the viewer
the frames it received (its /stats, `viewer_frames`); the bare nodes' from their own records.
Medians over --rounds rounds, the cases interleaved.
The step's /diagnostics says how much of its CPU went into its models ('models CPU ms'): a
processed frame's CPU is split into the models' and the rest. Prints a Markdown table with the
machine's load average, and an estimate for a Cortex-A53 with a factor for each kind of work
(docs/benchmarks.md: the models' convolutions 16 to 20 times this machine's time, everything
else, Python, copies and OpenCV, 10 to 15), and writes
bench/results/hand_signs-py<version>.json (the boards' Python 3.10 in the board-version
environment: `. scripts/board_env.sh && python bench/bench_hand_signs.py`).
"""

import argparse
import http.client
import json
import os
from pathlib import Path
import re
import signal
import statistics
import sys
import tempfile
import threading
import time
import urllib.request

from bench_common import (BENCH, CLK_TCK, cpu_ticks, FIRST_FRAME_MARK, fresh_report,
                          local_node_env, machine_ticks, read_results, save_results,
                          start_helper)
import ros_harness

SIZES = '640x480,320x240'
SETTLE_S = 3.0
START_S = 90.0
PROFILE = ros_harness.SHARE / 'config' / 'fastdds_image_profile.xml'
CASES = ('bare', 'circle', 'no hand', 'hand')
HAND_PHOTO_INSTALLED = '/usr/share/doc/opencv-doc/opencv4/html/handSrc.jpg'
# The clip: the photograph moved along a closed path (so that the loop has no jump), 2 s long.
CLIP_FRAMES, CLIP_FPS, DRIFT_PX = 60, 30.0, (16.0, 8.0)
# Cortex-A53 time over this machine's, low and high (docs/benchmarks.md, On a Cortex-A53): the
# models' float convolutions; the rest of the work (Python, frame copies, OpenCV).
A53_MODELS = (16.0, 20.0)
A53_OTHER = (10.0, 15.0)
STATS_LINE = re.compile(r'frames in \d+, processed \d+.*processing p50 ([\d.]+) ms')
VIEWER_URL = re.compile(r'browser viewer at (http://127\.0\.0\.1:\d+/)')


def hand_photo_path(given):
    """Return the photograph of a hand to make the clip of, or exit saying where to get one."""
    path = given or os.environ.get('PY_VISION_HAND_PHOTO') or HAND_PHOTO_INSTALLED
    if not os.path.isfile(path):
        raise SystemExit(
            'no photograph of a hand at %s: give one with --hand-photo or PY_VISION_HAND_PHOTO '
            "(scripts/test.sh takes handSrc.jpg out of Debian's opencv-doc package; or "
            'apt-get install opencv-doc)' % path)
    return path


def make_clip(photo_path, folder, size):
    """Write the looping clip of the hand (MJPEG .avi, which every OpenCV reads); return it."""
    import cv2
    import numpy as np
    photo = cv2.imread(photo_path, cv2.IMREAD_COLOR)
    if photo is None:
        raise SystemExit('cannot read %s as a picture' % photo_path)
    photo = cv2.resize(photo, size, interpolation=cv2.INTER_AREA)
    path = str(Path(folder) / ('hand_%dx%d.avi' % size))
    writer = cv2.VideoWriter(path, cv2.VideoWriter_fourcc(*'MJPG'), CLIP_FPS, size)
    scale = size[0] / 640.0
    for index in range(CLIP_FRAMES):
        turn = 2 * np.pi * index / CLIP_FRAMES
        shift = np.float32([[1, 0, scale * DRIFT_PX[0] * np.sin(turn)],
                            [0, 1, scale * DRIFT_PX[1] * np.sin(2 * turn)]])
        writer.write(cv2.warpAffine(photo, shift, size, borderMode=cv2.BORDER_REPLICATE))
    writer.release()
    return path


class Arrivals:
    """The arrival times (and data) of a topic's messages, from a ROS peer's thread."""

    def __init__(self, peer, msg_type, topic):
        from rclpy.qos import QoSProfile, ReliabilityPolicy
        self.records = []
        self._lock = threading.Lock()
        peer.node.create_subscription(
            msg_type, topic, self._received,
            QoSProfile(depth=100, reliability=ReliabilityPolicy.RELIABLE))

    def _received(self, msg):
        with self._lock:
            self.records.append((time.monotonic(), getattr(msg, 'data', None)))

    def between(self, start, end):
        with self._lock:
            return [data for when, data in self.records if start <= when < end]


class StreamClient:
    """Reads a viewer's MJPEG /stream on a thread of its own, as a browser does; counts parts."""

    PART = b'Content-Type: image/jpeg'

    def __init__(self, url):
        address = url.split('//', 1)[1].rstrip('/')
        host, port = address.rsplit(':', 1)
        self.parts = 0
        self._connection = http.client.HTTPConnection(host, int(port), timeout=10)
        self._connection.request('GET', '/stream')
        self._answer = self._connection.getresponse()
        if self._answer.status != 200:
            raise SystemExit('the viewer answered /stream with %d' % self._answer.status)
        self._thread = threading.Thread(target=self._read, daemon=True)
        self._thread.start()

    def _read(self):
        tail = b''
        try:
            while True:
                chunk = self._answer.read1(65536)
                if not chunk:
                    return
                data = tail + chunk
                self.parts += data.count(self.PART)
                tail = data[-len(self.PART) + 1:]
        except (OSError, ValueError, http.client.HTTPException):
            return  # the viewer stopped

    def close(self):
        self._connection.close()
        self._thread.join(5.0)


def viewer_frames(url):
    """Return the viewer's count of frames received (its /stats' viewer_frames)."""
    with urllib.request.urlopen(url + 'stats', timeout=10) as answer:
        return json.loads(answer.read())['viewer_frames']


def stop_all(processes):
    """Ctrl-C every process; return {name: exit status}; kill what does not end."""
    statuses = {}
    for proc in processes:
        statuses[proc.name] = proc.stop(signal.SIGINT, 20.0)
    return statuses


def ticks_of(processes):
    return {proc.name: cpu_ticks(proc.pid) for proc in processes}


class Window:
    """The CPU ticks of some processes and of the machine between two instants."""

    def __init__(self, processes, duration):
        self.start = time.monotonic()
        before, machine = ticks_of(processes), machine_ticks()
        time.sleep(duration)
        self.end = time.monotonic()
        after, machine_after = ticks_of(processes), machine_ticks()
        self.seconds = self.end - self.start
        self.ticks = {name: after[name] - before[name] for name in before}
        self.machine_busy = ((machine_after[0] - machine[0])
                             / max(1, machine_after[1] - machine[1]))


def node_figures(ticks, frames, seconds):
    """Return a node's figures: frames handled, CPU per frame and per second."""
    cpu_s = ticks / CLK_TCK
    return {'frames': frames, 'fps': round(frames / seconds, 2),
            'cpu_percent': round(100.0 * cpu_s / seconds, 2),
            'cpu_ms_per_frame': round(1000.0 * cpu_s / frames, 3) if frames else None}


def measure_reference(size, fps, window, env, workdir):
    """Run the bare publisher and subscriber at size and fps; return their figures."""
    domain = ros_harness.DomainId()
    # The bare nodes on py_vision's profile (its shared memory holds three VGA frames), as the
    # nodes are: the same transport.
    env = dict(env, ROS_DOMAIN_ID=str(domain.value), FASTRTPS_DEFAULT_PROFILES_FILE=str(PROFILE))
    python = sys.executable
    subscriber = start_helper('bare_subscriber', [
        python, str(BENCH / 'bare_image_subscriber.py'), '{out}', 'reliable'], env, workdir)
    publisher = start_helper('bare_publisher', [
        python, str(BENCH / 'bare_image_publisher.py'), '{out}', str(size[0]), str(size[1]),
        str(fps), 'reliable'], env, workdir)
    processes = [publisher, subscriber]
    try:
        subscriber.wait_for_output(FIRST_FRAME_MARK, START_S)
        time.sleep(SETTLE_S)
        measured = Window(processes, window)
        statuses = stop_all(processes)
    finally:
        for proc in processes:
            proc.kill()
        domain.release()
    if any(statuses.values()):
        raise SystemExit('the reference ended with %s' % statuses)
    published = read_results(publisher)['published']
    received = read_results(subscriber)['received']

    def within(records):
        return sum(1 for record in records if measured.start <= record[0] < measured.end)
    return measured, {
        'camera': node_figures(measured.ticks['bare_publisher'], within(published),
                               measured.seconds),
        'step': node_figures(measured.ticks['bare_subscriber'], within(received),
                             measured.seconds)}


def measure_pipeline(case, size, fps, window, threads, env, clip):
    """Run the three nodes of hand_signs.launch.py at size and fps; return their figures."""
    from diagnostic_msgs.msg import DiagnosticArray
    from rclpy.qos import QoSProfile, ReliabilityPolicy
    from sensor_msgs.msg import CameraInfo
    from std_msgs.msg import String
    domain = ros_harness.DomainId()
    env = dict(env, ROS_DOMAIN_ID=str(domain.value))
    device = clip if case == 'hand' else 'synthetic'
    peer = ros_harness.RosPeer(domain.value, name='bench_hand_signs')
    infos = Arrivals(peer, CameraInfo, 'usb_camera/camera_info')
    signs = Arrivals(peer, String, 'hand_sign')
    arrays = peer.collect(DiagnosticArray, '/diagnostics', QoSProfile(
        depth=100, reliability=ReliabilityPolicy.RELIABLE))
    processes, client = [], None
    try:
        processes.append(ros_harness.NodeProcess('usbcam_publisher', ros_harness.ros_args({
            'video_device': device, 'image_width': size[0], 'image_height': size[1],
            'framerate': float(fps)}), env, name='camera'))
        processes.append(ros_harness.NodeProcess('vision_step', ros_harness.ros_args({
            'step': 'circle' if case == 'circle' else 'hand_signs', 'threads': threads}),
            env, name='step'))
        viewer = ros_harness.NodeProcess('usbcam_subscriber', ros_harness.ros_args(
            {'display': 'web', 'web_port': 0}, {'usb_camera/image': 'vision_step/image'}),
            env, name='viewer')
        processes.append(viewer)
        url = viewer.wait_for_output(VIEWER_URL.pattern, START_S).group(1)
        client = StreamClient(url)
        ros_harness.wait_until(
            lambda: client.parts >= 3 and (signs.records or case == 'circle'), START_S, 0.05,
            'the first frames through the viewer')
        time.sleep(SETTLE_S)
        # The step's own count of its models' CPU, from a report at each end of the window.
        report_before = fresh_report(arrays)
        shown_before = viewer_frames(url)
        measured = Window(processes, window)
        shown = viewer_frames(url) - shown_before
        report_after = fresh_report(arrays)
        # The step's statistics line comes every 5 s: the last one covers the window's end.
        processes[1].wait_for_output(STATS_LINE.pattern, 10.0)
        processing = float(STATS_LINE.findall(processes[1].output())[-1])
        statuses = stop_all(processes)  # the viewer ends the client's stream
    finally:
        if client is not None:
            client.close()
        peer.close()
        for proc in processes:
            proc.kill()
        domain.release()
    if any(statuses.values()):
        raise SystemExit('a node ended with %s' % statuses)
    window_signs = signs.between(measured.start, measured.end)
    step = node_figures(measured.ticks['step'], shown if case == 'circle' else len(window_signs),
                        measured.seconds)
    step.update(processing_ms_p50=processing,
                signs={sign: window_signs.count(sign) for sign in sorted(set(window_signs))},
                models_cpu_ms_per_frame=models_per_frame(report_before, report_after))
    return measured, {
        'camera': node_figures(measured.ticks['camera'],
                               len(infos.between(measured.start, measured.end)),
                               measured.seconds),
        'step': step,
        'viewer': node_figures(measured.ticks['viewer'], shown, measured.seconds)}


def models_per_frame(before, after):
    """Return the models' CPU a processed frame between two reports of the step, or None."""
    try:
        frames = int(after['processed']) - int(before['processed'])
        models = float(after['models CPU ms']) - float(before['models CPU ms'])
    except (KeyError, ValueError):
        return None
    return round(models / frames, 3) if frames > 0 else None


def median_of(runs, key):
    values = [run[key] for run in runs if run.get(key) is not None]
    return round(statistics.median(values), 3) if values else None


def summarise(results):
    """Return one row per (size, rate, case, node): medians over the rounds."""
    rows, labels = [], []
    for result in results:
        if result['case'] not in labels:
            labels.append(result['case'])
    for size in sorted({r['size'] for r in results}, key=lambda s: -int(s.split('x')[0])):
        for fps in sorted({r['fps'] for r in results if r['size'] == size}):
            bare = {}
            for case in labels:
                runs = [r for r in results
                        if (r['size'], r['fps'], r['case']) == (size, fps, case)]
                for node in ('camera', 'step', 'viewer'):
                    figures = [r['nodes'][node] for r in runs if node in r['nodes']]
                    if not figures:
                        continue
                    row = {'size': size, 'fps': fps, 'case': case, 'node': node,
                           'rounds': len(figures), 'handled_fps': median_of(figures, 'fps'),
                           'cpu_ms_per_frame': median_of(figures, 'cpu_ms_per_frame'),
                           'cpu_percent': median_of(figures, 'cpu_percent')}
                    if node == 'step' and case != 'bare':
                        row['processing_ms_p50'] = median_of(figures, 'processing_ms_p50')
                        row['models_cpu_ms_per_frame'] = median_of(figures,
                                                                   'models_cpu_ms_per_frame')
                        row['signs'] = [f['signs'] for f in figures]
                    if case == 'bare':
                        bare[node] = row['cpu_ms_per_frame']
                    else:
                        # The camera against the bare publisher; step and viewer against the
                        # bare subscriber (each receives a frame, as they do).
                        base = bare.get('camera' if node == 'camera' else 'step')
                        row['x_bare'] = (round(row['cpu_ms_per_frame'] / base, 2)
                                         if base and row['cpu_ms_per_frame'] else None)
                    rows.append(row)
    return rows


def a53_board(camera_ms, step_ms, receive_ms, viewer_ms, fps, cores):
    """
    Return (step fps, cores left) on a board of `cores` Cortex-A53s, from per-frame A53 times.

    The camera takes its share at the full rate, and so does the step's receiving of every
    frame (receive_ms: the bare subscriber's), whether it processes it or skips it; the rest of
    the step's time a frame, and the viewer's, come with each processed frame. The step
    processes as fast as one core allows, or as what the others leave of the board allows, at
    most at the camera's rate. Negative cores left: the board cannot keep up.
    """
    camera = camera_ms * fps / 1000.0
    receive = min(receive_ms, step_ms) * fps / 1000.0
    per_frame = step_ms - min(receive_ms, step_ms) + viewer_ms
    step_fps = min(fps, 1000.0 / step_ms,
                   max(0.0, cores - camera - receive) * 1000.0 / per_frame)
    used = camera + receive + per_frame * step_fps / 1000.0
    return round(step_fps, 1), round(cores - used, 2) or 0.0  # never -0


def a53_estimate(rows):
    """Return the Cortex-A53 estimate per (size, rate, case) with a hand or none."""
    estimate = []
    for size, fps, case in sorted({(r['size'], r['fps'], r['case']) for r in rows
                                   if r['case'] not in ('bare', 'circle')},
                                  key=lambda k: (-int(k[0].split('x')[0]), k[1], k[2])):
        mine = [r for r in rows if (r['size'], r['fps'], r['case']) == (size, fps, case)]
        nodes = {r['node']: r['cpu_ms_per_frame'] for r in mine}
        models = next((r.get('models_cpu_ms_per_frame') or 0.0 for r in mine
                       if r['node'] == 'step'), 0.0)
        # Receiving a frame: the bare subscriber's time a frame at that size and rate.
        nodes['receive'] = next((r['cpu_ms_per_frame'] for r in rows if (
            r['size'], r['fps'], r['case'], r['node']) == (size, fps, 'bare', 'step')), 0.0)
        if not all(nodes.get(n) for n in ('camera', 'step', 'viewer')):
            continue
        line = {'size': size, 'fps': fps, 'case': case, 'models_ms': models}
        for bound, to_models, to_other in zip(('low', 'high'), A53_MODELS, A53_OTHER):
            ms = {node: (value or 0.0) * to_other for node, value in nodes.items()}
            # The step: its models' share at the convolutions' factor, the rest at the other.
            ms['step'] = (nodes['step'] - models) * to_other + models * to_models
            times = (ms['camera'], ms['step'], ms['receive'], ms['viewer'], fps)
            line[bound] = {
                'camera_cores': round(ms['camera'] * fps / 1000.0, 2),
                'step_ms_per_frame': round(ms['step'], 1),
                'viewer_ms_per_frame': round(ms['viewer'], 1),
                'two_cores': a53_board(*times, cores=2),
                'four_cores': a53_board(*times, cores=4)}
        estimate.append(line)
    return estimate


NODE_NAMES = {('bare', 'camera'): 'bare publisher', ('bare', 'step'): 'bare subscriber',
              'camera': 'usbcam_publisher', 'step': 'vision_step',
              'viewer': 'usbcam_subscriber (web, 1 MJPEG client)'}


def print_tables(rows, estimate, loads):
    print('\n| size | rate | case | node | frames/s handled | CPU per frame | of it, models '
          '| % of one core | x bare | step processing p50 |')
    print('|---|---:|---|---|---:|---:|---:|---:|---:|---:|')
    for r in rows:
        name = NODE_NAMES.get((r['case'], r['node']), NODE_NAMES[r['node']])
        print('| %s | %g | %s | %s | %.1f | %.2f ms | %s | %.1f | %s | %s |' % (
            r['size'], r['fps'], r['case'], name, r['handled_fps'], r['cpu_ms_per_frame'],
            '%.2f ms' % r['models_cpu_ms_per_frame'] if r.get('models_cpu_ms_per_frame')
            else '-', r['cpu_percent'], r.get('x_bare') or '-',
            '%.1f ms' % r['processing_ms_p50'] if r.get('processing_ms_p50') else '-'))
    print('\nmachine load average (1 min) during the run: %.1f to %.1f on %d CPUs' % (
        min(loads), max(loads), os.cpu_count()))
    print("\nCortex-A53, an estimate (not measured): the models' CPU a frame here times %g to "
          "%g, everything else times %g to %g; the step's rate and the cores left on 2 and 4 "
          'cores:' % (A53_MODELS + A53_OTHER))
    print('\n| size | rate | case | camera, cores | step, ms a frame | viewer, ms a frame | '
          'step fps, 2 cores | left | step fps, 4 cores | left |')
    print('|---|---:|---|---:|---:|---:|---:|---:|---:|---:|')
    for line in estimate:
        low, high = line['low'], line['high']

        def span(key, index=None):
            a, b = (low[key], high[key]) if index is None else (low[key][index],
                                                                high[key][index])
            return '%g to %g' % (a, b)
        print('| %s | %g | %s | %s | %s | %s | %s | %s | %s | %s |' % (
            line['size'], line['fps'], line['case'], span('camera_cores'),
            span('step_ms_per_frame'), span('viewer_ms_per_frame'), span('two_cores', 0),
            span('two_cores', 1), span('four_cores', 0), span('four_cores', 1)))


def main():
    parser = argparse.ArgumentParser(description=__doc__.split('\n\n')[1])
    parser.add_argument('--sizes', default=SIZES, help='frame sizes, comma-separated')
    parser.add_argument('--rates', default='10,15,30', help='camera rates, comma-separated')
    parser.add_argument('--window', type=float, default=20.0, help='seconds measured a case')
    parser.add_argument('--rounds', type=int, default=3, help='rounds (medians over them)')
    parser.add_argument('--threads', default='1',
                        help="vision_step's threads, comma-separated: each count a case of "
                             'its own (the first also for circle)')
    parser.add_argument('--cases', default=','.join(CASES), help='cases, comma-separated')
    parser.add_argument('--hand-photo', default='', help='photograph of a hand for the clip')
    parser.add_argument('--tables-of', metavar='JSON',
                        help='print the tables of a results file written before, measure nothing')
    options = parser.parse_args()
    if options.tables_of:
        saved = json.loads(Path(options.tables_of).read_text())
        rows = summarise(saved['runs'])
        print_tables(rows, a53_estimate(rows), saved['load_average'])
        return
    sizes = [tuple(int(v) for v in size.split('x')) for size in options.sizes.split(',')]
    rates = [float(rate) for rate in options.rates.split(',')]
    cases = options.cases.split(',')
    if not set(cases) <= set(CASES):
        raise SystemExit('--cases: choose from %s' % ', '.join(CASES))
    threads = [int(count) for count in options.threads.split(',')]
    # (label, case, threads): the hand_signs cases once per thread count.
    runs = [(case, case, threads[0]) for case in cases if case in ('bare', 'circle')]
    runs += [(case if count == threads[0] else '%s, %d threads' % (case, count), case, count)
             for case in cases if case not in ('bare', 'circle') for count in threads]
    env = local_node_env()  # this process' subscribers join the nodes on their transport
    results, loads = [], [os.getloadavg()[0]]
    with tempfile.TemporaryDirectory(prefix='bench_hand_signs_') as workdir:
        photo = hand_photo_path(options.hand_photo) if 'hand' in cases else None
        clips = {size: make_clip(photo, workdir, size) for size in sizes} if photo else {}
        for round_index in range(options.rounds):
            for size in sizes:
                for fps in rates:
                    for label, case, count in runs:
                        print('round %d, %dx%d at %g fps, %s ...' % (
                            (round_index + 1,) + size + (fps, label)), flush=True)
                        if case == 'bare':
                            measured, nodes = measure_reference(size, fps, options.window,
                                                                env, workdir)
                        else:
                            measured, nodes = measure_pipeline(
                                case, size, fps, options.window, count, env, clips.get(size))
                        loads.append(os.getloadavg()[0])
                        results.append({
                            'round': round_index + 1, 'size': '%dx%d' % size, 'fps': fps,
                            'case': label, 'seconds': round(measured.seconds, 2),
                            'machine_busy': round(measured.machine_busy, 3),
                            'load_average': loads[-1], 'nodes': nodes})
                        print('  %s' % json.dumps(nodes), flush=True)
    rows = summarise(results)
    estimate = a53_estimate(rows)
    print_tables(rows, estimate, loads)
    save_results('hand_signs-py%d%d' % sys.version_info[:2], {
        'sizes': options.sizes, 'rates': rates, 'window_s': options.window,
        'rounds': options.rounds, 'threads': threads, 'cpus': os.cpu_count(),
        'load_average': [min(loads), max(loads)],
        'a53_factors': {'models': A53_MODELS, 'other': A53_OTHER},
        'rows': rows, 'a53_estimate': estimate, 'runs': results})


if __name__ == '__main__':
    main()
