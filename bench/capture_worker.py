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
One measured run of bench_capture.py, in a process of its own (see it for what each way does).

Arguments: device width height FOURCC fps frames way warmup. Prints one JSON line: the frames
measured, the CPU time of the thread that read them per frame (ms) and the rate they came at.
"""

import json
import sys
import threading
import time

import cv2

cv2.setNumThreads(1)   # as usbcam_publisher runs it
device, width, height, fourcc, fps, frames, way, warmup = sys.argv[1:9]
width, height, fps, frames, WARMUP = int(width), int(height), float(fps), int(frames), int(warmup)
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
        if way == 'py_vision native':
            return frame.image('native')
        if way == 'py_vision jpeg':
            return frame.jpeg
        output = way.split()[0]
        return images.publish(Header(), lambda: frame.image(output), None,
                              frame.encoding(output), None, lambda out: frame.image(output, out))

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
