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
Benchmark the synthetic V4L2 source: the cost of one read() without its pacing, and its CPU use.

Run from the repository root: ``.venv/bin/python bench/bench_synthetic.py``. The reference is
the YUYV to BGR conversion alone, which OpenCV's V4L2 backend pays for every frame of a real
camera too. Prints a Markdown table of medians and writes bench/results/synthetic.json.
"""

import statistics
import time

from bench_common import save_results
import cv2
from fake_clock import FakeClock
from py_vision.capture import synthetic_device, synthetic_picture

SIZES = [(640, 480), (1280, 720), (1920, 1080)]
SAMPLES = 200
PACED = (640, 480, 30.0, 3.0)  # width, height, fps, seconds of real-time reading


def median_us(func):
    func()
    samples = []
    for _ in range(SAMPLES):
        start = time.perf_counter()
        func()
        samples.append(time.perf_counter() - start)
    return statistics.median(samples) * 1e6


def unpaced_read_us(width, height):
    # The tests' clock: a read's wait for its frame takes no time, and no frame is late.
    devices = synthetic_device.SyntheticDevices(clock=FakeClock())
    cam = synthetic_device.SyntheticCamera(width, height, 30.0, name='bench', devices=devices)
    return median_us(cam.read)


def paced_cpu_percent(width, height, fps, seconds):
    """Share of one core a loop of paced read() calls uses."""
    cam = synthetic_device.SyntheticCamera(width, height, fps, name='bench-paced')
    cam.read()
    wall, cpu = time.monotonic(), time.process_time()
    frames = 0
    while time.monotonic() - wall < seconds:
        frames += cam.read()[0]
    wall, cpu = time.monotonic() - wall, time.process_time() - cpu
    return 100.0 * cpu / wall, frames / wall


def main():
    rows = []
    for width, height in SIZES:
        yuyv = synthetic_picture.synthetic_yuyv(1, width, height)
        frame = synthetic_picture.synthetic_frame(1, width, height)
        times = {
            'cvtColor YUYV->BGR (reference)':
                median_us(lambda: cv2.cvtColor(yuyv, cv2.COLOR_YUV2BGR_YUYV)),
            'SyntheticCamera.read() without pacing': unpaced_read_us(width, height),
            'synthetic_frame()':
                median_us(lambda: synthetic_picture.synthetic_frame(7, width, height)),
            'read_frame_index()': median_us(lambda: synthetic_picture.read_frame_index(frame)),
        }
        reference = times['cvtColor YUYV->BGR (reference)']
        for name, micros in times.items():
            rows.append({'size': '%dx%d' % (width, height), 'case': name,
                         'median_us': micros, 'vs_cvtcolor': micros / reference})
    print('| size | case | median | x cvtColor |')
    print('|---|---|---:|---:|')
    for row in rows:
        cells = (row['size'], row['case'], row['median_us'], row['vs_cvtcolor'])
        print('| %s | %s | %.1f us | %.2f |' % cells)
    width, height, fps, seconds = PACED
    cpu, achieved = paced_cpu_percent(width, height, fps, seconds)
    print('\npaced read() loop, %dx%d at %g fps for %g s: %.1f fps, %.1f%% of one core'
          % (width, height, fps, seconds, achieved, cpu))
    paced = {'size': '%dx%d' % (width, height), 'fps': fps, 'achieved_fps': achieved,
             'cpu_percent_of_one_core': cpu}
    save_results('synthetic', {'rows': rows, 'paced': paced})


if __name__ == '__main__':
    main()
