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
usbcam_subscriber: receive usb_camera/image (raw or compressed) and show it.

The ROS 2 port of the tutorial's subscriber. It hears reliable and best-effort publishers,
shows any encoding the bridge knows (in an OpenCV window or a browser), logs the received
rate and latency, and survives malformed images with a rate-limited error. With
``image_transport:=compressed`` it reads usb_camera/image/compressed instead, and the browser
viewer forwards the JPEG bytes it receives without decoding them. With ``foxglove`` (or
``h264``, ``h265``) it reads a camera's own video (transport.VideoPublisher): the browser
viewer's page decodes it itself, and it is decoded here only for a window (viewer.display).
"""

import cv2
import numpy as np
from py_vision import dds
from py_vision.annexb import inspect
from py_vision.cv_bridge import CvBridge, CvBridgeError, cvtColorForDisplay
from py_vision.diagnostics import Diagnostics, OK, Recent, Status, WARN
from py_vision.node_main import main_for
from py_vision.params import ConfigError, Parameters, Spec, viewer_specs
from py_vision.stats import gap_worth_saying, stamp_age_s, StreamStats
from py_vision.transport import (
    jpeg_size, MAX_IMAGE, subscribe, TRANSPORTS, video_fields, VIDEO_TRANSPORTS)
from py_vision.viewer.display import Display, DISPLAYS
from rclpy.node import Node

DEPTH_ENCODINGS = ('16UC1', '16SC1')
IMAGE_TOPIC = 'usb_camera/image'
# A video message's format -> the codec it holds (CompressedVideo says h265, V4L2 HEVC).
VIDEO_CODECS = {'h264': 'h264', 'h265': 'hevc', 'hevc': 'hevc'}


class VideoSubscriber(Node):
    """The viewer node (node_main.NodeProgram): shows a topic's frames, logs rate and latency."""

    NODE_NAME = 'usbcam_subscriber'
    COMMANDS = {}
    PUBLISHES = dds.NO_IMAGES
    IMAGE_INPUT = IMAGE_TOPIC
    SUMMARY = ('Shows the frames of usb_camera/image (remap it to watch another topic) in an '
               'OpenCV window or a browser, and logs their rate and latency.')
    PARAMETERS = viewer_specs('auto', DISPLAYS) + (
        Spec('stats_period', 5.0, 'seconds between statistics log lines', (0.0, 3600.0),
             check=lambda v: v > 0, accepted='a number > 0 and <= 3600', live=True),
        Spec('image_transport', 'raw', 'raw: sensor_msgs/Image on the topic; compressed: '
             "sensor_msgs/CompressedImage on <topic>/compressed; foxglove: a camera's "
             'H.264 as foxglove_msgs/CompressedVideo on <topic>/foxglove; h264, h265: as '
             'sensor_msgs/CompressedImage on <topic>/h264 or /h265',
             choices=TRANSPORTS + VIDEO_TRANSPORTS),
        MAX_IMAGE,
    )

    # What close() finds when start-up was interrupted before they were made.
    display = subscription_ = None
    failed = False   # it never stops of an error of its own

    def __init__(self):
        super().__init__(self.NODE_NAME)
        params = Parameters(self)
        values = {spec.name: params.declare(
            spec, self._set_stats_period if spec.name == 'stats_period' else None)
            for spec in self.PARAMETERS}
        self.stats_period = values['stats_period']
        self.bridge_ = CvBridge()
        self.stats = StreamStats(window_s=self.stats_period)
        self._errors_reported = 0
        self._last_error = ''
        transport = values['image_transport']
        self._video_size = (0, 0)     # of the newest SPS seen
        self.display = Display(self.get_logger(), values['display'], values['web_host'],
                               values['web_port'], IMAGE_TOPIC, values['web_token'])
        callback = {'compressed': self.on_compressed, 'raw': self.callback}.get(
            transport, self.on_video)
        try:
            self.subscription_ = subscribe(self, IMAGE_TOPIC, transport, callback,
                                           max_image_mb=values['max_image_mb'])
        except ValueError as error:
            raise ConfigError(str(error))
        self._stats_timer = self.create_timer(self.stats_period, self.report_stats)
        self.display.attach(self, self.stats, self.subscription_.topic_name,
                            camera_topic=self.subscription_.topic_name)
        self._recent = Recent()
        self.diagnostics = Diagnostics(params, hardware_id=self.subscription_.topic_name)
        self.diagnostics.add('stream', self.stream_status)

    def _set_stats_period(self, period):
        self.stats_period = period
        self.stats.window_s = period
        self.destroy_timer(self._stats_timer)
        self._stats_timer = self.create_timer(period, self.report_stats)

    def _latency(self, msg):
        return stamp_age_s(self.get_clock().now().nanoseconds, msg.header.stamp)

    def callback(self, msg):
        """Show one sensor_msgs/Image (on the subscription's receive thread)."""
        latency = self._latency(msg)
        try:
            image = self.bridge_.imgmsg_to_cv2(msg)
            shown = image if msg.encoding == 'bgr8' else None
            if shown is None and self.display.active:
                # Depth images (float, or 16UC1 in millimetres) are scaled to the range they
                # hold, as image viewers do; mono16 and colour images keep their full range.
                depth = image.dtype.kind == 'f' or msg.encoding in DEPTH_ENCODINGS
                shown = cvtColorForDisplay(image, msg.encoding, 'bgr8',
                                           do_dynamic_scaling=depth)
        except CvBridgeError as error:
            self._bad_message(msg.width, msg.height, '"%s" image' % msg.encoding, error)
            return
        self.stats.add(latency, msg.width, msg.height, msg.encoding)
        if shown is not None:
            self.display.show(shown)

    def on_compressed(self, msg):
        """Show one sensor_msgs/CompressedImage, decoding it only where pixels are needed."""
        latency = self._latency(msg)
        data = np.frombuffer(msg.data, np.uint8)
        size = jpeg_size(data)
        is_jpeg = size is not None
        image = None
        if not is_jpeg or self.display.needs_pixels:
            image = cv2.imdecode(data, cv2.IMREAD_COLOR) if data.size else None
            if image is None:
                self._bad_message(0, 0, 'compressed image (format "%s", %d bytes)' % (
                    msg.format, data.size), 'it does not decode as JPEG or PNG')
                return
            size = (image.shape[1], image.shape[0])
        if self.display.active:
            if is_jpeg:
                self.display.show_jpeg(data, image)
            else:
                self.display.show(image)  # a PNG: the viewer encodes it
        self.stats.add(latency, size[0], size[1], msg.format.split(';')[0] or 'jpeg')

    def on_video(self, msg):
        """Show one access unit of a camera's H.264 or HEVC (CompressedVideo, CompressedImage)."""
        stamp, _, video_format = video_fields(msg)
        latency = stamp_age_s(self.get_clock().now().nanoseconds, stamp)
        codec = VIDEO_CODECS.get(video_format)
        unit = bytes(msg.data)
        info = inspect(unit, codec) if codec is not None else None
        if info is None or not info.nal_types:
            self._bad_message(0, 0, 'video message (format "%s", %d bytes)' % (
                video_format, len(unit)), 'it is not H.264 or HEVC in Annex B form' if
                codec is None else 'it holds no NAL unit')
            return
        if info.width:
            self._video_size = (info.width, info.height)
        self.stats.add(latency, self._video_size[0], self._video_size[1], video_format)
        if self.display.active:
            self.display.show_video(unit, info, codec)

    def _bad_message(self, width, height, what, error):
        self.stats.add_error()
        self._last_error = 'cannot show a %dx%d %s: %s' % (width, height, what, error)
        if self.stats.errors == 1:
            # The first one is reported at once; later ones in the periodic summary.
            self._errors_reported = 1
            self.get_logger().error(self._last_error)

    def report_stats(self):
        """Log one line: frames received so far, rate and latency lately, and any problems."""
        s = self.stats.snapshot()
        topic = self.subscription_.topic_name
        if not s['recent_frames']:
            self.get_logger().info('no frames on %s in the last %.3g s (%d received in total)' % (
                topic, self.stats_period, s['frames']))
        else:
            longest = gap_worth_saying(s)
            gap = '' if longest is None else ', gap of %.2f s' % longest
            rate = ('%.1f fps' % s['fps']) if s['fps'] > 0 else 'rate not measured yet'
            latency = 'without a stamp (no latency)'
            if s['latency_ms_p50'] is not None:
                latency = 'latency p50 %.1f ms p99 %.1f ms' % (
                    s['latency_ms_p50'], s['latency_ms_p99'])
            self.get_logger().info('received %d frames (%s), %s, %dx%d %s on %s%s' % (
                s['frames'], rate, latency, s['width'], s['height'], s['encoding'], topic, gap))
        self.stats.reset_gap()
        new_errors = self.stats.errors - self._errors_reported
        if new_errors > 0:
            self._errors_reported = self.stats.errors
            self.get_logger().error(
                '%d malformed image(s) dropped in the last %.3g s; last: %s' % (
                    new_errors, self.stats_period, self._last_error))

    def stream_status(self):
        """Return the received stream's status for /diagnostics: rate, latency, unshowable."""
        s = self.stats.snapshot()
        recent = self._recent.update(frames=s['frames'], errors=s['errors'])
        return stream_status(s, recent['errors'], self.subscription_.topic_name)

    def close(self):
        """Stop taking frames, close the window or the browser viewer (releasing its port)."""
        if self.subscription_ is not None:
            self.subscription_.close()
        if self.display is not None:
            self.display.close()


