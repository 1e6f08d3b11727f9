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
Measure vision_step's model steps behind the synthetic camera: time a frame, rate, age, memory.

  .venv/bin/python bench/bench_vision_step.py [--duration S] [--threads N] [--steps ...]

The camera is usbcam_publisher on the synthetic source, 640x480 at 30 fps. For each step
(`circle` is cv_bridge_test itself, the reference; then vision_step with step:=hand_signs and
step:=faces) it runs the camera and the node, one case after the other, each on its own ROS
domain. A collector in this process subscribes to the node's output and records each output's
age (arrival minus the input's capture stamp). After the first output it waits 2 s, then
measures --duration seconds: outputs per second, output age p50/p99; the node's own statistics
line gives the time a frame took in the step (processing p50/p99: conversion, step, publishing,
over its last 5 s); at the end, the node's VmRSS with its models loaded, and how much more than
cv_bridge_test's that is.
Prints a Markdown table and writes bench/results/vision_step.json.

  .venv/bin/python bench/bench_vision_step.py --lazy [--rounds N] [--duration S] [--steps ...]

measures instead what publishing vision_step/image only while someone subscribes saves: for
each step (default circle, the cheapest, and hand_signs) the node's CPU time (utime + stime
from /proc) over --duration seconds, with a subscriber of vision_step/image in this process
(what every frame cost before: the image published whoever listened) and without one, the two
alternating for --rounds rounds, each on a fresh camera and node. Per processed frame (the
count from the node's /diagnostics): CPU ms, medians of the rounds, and their ratio. Writes
bench/results/vision_step_lazy.json.
"""

import argparse
import os
from pathlib import Path
import re
import statistics
import threading
import time

from bench_common import CLK_TCK, cpu_ticks, local_node_env, save_results, stopped_after
import ros_harness

FPS = 30.0
WIDTH, HEIGHT = 640, 480
SETTLE_S = 2.0
STEPS = ('circle', 'hand_signs', 'faces')
LAZY_STEPS = ('circle', 'hand_signs')  # --lazy's: the cheapest step, and the model one
STATS = re.compile(r'processing p50 ([\d.]+) ms p99 ([\d.]+) ms')


class Collector:
    """Records (arrival, age in s) of every output, from a ROS peer's thread."""

    def __init__(self, peer, topic):
        from rclpy.qos import QoSProfile, ReliabilityPolicy
        from sensor_msgs.msg import Image
        self.records = []
        self._lock = threading.Lock()
        peer.node.create_subscription(
            Image, topic, self._received,
            QoSProfile(depth=100, reliability=ReliabilityPolicy.RELIABLE))

    def _received(self, msg):
        age = time.time() - (msg.header.stamp.sec + msg.header.stamp.nanosec * 1e-9)
        with self._lock:
            self.records.append((time.monotonic(), age))

    def between(self, start, end):
        with self._lock:
            return [r for r in self.records if start <= r[0] < end]


def rss_mib(pid):
    """Return a process' VmRSS in MiB."""
    for line in Path('/proc/%d/status' % pid).read_text().splitlines():
        if line.startswith('VmRSS:'):
            return int(line.split()[1]) / 1024.0
    raise RuntimeError('no VmRSS for process %d' % pid)


def measure(step, duration, threads, env):
    """Run the camera and the node running step; return what was measured."""
    from py_vision.stats import percentile
    domain = ros_harness.DomainId()
    env = dict(env, ROS_DOMAIN_ID=str(domain.value))
    camera = ros_harness.NodeProcess('usbcam_publisher', ros_harness.ros_args({
        'video_device': 'synthetic', 'image_width': WIDTH, 'image_height': HEIGHT,
        'framerate': FPS}), env)
    if step == 'circle':
        node, topic = ros_harness.NodeProcess('cv_bridge_test', [], env), 'cv_bridge_image'
    else:
        node = ros_harness.NodeProcess('vision_step', ros_harness.ros_args(
            {'step': step, 'threads': threads}), env)
        topic = 'vision_step/image'
    peer = ros_harness.RosPeer(domain.value, name='bench_collector')
    with stopped_after(domain, peer, node, camera) as ended:
        collector = Collector(peer, topic)
        ros_harness.wait_until(lambda: collector.records, 90.0, 0.05, 'the first output')
        start = time.monotonic() + SETTLE_S
        time.sleep(SETTLE_S + duration)
        records = collector.between(start, start + duration)
        rss = rss_mib(node.pid)
        # The node's statistics line comes every 5 s: the last one covers the measured time.
        line = node.wait_for_output(STATS.pattern, 10.0)
        stats = STATS.findall(node.output())[-1]
    ages = sorted(r[1] for r in records)
    return {
        'step': step, 'node': 'cv_bridge_test' if step == 'circle' else 'vision_step',
        'outputs': len(records), 'output_fps': round(len(records) / duration, 2),
        'processing_ms_p50': float(stats[0]), 'processing_ms_p99': float(stats[1]),
        'age_ms_p50': round(percentile(ages, 0.5) * 1e3, 1) if ages else None,
        'age_ms_p99': round(percentile(ages, 0.99) * 1e3, 1) if ages else None,
        'rss_mib': round(rss, 1),
        'log': [text for text in ended.log.splitlines()
                if 'running step' in text or 'drawing on' in text] + [line.group(0)],
    }


def processed(arrays):
    """Return the newest (processed, images published) of vision_step's /diagnostics, or None."""
    values = ros_harness.status_values(arrays, 'vision_step: processing')
    if not values:
        return None
    return int(values['processed']), int(values.get('images published', -1))


def lazy_case(step, subscribed, duration, threads, env):
    """Run camera and vision_step; return its CPU ms per processed frame, and the counts."""
    from diagnostic_msgs.msg import DiagnosticArray
    from rclpy.qos import QoSProfile, ReliabilityPolicy
    domain = ros_harness.DomainId()
    env = dict(env, ROS_DOMAIN_ID=str(domain.value))
    camera = ros_harness.NodeProcess('usbcam_publisher', ros_harness.ros_args({
        'video_device': 'synthetic', 'image_width': WIDTH, 'image_height': HEIGHT,
        'framerate': FPS}), env)
    node = ros_harness.NodeProcess('vision_step', ros_harness.ros_args(
        {'step': step, 'threads': threads}), env)
    peer = ros_harness.RosPeer(domain.value, name='bench_lazy')
    with stopped_after(domain, peer, node, camera):
        arrays = peer.collect(DiagnosticArray, '/diagnostics', QoSProfile(
            depth=100, reliability=ReliabilityPolicy.RELIABLE))
        if subscribed:
            outputs = Collector(peer, 'vision_step/image')
        ros_harness.wait_until(lambda: (processed(arrays) or (0,))[0] > 0, 90.0, 0.1,
                               'frames processed')
        if subscribed:
            ros_harness.wait_until(lambda: outputs.records, 30.0, 0.05, 'the first output')
        time.sleep(SETTLE_S)
        # A fresh diagnostics report at each end of the window: counts and CPU together.
        count = len(arrays)
        ros_harness.wait_until(lambda: len(arrays) > count, 10.0, 0.01, 'a report')
        (start_frames, start_published), start_cpu = processed(arrays), cpu_ticks(node.pid)
        time.sleep(duration)
        count = len(arrays)
        ros_harness.wait_until(lambda: len(arrays) > count, 10.0, 0.01, 'a report')
        (end_frames, end_published), end_cpu = processed(arrays), cpu_ticks(node.pid)
    frames = end_frames - start_frames
    published = end_published - start_published
    if frames <= 0 or (published > 0) != subscribed:
        raise SystemExit('%s, subscribed %s: %d frames processed, %d published' % (
            step, subscribed, frames, published))
    return {'cpu_ms_per_frame': (end_cpu - start_cpu) / CLK_TCK / frames * 1e3,
            'processed': frames, 'published': published}


def lazy(options, env):
    """Measure each step with and without a subscriber of its image; print and save."""
    steps = options.steps.split(',') if options.steps != ','.join(STEPS) else LAZY_STEPS
    load_before = os.getloadavg()[0]
    runs = {(step, subscribed): [] for step in steps for subscribed in (True, False)}
    for round_ in range(options.rounds):
        for step in steps:
            for subscribed in (True, False):
                case = lazy_case(step, subscribed, options.duration, options.threads, env)
                runs[step, subscribed].append(case)
                print('round %d, %-10s %-13s %.3f ms CPU a frame (%d frames, %d published)' % (
                    round_ + 1, step, 'subscribed' if subscribed else 'nobody',
                    case['cpu_ms_per_frame'], case['processed'], case['published']), flush=True)
    load = (load_before, os.getloadavg()[0])
    print('\n| step | vision_step/image | CPU a processed frame (median of %d) | ratio to '
          'subscribed | saved a frame |' % options.rounds)
    print('|---|---|---:|---:|---:|')
    summary = []
    for step in steps:
        on = statistics.median(c['cpu_ms_per_frame'] for c in runs[step, True])
        off = statistics.median(c['cpu_ms_per_frame'] for c in runs[step, False])
        print('| %s | subscribed (reference) | %.3f ms | 1.00 | - |' % (step, on))
        print('| %s | nobody subscribed | %.3f ms | %.2f | %.3f ms |' % (
            step, off, off / on, on - off))
        summary.append({'step': step, 'subscribed_cpu_ms': round(on, 4),
                        'nobody_cpu_ms': round(off, 4), 'ratio': round(off / on, 4)})
    print('machine load average (1 min) before and after: %.1f, %.1f on %d CPUs' % (
        load + (os.cpu_count(),)))
    save_results('vision_step_lazy', {
        'camera': '%dx%d at %g fps, synthetic' % (WIDTH, HEIGHT, FPS),
        'duration_s': options.duration, 'rounds': options.rounds, 'threads': options.threads,
        'cpus': os.cpu_count(), 'load_average': load, 'summary': summary,
        'runs': [dict(case, step=step, subscribed=subscribed)
                 for (step, subscribed), cases in runs.items() for case in cases]})


def main():
    parser = argparse.ArgumentParser(description=__doc__.split('\n\n')[1])
    parser.add_argument('--duration', type=float, default=10.0, help='seconds measured a step')
    parser.add_argument('--threads', type=int, default=1, help="vision_step's threads")
    parser.add_argument('--steps', default=','.join(STEPS),
                        help='steps, comma-separated (circle: cv_bridge_test, the reference)')
    parser.add_argument('--lazy', action='store_true',
                        help='measure vision_step with and without a subscriber of its image')
    parser.add_argument('--rounds', type=int, default=3, help='rounds of --lazy')
    options = parser.parse_args()
    steps = options.steps.split(',')
    env = local_node_env()  # the collector joins the nodes on their transport
    if options.lazy:
        lazy(options, env)
        return

    load_before = os.getloadavg()[0]
    cases = []
    for step in steps:
        print('%-10s ...' % step, flush=True)
        result = measure(step, options.duration, options.threads, env)
        cases.append(result)
        print('  %s' % {k: v for k, v in result.items() if k != 'log'}, flush=True)
    reference = next((c['rss_mib'] for c in cases if c['step'] == 'circle'), None)
    for case in cases:
        case['rss_more_than_cv_bridge_test_mib'] = (
            None if reference is None else round(case['rss_mib'] - reference, 1))

    print('\n| step | node | processed fps | processing p50 | p99 | output age p50 | p99 | '
          'RSS | RSS more than cv_bridge_test |')
    print('|---|---|---:|---:|---:|---:|---:|---:|---:|')
    for c in cases:
        print('| %s | %s | %.1f | %.1f ms | %.1f ms | %s ms | %s ms | %.1f MiB | %s |' % (
            c['step'], c['node'], c['output_fps'], c['processing_ms_p50'],
            c['processing_ms_p99'], c['age_ms_p50'], c['age_ms_p99'], c['rss_mib'],
            '-' if c['step'] == 'circle' or reference is None
            else '%.1f MiB' % c['rss_more_than_cv_bridge_test_mib']))
    # Other work on the machine shows in the times (they are wall-clock times).
    load = (load_before, os.getloadavg()[0])
    print('machine load average (1 min) before and after: %.1f, %.1f on %d CPUs' % (
        load + (os.cpu_count(),)))
    save_results('vision_step', {
        'camera': '%dx%d at %g fps, synthetic' % (WIDTH, HEIGHT, FPS),
        'duration_s': options.duration, 'threads': options.threads, 'cpus': os.cpu_count(),
        'load_average': load, 'cases': cases})


if __name__ == '__main__':
    main()
