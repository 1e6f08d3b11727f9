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
The floor of a camera driver in Python: the least a loop does per frame, nothing else.

Usage: camera_floor.py DEVICE WIDTH HEIGHT FPS OUTPUT (bgr8 or native: YUYV as yuv422_yuy2)
A bare rclpy node with py_vision's Fast DDS profile (tailored as usbcam_publisher's) and one
loop: wait for a V4L2 frame and take it (py_vision's V4L2Source: poll, VIDIOC_DQBUF and QBUF),
convert it into the serialized Image (native: the camera captured it into the message itself,
V4L2 USERPTR, as the node does where the driver allows; else it is copied there), write the
stamp, publish it, publish the CameraInfo with the same stamp (py_vision.serialized and
serialized_publisher). No
parameters, no executor, no checks, no statistics, no recovery: what usbcam_publisher costs
above this is the node's own. Prints FIRST_FRAME_MARK once publishing and stops on
SIGINT/SIGTERM.
"""

import sys
import time

from bench_common import announce_first_frame, StopFlag
from py_vision import dds


def main():
    device, width, height, fps, output = sys.argv[1:6]
    width, height, fps = int(width), int(height), float(fps)
    dds.use_packaged_profile(dds.OWN_SIZE, ['-p', 'image_width:=%d' % width,
                                            '-p', 'image_height:=%d' % height],
                             'camera_floor', image_topics=())
    import cv2
    from py_vision.capture.pixel_formats import FORMATS
    from py_vision.capture.v4l2_stream import V4L2Source
    from py_vision.serialized import SerializedImage, SerializedStamped
    from py_vision.serialized_publisher import SerializedPublisher
    import rclpy
    from rclpy.signals import SignalHandlerOptions
    from sensor_msgs.msg import CameraInfo, Image
    from std_msgs.msg import Header
    cv2.setNumThreads(1)
    rclpy.init(args=sys.argv[6:], signal_handler_options=SignalHandlerOptions.NO)
    stop = StopFlag()
    node = rclpy.create_node('camera_floor')
    images = SerializedPublisher(node.create_publisher(Image, 'usb_camera/image', 10))
    infos = SerializedPublisher(node.create_publisher(CameraInfo, 'usb_camera/camera_info', 10))
    source = V4L2Source(device)
    source.configure(FORMATS['YUYV'], width, height, fps)
    messages = []
    if output != 'bgr8':
        messages = [SerializedImage(source.buffer_bytes) for _ in range(4)]
        source.capture_into([message.pixels() for message in messages])
    source.start()
    header = Header(frame_id='usb_camera')
    info = CameraInfo(header=header, width=width, height=height)
    image, info_bytes = SerializedImage(), SerializedStamped()
    encoding, channels = ('bgr8', 3) if output == 'bgr8' else ('yuv422_yuy2', 2)
    image.prepare(header, height, width, encoding, width * channels)
    out = image.data().reshape(height, width, channels)
    announced = False
    try:
        while not stop.is_set():
            frame = source.next_frame()
            if frame is None or frame.data is None or frame.corrupt:
                continue
            header.stamp.sec, header.stamp.nanosec = divmod(time.time_ns(), 1000000000)
            if frame.user_buffer is not None:
                message = messages[frame.user_buffer]
            else:
                message = image
                view = frame.data.reshape(height, width, 2)
                if channels == 3:
                    cv2.cvtColor(view, cv2.COLOR_YUV2BGR_YUYV, dst=out)
                else:
                    out[...] = view
            message.prepare(header, height, width, encoding, width * channels)
            images.publish_at(*message.where())
            infos.publish_at(*info_bytes.stamp(info))
            if not announced:
                announce_first_frame()
                announced = True
    finally:
        source.release()
        node.destroy_node()
        rclpy.try_shutdown()


if __name__ == '__main__':
    main()
