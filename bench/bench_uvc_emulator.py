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
Benchmark the emulated UVC camera: the CPU a process streaming from it pays per frame.

Run from the repository root: ``.venv/bin/python bench/bench_uvc_emulator.py``. A child process
with the emulator streams each mode for a few seconds through mmap buffers (DQBUF, copy the
bytes out, QBUF). Measured: the CPU time the library spends making each frame (its frame
thread's own clock, which it adds up in the camera's state), and the whole child's CPU share
(getrusage: that plus the reading loop). The reference, measured in the same run, is what a
frame costs made plainly: cv2.imencode of the whole frame for MJPEG, a numpy copy of the
frame for YUYV. Prints a Markdown table and writes bench/results/uvc_emulator.json.
"""

import json
import os
import statistics
import subprocess
import sys
import tempfile
import time

from bench_common import save_results, TESTS
import cv2
import emulated_camera
import ros_harness

MODES = [('MJPG', 1920, 1080, 30), ('MJPG', 1280, 720, 30), ('MJPG', 640, 480, 30),
         ('YUYV', 1920, 1080, 5), ('YUYV', 640, 480, 30)]
SECONDS = 3.0
CHILD = """
import json, os, resource, struct, sys, time
import v4l2_ioctl as v4l2
state = os.path.join(os.environ['PY_VISION_UVC_CAMERAS'], 'state')

def counters():  # frames served, ns spent making frames: the camera's shared state
    with open(state, 'rb') as f:
        data = f.read(328)
    return struct.unpack_from('Q', data, 56)[0], struct.unpack_from('Q', data, 320)[0]

code, width, height, fps, seconds = json.loads(sys.argv[1])
fd = v4l2.open_device('/dev/video40')
stream = v4l2.Stream(fd, code, width, height, interval=(1, fps))
stream.read()  # the first frame of a size also encodes its background
before, start, sizes = resource.getrusage(resource.RUSAGE_SELF), time.monotonic(), []
served, made = counters()
while time.monotonic() - start < seconds:
    sizes.append(len(stream.read()[1]))
after, end = resource.getrusage(resource.RUSAGE_SELF), time.monotonic()
served_after, made_after = counters()
cpu = after.ru_utime + after.ru_stime - before.ru_utime - before.ru_stime
print(json.dumps({'frames': len(sizes), 'seconds': end - start, 'cpu': cpu,
                  'render_ms': (made_after - made) / 1e6 / max(1, served_after - served),
                  'size': sorted(sizes)[len(sizes) // 2]}))
"""


def reference_ms(code, width, height):
    """Return the median ms of what one frame costs done plainly (whole encode or a copy)."""
    frame = cv2.cvtColor(emulated_camera.expected_yuyv(1, width, height),
                         cv2.COLOR_YUV2BGR_YUYV)
    yuyv = emulated_camera.expected_yuyv(1, width, height)
    times = []
    for _ in range(15):
        start = time.perf_counter()
        if code == 'MJPG':
            cv2.imencode('.jpg', frame, [cv2.IMWRITE_JPEG_QUALITY, emulated_camera.JPEG_QUALITY])
        else:
            yuyv.copy()
        times.append((time.perf_counter() - start) * 1000)
    return statistics.median(times)


def main():
    state = tempfile.mkdtemp(prefix='bench_uvc_')
    camera = emulated_camera.EmulatedCamera(state, 'webcam_1080p')
    env = camera.env(dict(os.environ, PYTHONPATH=os.pathsep.join(
        [str(TESTS), str(ros_harness.SITE_PACKAGES)])))
    rows = []
    try:
        for code, width, height, fps in MODES:
            out = subprocess.run(
                [sys.executable, '-c', CHILD, json.dumps([code, width, height, fps, SECONDS])],
                env=env, capture_output=True, text=True, timeout=60)
            if out.returncode != 0:
                raise SystemExit(out.stderr)
            got = json.loads(out.stdout)
            per_frame = got['render_ms']
            reference = reference_ms(code, width, height)
            rows.append({'mode': '%s %dx%d @ %d' % (code, width, height, fps),
                         'fps': got['frames'] / got['seconds'],
                         'cpu_percent': 100 * got['cpu'] / got['seconds'],
                         'ms_per_frame': per_frame, 'reference_ms': reference,
                         'ratio': per_frame / reference, 'frame_bytes': got['size']})
    finally:
        camera.close()
        os.rmdir(state)
    print('| mode | frames/s | child CPU (% of a core) | emulator CPU per frame |'
          ' reference per frame | × reference | frame bytes |')
    print('|---|---:|---:|---:|---:|---:|---:|')
    for r in rows:
        print('| %s | %.1f | %.1f | %.2f ms | %.2f ms | %.2f | %d |' % (
            r['mode'], r['fps'], r['cpu_percent'], r['ms_per_frame'], r['reference_ms'],
            r['ratio'], r['frame_bytes']))
    save_results('uvc_emulator', {'seconds_per_mode': SECONDS, 'rows': rows,
                                  'reference': 'MJPG: cv2.imencode of the whole frame; '
                                               'YUYV: a numpy copy of the frame'})


if __name__ == '__main__':
    main()
