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
One run of bench_capture.py: read a camera one way and print what a frame cost.

  capture_worker.py DEVICE WIDTH HEIGHT FOURCC FPS FRAMES WARMUP WAY

WAY is 'bare' (V4L2 ioctls, no conversion), 'opencv' or 'opencv jpeg' (cv2.VideoCapture with
or without its conversion), 'py_vision' or 'py_vision jpeg' (the capture loop, the frame as
BGR or the camera's JPEG), or 'bgr8 published' / 'native published' (the capture loop and the
publisher's image topic). Prints one JSON line: frames, CPU ms per frame of the thread reading
them (after WARMUP frames), fps.
"""

import json
import sys
import threading
import time

import cv2

cv2.setNumThreads(1)   # as usbcam_publisher runs it


def read_bare(device, width, height, fourcc, fps, count, frame_seen):
    """Dequeue and queue buffers with the tests' V4L2 ioctls: the floor."""
    import v4l2_ioctl
    fd = v4l2_ioctl.open_device(device)
    stream = v4l2_ioctl.Stream(fd, fourcc, width, height, interval=(1, int(fps)))
    for _ in range(count):
        stream.queue(stream.dequeue()['index'])
        frame_seen()
    stream.close()


def read_opencv(device, width, height, fourcc, fps, count, frame_seen, jpeg):
    """Read with OpenCV's V4L2 backend, stamping each frame as a node does."""
    cap = cv2.VideoCapture(device, cv2.CAP_V4L2)
    cap.set(cv2.CAP_PROP_FOURCC, cv2.VideoWriter_fourcc(*fourcc))
    if jpeg:
        cap.set(cv2.CAP_PROP_CONVERT_RGB, 0)
    cap.set(cv2.CAP_PROP_FRAME_WIDTH, width)
    cap.set(cv2.CAP_PROP_FRAME_HEIGHT, height)
    cap.set(cv2.CAP_PROP_FPS, fps)
    seen = 0
    while seen < count:
        ok, _ = cap.read()
        if ok:
            cap.get(cv2.CAP_PROP_POS_MSEC)   # the capture time, as a node stamps it
            frame_seen()
            seen += 1
    cap.release()


class _Log:
    """The capture loop's logger: warnings and errors to stderr."""

    def info(self, text):
        pass

    def warning(self, text):
        print(text, file=sys.stderr)

    error = warning


def read_py_vision(device, width, height, fourcc, fps, count, frame_seen, way):
    """Read with py_vision's capture loop, keeping each frame as `way` says."""
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
    seen = []

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
        seen.append(None)
        if len(seen) >= count:
            done.set()
    loop = CaptureLoop(lambda: Camera.open(device, width, height, fps, fourcc), on_frame, _Log())
    loop.start()
    done.wait(120)
    loop.close()


def main():
    device, width, height, fourcc, fps, frames, warmup, way = sys.argv[1:9]
    width, height, fps, frames, warmup = int(width), int(height), float(fps), int(frames), \
        int(warmup)
    marks = []

    def frame_seen():
        marks.append((time.monotonic(), time.thread_time()))   # of the thread reading frames
    count = warmup + frames
    if way == 'bare':
        read_bare(device, width, height, fourcc, fps, count, frame_seen)
    elif way.startswith('opencv'):
        read_opencv(device, width, height, fourcc, fps, count, frame_seen, way == 'opencv jpeg')
    else:
        read_py_vision(device, width, height, fourcc, fps, count, frame_seen, way)
    (t0, c0), (t1, c1) = marks[warmup - 1], marks[-1]
    measured = len(marks) - warmup
    print(json.dumps({'frames': measured, 'cpu_ms_per_frame': 1e3 * (c1 - c0) / measured,
                      'fps': measured / (t1 - t0)}))


if __name__ == '__main__':
    main()
