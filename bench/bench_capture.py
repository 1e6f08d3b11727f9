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
Benchmark the capture: CPU per frame of py_vision's capture against a bare OpenCV read loop.

Run from the repository root: ``.venv/bin/python bench/bench_capture.py`` (about 9 minutes;
``--quick``: one run of each). Both read the same emulated USB camera (the tests' emulated
webcam, docs/emulated_cameras.md: OpenCV's real V4L2 backend streams it) at 640x480, 1280x720
and 1920x1080, in YUYV and in MJPEG, each run in a process of its own:

- bare: ``cv2.VideoCapture(device, cv2.CAP_V4L2)`` set to the format, size and rate, and a
  ``cap.read()`` loop, which gives BGR images (OpenCV converts YUYV and decodes MJPEG), with
  each frame's capture time read (``CAP_PROP_POS_MSEC``, the driver's buffer time), as
  py_vision reads it for the frame's stamp;
- py_vision: `CaptureLoop` over `Camera.open` (negotiation, the driver's timestamps, stale and
  corrupt frame checks, loss detection, counters) handing each frame to a function that takes
  its BGR image (`Frame.bgr()`: the camera's JPEG decoded on demand), as usbcam_publisher does
  for a raw subscriber.

MJPEG is measured a second way, the camera's JPEG kept as it is (what usbcam_publisher does
for compressed subscribers only): bare with OpenCV's RGB conversion off against py_vision's
capture without ``bgr()``.

