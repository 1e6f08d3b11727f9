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
usbcam_subscriber: receive usb_camera/image, convert it with the bridge and show it.

The ROS 2 port of the tutorial's subscriber. It hears reliable and best-effort publishers,
shows any encoding the bridge knows (in an OpenCV window or a browser), logs the received
rate and latency, and survives malformed images with a rate-limited error.
"""

from py_vision.cv_bridge import CvBridge, CvBridgeError, cvtColorForDisplay
from py_vision.display import window_unavailable_reason, WindowDisplay
from py_vision.node_main import ConfigError, main_for
from py_vision.params import Parameters
from py_vision.qos import ImageSubscription
from py_vision.stats import StreamStats
from py_vision.synthetic_camera import read_frame_index
from py_vision.web_viewer import WebViewer, WebViewerError
from rclpy.node import Node
from rclpy.time import Time
from sensor_msgs.msg import Image

DISPLAYS = ('auto', 'window', 'web', 'none')
WEB_STATS_PERIOD_S = 1.0


class VideoSubscriber(Node):
    NODE_NAME = 'usbcam_subscriber'

    def __init__(self):
        super().__init__(self.NODE_NAME)
        params = Parameters(self)
        display = params.declare(
            'display', 'auto', 'where to show frames', check=DISPLAYS.__contains__,
            accepted=', '.join(DISPLAYS))
        web_host = params.declare(
            'web_host', '127.0.0.1', 'address the browser viewer listens on', check=bool,
            accepted='an IP address or host name')
        web_port = params.declare(
            'web_port', 8080, 'port of the browser viewer', check=lambda v: 0 <= v <= 65535,
            accepted='0..65535 (0: any free port)')
        self.stats_period = params.declare(
            'stats_period', 5.0, 'seconds between statistics log lines',
            check=lambda v: 0 < v <= 3600, accepted='a number > 0 and <= 3600',
            on_change=self._set_stats_period)

        self.bridge_ = CvBridge()
        self.stats = StreamStats(window_s=self.stats_period)
        self.window = None
        self.viewer = None
        self._errors_reported = 0
        self._last_error = ''
        self._open_display(display, web_host, web_port)
        self.subscription_ = ImageSubscription(self, Image, 'usb_camera/image', self.callback)
        self._stats_timer = self.create_timer(self.stats_period, self.report_stats)
        if self.viewer is not None:
            self.create_timer(WEB_STATS_PERIOD_S, self._update_web_stats)

    def _open_display(self, display, web_host, web_port):
        if display in ('auto', 'window'):
            reason = window_unavailable_reason()
            if reason is None:
                self.window = WindowDisplay()
                self.get_logger().info('showing frames in an OpenCV window')
                return
            if display == 'window':
                self.get_logger().warning(
                    'display:=window is not possible: %s; showing statistics only '
                    '(display:=web shows the stream in a browser)' % reason)
                return
            display = 'web'
        if display == 'web':
            self.viewer = WebViewer(web_host, web_port, title='py_vision: usb_camera/image',
                                    logger=self.get_logger())
            try:
                self.viewer.start()
            except WebViewerError as error:
                self.viewer = None
                raise ConfigError('parameter web_port: %s' % error)
            self.get_logger().info('browser viewer at %s' % self.viewer.url)

    def _set_stats_period(self, period):
        self.stats_period = period
        self.stats.window_s = period
        self._stats_timer.cancel()
        self._stats_timer = self.create_timer(period, self.report_stats)

    def callback(self, msg):
        latency = (self.get_clock().now() - Time.from_msg(msg.header.stamp)).nanoseconds / 1e9
        try:
            image = self.bridge_.imgmsg_to_cv2(msg)
            shown = image if msg.encoding == 'bgr8' else None
            if shown is None and (self.window is not None or self.viewer is not None):
                # Depth and other float images are scaled to their range, as image viewers do.
                shown = cvtColorForDisplay(image, msg.encoding, 'bgr8',
                                           do_dynamic_scaling=image.dtype.kind == 'f')
        except CvBridgeError as error:
            self._bad_message(msg, error)
            return
        self.stats.add(latency, msg.width, msg.height, msg.encoding,
                       read_frame_index(image) if msg.encoding == 'bgr8' else None)
        if self.window is not None:
            self.window.show(shown)
        if self.viewer is not None:
            self.viewer.submit(shown)

    def _bad_message(self, msg, error):
        self.stats.add_error()
        self._last_error = 'cannot show a %dx%d "%s" image: %s' % (
            msg.width, msg.height, msg.encoding, error)
        if self.stats.errors == 1:
            # The first one is reported at once; later ones in the periodic summary.
            self._errors_reported = 1
            self.get_logger().error(self._last_error)

    def report_stats(self):
        """Log one line: what arrived in the last period, and any problems."""
        s = self.stats.snapshot()
        topic = self.subscription_.topic_name
        if s['latency_ms_p50'] is None:
            self.get_logger().info('no frames on %s in the last %.3g s (%d received in total)' % (
                topic, self.stats_period, s['frames']))
        else:
            gap = ''
            if s['longest_gap_s'] > max(1.0, 5.0 / max(s['fps'], 1e-3)):
                gap = ', gap of %.2f s' % s['longest_gap_s']
            self.get_logger().info(
                'received %d frames (%.1f fps), latency p50 %.1f ms p99 %.1f ms, lost %d, '
                '%dx%d %s on %s%s' % (
                    s['frames'], s['fps'], s['latency_ms_p50'], s['latency_ms_p99'], s['lost'],
                    s['width'], s['height'], s['encoding'], topic, gap))
        self.stats.reset_gap()
        new_errors = self.stats.errors - self._errors_reported
        if new_errors > 0:
            self._errors_reported = self.stats.errors
            self.get_logger().error(
                '%d malformed image(s) dropped in the last %.3g s; last: %s' % (
                    new_errors, self.stats_period, self._last_error))

    def _update_web_stats(self):
        stats = self.stats.snapshot()
        stats['topic'] = self.subscription_.topic_name
        self.viewer.set_stats(stats)

    def close(self):
        """Close the window or the browser viewer (releasing its port)."""
        if self.window is not None:
            self.window.close()
        if self.viewer is not None:
            self.viewer.close()


main = main_for(VideoSubscriber)


if __name__ == '__main__':
    main()
