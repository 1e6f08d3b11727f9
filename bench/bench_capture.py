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
Benchmark the capture: CPU per frame of py_vision's own V4L2 streaming.

Run from the repository root: ``.venv/bin/python bench/bench_capture.py`` (about 8 minutes;
``--quick``: one run of each). Every way reads the same emulated USB camera (the tests'
emulated webcam, docs/emulated_cameras.md), each run in a process of its own:

- bare: the least a program can do, in Python: S_FMT, mmap buffers, STREAMON, then for each
  frame poll(), VIDIOC_DQBUF and VIDIOC_QBUF, touching no pixel (the tests' v4l2_ioctl);
- OpenCV: ``cv2.VideoCapture(device, cv2.CAP_V4L2)`` and a ``cap.read()`` loop, which gives
  BGR images (OpenCV converts YUYV), or the camera's JPEG with CAP_PROP_CONVERT_RGB off, with
  each frame's capture time read (CAP_PROP_POS_MSEC) as a driver would stamp it;
- py_vision: `CaptureLoop` over `Camera.open`, as usbcam_publisher runs it (its own mmap
  streaming, the buffers' timestamps, the stale, corrupt, error and dropped frame checks,
  loss detection, counters), handing each frame to a function that takes what is measured:
  its BGR image (``Frame.image('bgr8')``), its pixels as sent (``Frame.image('native')``: the
  image the node publishes with output_encoding native), its JPEG as the camera sent it
  (``Frame.jpeg``), or
  the frame published as usbcam_publisher publishes it (`ImagePublisher`: the frame converted,
  or copied, straight into the serialized Image that goes to rcl, which the middleware copies;
  nobody subscribed, so nothing crosses a process), as bgr8 and as native (the camera's YUYV,
  yuv422_yuy2).

The cost is the CPU time of the thread that reads the frames (the system calls, OpenCV's read
and conversion, py_vision's own work; not the emulated camera's thread that makes the frames,
which is the device's) per frame after the first 10, at the camera's own rate. The runs of a
case alternate the ways, 5 of each: the tables give the medians, and the ratios are medians of
each run's ratio to the run of the other way just before it. Prints two Markdown tables and
writes bench/results/capture.json. ``--runs N`` N runs of each.
"""

import argparse
import json
import os
import shutil
import statistics
import subprocess
import sys
import tempfile

from bench_common import BENCH, save_results, TESTS
from emulated_camera import EmulatedCamera
import ros_harness

# width, height, FourCC, rate (the highest the camera offers at that size)
SIZES = [(640, 480, 'YUYV', 30.0), (1280, 720, 'YUYV', 10.0), (1280, 720, 'MJPG', 30.0)]
# What a case compares: (its name, the ways, in the order they run)
COMPARE = {'YUYV': [('to BGR', ('bare', 'opencv', 'py_vision')),
                    ('the image to publish', ('py_vision', 'py_vision native')),
                    ('published', ('bgr8 published', 'native published'))],
           'MJPG': [("the camera's JPEG kept", ('bare', 'opencv jpeg', 'py_vision jpeg'))]}
WARMUP = 10
SECONDS = 4.0        # of measured reading at 30 fps; more frames' worth at lower rates
MIN_FRAMES = 40
RUNS = 5

WORKER = BENCH / 'capture_worker.py'


def run(camera, env, width, height, fourcc, fps, way):
    frames = max(MIN_FRAMES, int(SECONDS * fps))
    out = subprocess.run(
        [sys.executable, str(WORKER), camera.device, str(width), str(height), fourcc,
         str(fps), str(frames), way, str(WARMUP)],
        env=env, capture_output=True, text=True, timeout=180)
    if out.returncode != 0:
        raise RuntimeError('%s run failed: %s' % (way, out.stderr))
    return json.loads(out.stdout.splitlines()[-1])


def paired(runs, way, reference):
    """Return the median of each run's ratio to the reference's run just before it."""
    return statistics.median(ours['cpu_ms_per_frame'] / theirs['cpu_ms_per_frame']
                             for theirs, ours in zip(runs[reference], runs[way]))


def main():
    parser = argparse.ArgumentParser(description=__doc__.split('\n\n')[0])
    parser.add_argument('--quick', action='store_true', help='one run of each')
    parser.add_argument('--runs', type=int, default=RUNS, help='runs of each (%d)' % RUNS)
    args = parser.parse_args()
    runs = 1 if args.quick else args.runs
    state = tempfile.mkdtemp(prefix='bench_capture_')
    camera = EmulatedCamera(state, 'webcam_1080p', 60)
    env = camera.env(ros_harness.installed_env())
    env['PYTHONPATH'] = os.pathsep.join([str(TESTS), env.get('PYTHONPATH', '')])
    cases = []
    try:
        for width, height, fourcc, fps in SIZES:
            for name, ways in COMPARE[fourcc]:
                results = {way: [] for way in ways}
                for _ in range(runs):
                    for way in ways:
                        results[way].append(run(camera, env, width, height, fourcc, fps, way))
                medians = {way: statistics.median(r['cpu_ms_per_frame'] for r in results[way])
                           for way in ways}
                cases.append({'size': '%dx%d' % (width, height), 'format': fourcc, 'fps': fps,
                              'what': name, 'ms_per_frame': medians,
                              'ratio': paired(results, ways[-1], ways[-2]),
                              'runs': results})
                print('%dx%d %s %s done' % (width, height, fourcc, name), file=sys.stderr)
    finally:
        camera.close()
        shutil.rmtree(state, ignore_errors=True)
    print('| size | format | fps | frames | bare loop | OpenCV backend | py_vision | '
          'py_vision / OpenCV |')
    print('|---|---|---:|---|---:|---:|---:|---:|')
    for case in cases:
        ms = list(case['ms_per_frame'].values())
        if len(ms) == 3:
            print('| %s | %s | %g | %s | %.3f | %.3f | %.3f | %.2f |' % (
                case['size'], case['format'], case['fps'], case['what'], *ms, case['ratio']))
    print('\n| size | format | fps | frames | bgr8 | native | native / bgr8 |')
    print('|---|---|---:|---|---:|---:|---:|')
    for case in cases:
        ms = list(case['ms_per_frame'].values())
        if len(ms) == 2:
            print('| %s | %s | %g | %s | %.3f | %.3f | %.2f |' % (
                case['size'], case['format'], case['fps'], case['what'], *ms, case['ratio']))
    save_results('capture', {'cases': cases, 'runs_each': runs})


if __name__ == '__main__':
    main()
