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
Benchmark py_vision.cv_bridge against a plain numpy copy and upstream's way of filling a message.

Run from the repository root: ``.venv/bin/python bench/bench_cv_bridge.py``. Prints a Markdown
table of medians and writes bench/results/cv_bridge.json.
"""

import statistics
import time

from bench_common import save_results
import numpy as np
from py_vision.cv_bridge import CvBridge
from sensor_msgs.msg import Image
from std_msgs.msg import Header

SIZES = [(640, 480), (1280, 720), (1920, 1080)]
REPEATS = 21
MIN_BATCH_SECONDS = 0.02


def batch_size(func):
    """Return how many calls take at least MIN_BATCH_SECONDS."""
    calls = 1
    while True:
        start = time.perf_counter()
        for _ in range(calls):
            func()
        if time.perf_counter() - start >= MIN_BATCH_SECONDS:
            return calls
        calls *= 2


def measure(cases):
    """
    Time every case, interleaved round by round so a busy machine slows them all alike.

    Returns {case: (median seconds per call, median ratio to the first case in the same round)}.
    Results stay alive for a few calls, as a node's frames do, so allocation costs are real.
    """
    batches = {name: batch_size(func) for name, func in cases.items()}
    samples = {name: [] for name in cases}
    keep = [None, None, None]
    for _ in range(REPEATS):
        for name, func in cases.items():
            calls = batches[name]
            start = time.perf_counter()
            for i in range(calls):
                keep[i % 3] = func()
            samples[name].append((time.perf_counter() - start) / calls)
    reference = samples[next(iter(cases))]
    return {name: (statistics.median(times),
                   statistics.median(t / r for t, r in zip(times, reference)))
            for name, times in samples.items()}


def upstream_fill(frame):
    """Fill a message the way upstream cv_bridge's cv2_to_imgmsg does."""
    msg = Image()
    msg.height, msg.width = frame.shape[:2]
    msg.encoding = 'bgr8'
    msg.data.frombytes(frame.tobytes())
    msg.step = len(msg.data) // msg.height
    return msg


def main():
    bridge = CvBridge()
    header = Header(frame_id='usb_camera')
    rows = []
    for width, height in SIZES:
        frame = np.random.default_rng(0).integers(0, 256, (height, width, 3), np.uint8)
        msg = bridge.cv2_to_imgmsg(frame, 'bgr8', header=header)
        # A 16-bit camera's frame (depth, thermal): scaling to 8 bits rounds as convertTo does.
        deep = np.random.default_rng(1).integers(0, 65536, (height, width), np.uint16)
        mono16 = bridge.cv2_to_imgmsg(deep, 'mono16', header=header)
        cases = {
            'numpy copy (reference)': frame.copy,
            'upstream fill: frombytes(tobytes())': lambda: upstream_fill(frame),
            'cv2_to_imgmsg bgr8': lambda: bridge.cv2_to_imgmsg(frame, 'bgr8', header=header),
            'imgmsg_to_cv2 passthrough': lambda: bridge.imgmsg_to_cv2(msg),
            'imgmsg_to_cv2 bgr8 from bgr8': lambda: bridge.imgmsg_to_cv2(msg, 'bgr8'),
            'imgmsg_to_cv2 rgb8 from bgr8': lambda: bridge.imgmsg_to_cv2(msg, 'rgb8'),
            'imgmsg_to_cv2 mono8 from mono16': lambda: bridge.imgmsg_to_cv2(mono16, 'mono8'),
        }
        for name, (seconds, ratio) in measure(cases).items():
            rows.append({'size': '%dx%d' % (width, height), 'case': name,
                         'median_us': seconds * 1e6, 'vs_numpy_copy': ratio})
    print('| size | case | median | x numpy copy (median of per-round ratios) |')
    print('|---|---|---:|---:|')
    for row in rows:
        print('| %s | %s | %.1f us | %.2f |' % (
            row['size'], row['case'], row['median_us'], row['vs_numpy_copy']))
    save_results('cv_bridge', {'rows': rows})


if __name__ == '__main__':
    main()