The cost is the CPU time of the thread that reads the frames (OpenCV's read and conversion,
the system calls, py_vision's own work; not the emulated camera's thread that makes the
frames, which is the device's) per frame after the first 10, at the camera's own rate. The
runs alternate bare and py_vision, 5 of each: the table gives the medians, and the median of
the ratios of each py_vision run to the bare run just before it. Prints a Markdown table and
writes bench/results/capture.json. ``--cases 640x480/mjpeg/JPEG ...`` measures some cases only,
``--runs N`` N runs of each.
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

# width, height, pixel format, rate (the highest the camera offers), what the loop keeps
CASES = [(640, 480, 'yuyv', 30.0, 'BGR'), (1280, 720, 'yuyv', 10.0, 'BGR'),
         (1920, 1080, 'yuyv', 5.0, 'BGR'), (640, 480, 'mjpeg', 30.0, 'BGR'),
         (1280, 720, 'mjpeg', 30.0, 'BGR'), (1920, 1080, 'mjpeg', 30.0, 'BGR'),
         (640, 480, 'mjpeg', 30.0, 'JPEG'), (1280, 720, 'mjpeg', 30.0, 'JPEG'),
         (1920, 1080, 'mjpeg', 30.0, 'JPEG')]
WARMUP = 10
SECONDS = 4.0        # of measured reading at 30 fps; more frames' worth at lower rates
MIN_FRAMES = 40
RUNS = 5

WORKER = r"""
import json, sys, threading, time
import cv2
cv2.setNumThreads(1)   # as usbcam_publisher runs it
device, width, height, fmt, fps, frames, mode, output = sys.argv[1:9]
width, height, fps, frames = int(width), int(height), float(fps), int(frames)
WARMUP = %d


def cpu():
    return time.thread_time()   # of the thread that reads the frames


marks = []


def frame_seen():
    marks.append((time.monotonic(), cpu()))


if mode == 'bare':
    cap = cv2.VideoCapture(device, cv2.CAP_V4L2)
    cap.set(cv2.CAP_PROP_FOURCC, cv2.VideoWriter_fourcc(*('MJPG' if fmt == 'mjpeg' else 'YUYV')))
    if output == 'JPEG':
        cap.set(cv2.CAP_PROP_CONVERT_RGB, 0)
    cap.set(cv2.CAP_PROP_FRAME_WIDTH, width)
    cap.set(cv2.CAP_PROP_FRAME_HEIGHT, height)
    cap.set(cv2.CAP_PROP_FPS, fps)
    kept = None
    while len(marks) < WARMUP + frames:
        ok, kept = cap.read()
        if ok:
            stamp = cap.get(cv2.CAP_PROP_POS_MSEC)   # the capture time, as py_vision reads it
            frame_seen()
    cap.release()
else:
    from py_vision.capture import Camera, CaptureLoop
    done = threading.Event()

    class Log:
        def info(self, text): pass
        def warning(self, text): print(text, file=sys.stderr)
        error = warning

    def on_frame(camera, frame):
        if output == 'BGR':
            frame.bgr()
        frame_seen()
        if len(marks) >= WARMUP + frames:
            done.set()
    loop = CaptureLoop(lambda: Camera.open(device, width, height, fps, fmt), on_frame, Log())
    loop.start()
    done.wait(120)
    loop.close()
(t0, c0), (t1, c1) = marks[WARMUP - 1], marks[-1]
count = len(marks) - WARMUP
print(json.dumps({'frames': count, 'cpu_ms_per_frame': 1e3 * (c1 - c0) / count,
                  'fps': count / (t1 - t0)}))
""" % WARMUP


def run(camera, env, width, height, fmt, fps, output, mode):
    frames = max(MIN_FRAMES, int(SECONDS * fps))
    out = subprocess.run(
        [sys.executable, '-c', WORKER, camera.device, str(width), str(height), fmt, str(fps),
         str(frames), mode, output], env=env, capture_output=True, text=True, timeout=180)
    if out.returncode != 0:
        raise RuntimeError('%s run failed: %s' % (mode, out.stderr))
    return json.loads(out.stdout.splitlines()[-1])


def main():
    parser = argparse.ArgumentParser(description=__doc__.split('\n\n')[0])
    parser.add_argument('--quick', action='store_true', help='one run of each')
    parser.add_argument('--runs', type=int, default=RUNS, help='runs of each (%d)' % RUNS)
    parser.add_argument('--cases', nargs='+', metavar='SIZE/FORMAT/KEPT',
                        help='only these cases, e.g. 640x480/mjpeg/JPEG 1280x720/yuyv/BGR')
    args = parser.parse_args()
    runs = 1 if args.quick else args.runs
    cases = CASES
    if args.cases:
        names = {'%dx%d/%s/%s' % (case[:3] + (case[4],)): case for case in CASES}
        unknown = [name for name in args.cases if name not in names]
        if unknown:
            parser.error('no case %s; the cases: %s' % (', '.join(unknown), ' '.join(names)))
        cases = [names[name] for name in args.cases]
    state = tempfile.mkdtemp(prefix='bench_capture_')
    camera = EmulatedCamera(state, 'webcam_1080p', 60)
    env = camera.env(dict(os.environ, PYTHONPATH=os.pathsep.join(
        [str(REPO / 'py_vision'), os.environ.get('PYTHONPATH', '')])))
    rows = []
    try:
        for width, height, fmt, fps, output in cases:
            results = {'bare': [], 'py_vision': []}
            for _ in range(runs):
                for mode in results:
                    results[mode].append(
                        run(camera, env, width, height, fmt, fps, output, mode))
            bare = statistics.median(r['cpu_ms_per_frame'] for r in results['bare'])
            ours = statistics.median(r['cpu_ms_per_frame'] for r in results['py_vision'])
            # Each py_vision run against the bare run just before it: the machine's load
            # drifts less between the two than over the whole benchmark.
            ratio = statistics.median(
                ours_run['cpu_ms_per_frame'] / bare_run['cpu_ms_per_frame']
                for bare_run, ours_run in zip(results['bare'], results['py_vision']))
            rows.append({'size': '%dx%d' % (width, height), 'format': fmt.upper(), 'fps': fps,
                         'output': output,
                         'bare_ms': bare, 'py_vision_ms': ours, 'ratio': ratio,
                         'measured_fps': statistics.median(
                             r['fps'] for r in results['py_vision']),
                         'runs': results})
            print('%s %s %s done' % (rows[-1]['size'], rows[-1]['format'], output),
                  file=sys.stderr)
    finally:
        camera.close()
        shutil.rmtree(state, ignore_errors=True)
    print('| size | format | fps | frames kept as | bare cv2 read, ms CPU/frame | '
          'py_vision capture, ms CPU/frame | ratio |')
    print('|---|---|---|---|---|---|---|')
    for row in rows:
        print('| %s | %s | %g | %s | %.3f | %.3f | %.2f |' % (
            row['size'], row['format'], row['fps'], row['output'], row['bare_ms'],
            row['py_vision_ms'], row['ratio']))
    save_results('capture', {'cases': rows, 'runs_each': runs})


if __name__ == '__main__':
    main()
