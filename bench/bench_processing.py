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
Measure a processing step slower than the camera: cv_bridge_test against the tutorial's pattern.

  .venv/bin/python bench/bench_processing.py [--duration S] [--loads 0,20,50,100,200]

The camera is usbcam_publisher on the synthetic source, 640x480 at 30 fps. For each processing
time per frame (cv_bridge_test's simulated_work_ms, the same busy work in the reference) it runs
  latest     cv_bridge_test as installed: newest-frame worker, keep-last 1 subscription
  tutorial   the tutorial's node: default keep-last 10 subscription, the work in the callback
one after the other (never both at once: they would compete for the cores), each with its own
camera and ROS domain. A collector in this process subscribes to cv_bridge_image; per output it
records the age (arrival minus the input's capture stamp) and the frame index the synthetic
camera wrote into the image. After the first output it waits 2 s, then measures --duration
seconds: output rate, frames of the camera that got no output (skipped by the worker, or dropped
by a full subscription queue), output age p50/p99, against the target age
processing + 2 frame periods + 10 ms.
Prints a Markdown table and writes bench/results/processing.json.
"""

import argparse
import os
import sys
import threading
import time

from bench_common import local_node_env, save_results, StopFlag, stopped_after
import ros_harness

FPS = 30.0
WIDTH, HEIGHT = 640, 480
LOADS_MS = (0, 20, 50, 100, 200)
SETTLE_S = 2.0
KINDS = ('latest', 'tutorial')


def tutorial_node(work_ms):
    """Run the tutorial-style node (this file's `tutorial` mode) until Ctrl-C."""
    import cv2
    from py_vision import dds
    from py_vision.cv_bridge import CvBridge
    from py_vision.steps.circle import CIRCLE_BGR, CIRCLE_CENTER, CIRCLE_RADIUS, \
        simulated_work
    import rclpy
    from rclpy.node import Node
    from rclpy.signals import SignalHandlerOptions
    from sensor_msgs.msg import Image

    class TutorialProcessing(Node):
        """What the tutorial teaches: all the work in the callback of a depth-10 subscription."""

        def __init__(self):
            super().__init__('tutorial_processing')
            self.bridge = CvBridge()
            self.publisher_ = self.create_publisher(Image, 'cv_bridge_image', 10)
            self.subscription_ = self.create_subscription(
                Image, 'usb_camera/image', self.callback, 10)

        def callback(self, msg):
            image = self.bridge.imgmsg_to_cv2(msg, 'bgr8')
            simulated_work(work_ms / 1e3, lambda: False)
            cv2.circle(image, CIRCLE_CENTER, CIRCLE_RADIUS, CIRCLE_BGR, -1)
            self.publisher_.publish(self.bridge.cv2_to_imgmsg(image, 'bgr8', header=msg.header))

    # The same transport as the py_vision nodes: on Humble, images alone through shared memory.
    dds.use_packaged_profile(image_topics=('/usb_camera/image',))
    # Ctrl-C ends the loop between callbacks: rclpy's own handler would shut the context down
    # under a callback still publishing, and the reference would end in a traceback.
    rclpy.init(signal_handler_options=SignalHandlerOptions.NO)
    stop = StopFlag()
    node = TutorialProcessing()
    try:
        while not stop.is_set():
            rclpy.spin_once(node, timeout_sec=0.1)
    finally:
        node.destroy_node()
        rclpy.try_shutdown()


class Collector:
    """Records (arrival, age in s, frame index) of every output, from a ROS peer's thread."""

    def __init__(self, peer):
        from rclpy.qos import QoSProfile, ReliabilityPolicy
        from sensor_msgs.msg import Image
        self.records = []
        self._lock = threading.Lock()
        peer.node.create_subscription(
            Image, 'cv_bridge_image', self._received,
            QoSProfile(depth=100, reliability=ReliabilityPolicy.RELIABLE))

    def _received(self, msg):
        import numpy as np
        from py_vision.capture.synthetic_picture import read_frame_index
        age = time.time() - (msg.header.stamp.sec + msg.header.stamp.nanosec * 1e-9)
        image = np.frombuffer(bytes(msg.data), np.uint8).reshape(msg.height, msg.width, 3)
        with self._lock:
            self.records.append((time.monotonic(), age, read_frame_index(image)))

    def since(self, start):
        with self._lock:
            return [r for r in self.records if r[0] >= start]


def measure(kind, work_ms, duration, env):
    """Run the camera and one processing node; return what reached the collector."""
    from py_vision.stats import percentile
    domain = ros_harness.DomainId()
    env = dict(env, ROS_DOMAIN_ID=str(domain.value))
    camera = ros_harness.NodeProcess('usbcam_publisher', ros_harness.ros_args({
        'video_device': 'synthetic', 'image_width': WIDTH, 'image_height': HEIGHT,
        'framerate': FPS}), env)
    if kind == 'latest':
        node = ros_harness.NodeProcess('cv_bridge_test', ros_harness.ros_args({
            'simulated_work_ms': float(work_ms)}), env)
    else:
        node = ros_harness.NodeProcess(sys.executable, [__file__, 'tutorial', str(work_ms)],
                                       env, name='tutorial_processing')
    peer = ros_harness.RosPeer(domain.value, name='bench_collector')
    with stopped_after(domain, peer, node, camera) as ended:
        collector = Collector(peer)
        ros_harness.wait_until(lambda: collector.records, 60.0, 0.05, 'the first output')
        start = time.monotonic() + SETTLE_S
        time.sleep(SETTLE_S + duration)
        records = collector.since(start)
        records = [r for r in records if r[0] < start + duration]
    indices = [r[2] for r in records if r[2] is not None]
    ages = sorted(r[1] for r in records)
    camera_frames = indices[-1] - indices[0] + 1 if indices else 0
    result = {
        'outputs': len(records),
        'output_fps': round(len(records) / duration, 2),
        'camera_frames': camera_frames,
        'not_processed': camera_frames - len(indices),
        'in_order': indices == sorted(indices),
        'age_ms_p50': round(percentile(ages, 0.5) * 1e3, 1) if ages else None,
        'age_ms_p99': round(percentile(ages, 0.99) * 1e3, 1) if ages else None,
    }
    if kind == 'latest':
        result['log'] = [line for line in ended.log.splitlines() if 'frames in' in line][-1:]
    return result


def main():
    if sys.argv[1:2] == ['tutorial']:
        tutorial_node(float(sys.argv[2]))
        return
    parser = argparse.ArgumentParser(description=__doc__.split('\n\n')[1])
    parser.add_argument('--duration', type=float, default=10.0, help='seconds measured a case')
    parser.add_argument('--loads', default=','.join(str(v) for v in LOADS_MS),
                        help='processing times per frame in ms, comma-separated')
    options = parser.parse_args()
    loads = [float(v) for v in options.loads.split(',')]

    env = local_node_env()  # the collector joins the nodes on their transport

    period_ms = 1e3 / FPS
    load_before = os.getloadavg()[0]
    cases = []
    for work_ms in loads:
        for kind in KINDS:
            print('%-8s %5g ms a frame ...' % (kind, work_ms), flush=True)
            result = measure(kind, work_ms, options.duration, env)
            target = work_ms + 2 * period_ms + 10.0
            result.update(node=kind, work_ms=work_ms, target_age_ms=round(target, 1),
                          meets_target=result['age_ms_p99'] is not None
                          and result['age_ms_p99'] <= target)
            cases.append(result)
            print('  %s' % {k: v for k, v in result.items() if k != 'log'}, flush=True)

    print('\n| processing | node | output fps | camera frames | not processed | age p50 | '
          'age p99 | target p99 | meets |')
    print('|---:|---|---:|---:|---:|---:|---:|---:|---|')
    for c in cases:
        print('| %g ms | %s | %.1f | %d | %d | %s ms | %s ms | %.0f ms | %s |' % (
            c['work_ms'], 'cv_bridge_test' if c['node'] == 'latest' else 'tutorial-style',
            c['output_fps'], c['camera_frames'], c['not_processed'], c['age_ms_p50'],
            c['age_ms_p99'], c['target_age_ms'], 'yes' if c['meets_target'] else 'no'))
    for work_ms in loads:
        pair = {c['node']: c for c in cases if c['work_ms'] == work_ms}
        if pair['latest']['age_ms_p99'] and pair['tutorial']['age_ms_p99']:
            print('%g ms: tutorial-style age p99 / cv_bridge_test age p99 = %.2f' % (
                work_ms, pair['tutorial']['age_ms_p99'] / pair['latest']['age_ms_p99']))
    # Other work on the machine shows in the ages (the step is timed by the wall clock).
    load = (load_before, os.getloadavg()[0])
    print('machine load average (1 min) before and after: %.1f, %.1f on %d CPUs' % (
        load + (os.cpu_count(),)))
    save_results('processing', {
        'camera': '%dx%d at %g fps, synthetic' % (WIDTH, HEIGHT, FPS),
        'duration_s': options.duration, 'cpus': os.cpu_count(), 'load_average': load,
        'cases': cases})


if __name__ == '__main__':
    main()
