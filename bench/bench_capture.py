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
  its BGR image (``Frame.image('bgr8')``), its JPEG as the camera sent it (``Frame.jpeg``), or
  the frame published as usbcam_publisher publishes it (`ImagePublisher`: the Image holding the
  frame's bytes, rclpy copying them into the middleware's message; nobody subscribed, so
  nothing crosses a process), as bgr8 and as native (the camera's YUYV, yuv422_yuy2).

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
from pathlib import Path
import shutil
import statistics
import subprocess
import sys
import tempfile

REPO = Path(__file__).resolve().parent.parent
TESTS = REPO / 'py_vision' / 'test'
sys.path.insert(0, str(TESTS))
sys.path.insert(0, str(REPO / 'py_vision'))

from bench_common import save_results  # noqa: E402,I100
from emulated_camera import EmulatedCamera  # noqa: E402
import ros_harness  # noqa: E402

# width, height, FourCC, rate (the highest the camera offers at that size)
SIZES = [(640, 480, 'YUYV', 30.0), (1280, 720, 'YUYV', 10.0), (1280, 720, 'MJPG', 30.0)]
# What a case compares: (its name, the ways, in the order they run)
COMPARE = {'YUYV': [('to BGR', ('bare', 'opencv', 'py_vision')),
                    ('published', ('bgr8 published', 'native published'))],
           'MJPG': [("the camera's JPEG kept", ('bare', 'opencv jpeg', 'py_vision jpeg'))]}
WARMUP = 10
SECONDS = 4.0        # of measured reading at 30 fps; more frames' worth at lower rates
MIN_FRAMES = 40
RUNS = 5

WORKER = r"""
import json, sys, threading, time
import cv2
cv2.setNumThreads(1)   # as usbcam_publisher runs it
device, width, height, fourcc, fps, frames, way = sys.argv[1:8]
width, height, fps, frames = int(width), int(height), float(fps), int(frames)
WARMUP = %d
marks = []


def frame_seen():
    marks.append((time.monotonic(), time.thread_time()))   # of the thread reading frames


if way == 'bare':
    import v4l2_ioctl
    fd = v4l2_ioctl.open_device(device)
    stream = v4l2_ioctl.Stream(fd, fourcc, width, height, interval=(1, int(fps)))
    while len(marks) < WARMUP + frames:
        stream.queue(stream.dequeue()['index'])
        frame_seen()
    stream.close()
elif way.startswith('opencv'):
    cap = cv2.VideoCapture(device, cv2.CAP_V4L2)
    cap.set(cv2.CAP_PROP_FOURCC, cv2.VideoWriter_fourcc(*fourcc))
    if way == 'opencv jpeg':
        cap.set(cv2.CAP_PROP_CONVERT_RGB, 0)
    cap.set(cv2.CAP_PROP_FRAME_WIDTH, width)
    cap.set(cv2.CAP_PROP_FRAME_HEIGHT, height)
    cap.set(cv2.CAP_PROP_FPS, fps)
    while len(marks) < WARMUP + frames:
        ok, kept = cap.read()
        if ok:
            stamp = cap.get(cv2.CAP_PROP_POS_MSEC)   # the capture time, as a node stamps it
            frame_seen()
    cap.release()
else:
    from py_vision.capture import Camera, CaptureLoop
    from py_vision.cv_bridge import CvBridge
    from py_vision.params import Parameters
    from py_vision.transport import ImagePublisher
    import rclpy
    from rclpy.qos import QoSProfile
    from std_msgs.msg import Header
    rclpy.init()
    node = rclpy.create_node('bench_capture')
    images = ImagePublisher(Parameters(node), 'bench_image', QoSProfile(depth=10), CvBridge(),
                            lazy_raw=False)
    done = threading.Event()

    class Log:
        def info(self, text): pass
        def warning(self, text): print(text, file=sys.stderr)
        error = warning

    def keep(frame):
        if way == 'py_vision':
            return frame.image('bgr8')
        if way == 'py_vision jpeg':
            return frame.jpeg
        output = way.split()[0]
        return images.publish(Header(), lambda: frame.image(output), None,
                              frame.encoding(output))

    def on_frame(camera, frame):
        keep(frame)
        frame_seen()
        if len(marks) >= WARMUP + frames:
            done.set()
    loop = CaptureLoop(lambda: Camera.open(device, width, height, fps, fourcc), on_frame, Log())
    loop.start()
    done.wait(120)
    loop.close()
(t0, c0), (t1, c1) = marks[WARMUP - 1], marks[-1]
count = len(marks) - WARMUP
print(json.dumps({'frames': count, 'cpu_ms_per_frame': 1e3 * (c1 - c0) / count,
                  'fps': count / (t1 - t0)}))
""" % WARMUP


def run(camera, env, width, height, fourcc, fps, way):
    frames = max(MIN_FRAMES, int(SECONDS * fps))
    out = subprocess.run(
        [sys.executable, '-c', WORKER, camera.device, str(width), str(height), fourcc, str(fps),
         str(frames), way], env=env, capture_output=True, text=True, timeout=180)
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
    print('\n| size | format | fps | bgr8 published | native published | native / bgr8 |')
    print('|---|---|---:|---:|---:|---:|')
    for case in cases:
        ms = list(case['ms_per_frame'].values())
        if len(ms) == 2:
            print('| %s | %s | %g | %.3f | %.3f | %.2f |' % (
                case['size'], case['format'], case['fps'], *ms, case['ratio']))
    save_results('capture', {'cases': cases, 'runs_each': runs})


if __name__ == '__main__':
    main()