def stream_status(snapshot: dict, recent_errors: int, topic: str) -> Status:
    """
    Return the status "<node>: stream" for a StreamStats snapshot.

    recent_errors is how many frames could not be shown lately (Recent). A rate needs two
    frames in the window: with one (the first frame, or a stream slower than the window) the
    status says the rate is not measured yet instead of claiming 0 fps.
    """
    s = snapshot
    values = {'topic': topic, 'frame rate': float(s['fps']),
              'latency p50 ms': s['latency_ms_p50'], 'latency p99 ms': s['latency_ms_p99'],
              'frames': s['frames'], 'not shown': s['errors'],
              'size': '%dx%d' % (s['width'], s['height']), 'encoding': s['encoding']}
    if recent_errors:
        return Status(WARN, '%d frame(s) could not be shown lately' % recent_errors, values)
    if not s['recent_frames']:
        what = 'no frames on %s lately' if s['frames'] else 'waiting for frames on %s'
        return Status(WARN, what % topic, values)
    if s['fps'] <= 0:
        return Status(OK, 'receiving on %s, one frame lately: rate not measured yet' % topic,
                      values)
    return Status(OK, 'receiving %.1f fps' % s['fps'], values)


main = main_for(VideoSubscriber)


if __name__ == '__main__':
    main()
