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
cv_bridge_test: the processing step of the second tutorial, ported to ROS 2.

Every image from usb_camera/image (or usb_camera/image/compressed with
``image_transport:=compressed``) is converted to an OpenCV bgr8 image with the bridge, gets
a red filled circle at (60, 60) with radius 30 when it is larger than 60x60, and goes out on
cv_bridge_image with the header it came with (and, while it has subscribers, as JPEG on
cv_bridge_image/compressed). A message the bridge cannot convert is logged
(at most once per ERROR_LOG_PERIOD_S) and skipped; the node keeps going. With `display` set,
the processed frames are also shown, like the subscriber shows its own.

The processing runs on a LatestFrameWorker, not in the subscription callback: a step slower
than the camera (`simulated_work_ms` makes one) works on the newest frame and counts the ones
it skips, instead of working through a backlog of old frames. docs/processing.md explains it.
"""

import threading
import time
from typing import Callable, Optional

import cv2
import numpy as np
from py_vision import dds
from py_vision.cv_bridge import CvBridge, CvBridgeError
from py_vision.diagnostics import Diagnostics, OK, Recent, Status, WARN
from py_vision.latest_frame import LatestFrameWorker
from py_vision.node_main import main_for
from py_vision.params import Parameters, Spec, viewer_specs
from py_vision.qos import publisher_qos
from py_vision.stats import stamp_age_s, StreamStats
from py_vision.transport import ImagePublisher, MAX_IMAGE, subscribe, TRANSPORTS
from py_vision.viewer.display import Display, DISPLAYS
from rclpy.node import Node
from sensor_msgs.msg import CompressedImage

CIRCLE_CENTER, CIRCLE_RADIUS, CIRCLE_BGR = (60, 60), 30, (0, 0, 255)
ERROR_LOG_PERIOD_S = 5.0
STATS_PERIOD_S = 5.0
MAX_SIMULATED_WORK_MS = 10000.0
# Skipping more than this fraction of the input lately is "cannot keep up" (WARN); a frame
# skipped now and then on a loaded machine is not.
SKIPPED_WARN_FRACTION = 0.1
# One call of the simulated work: short enough to meet its end time and notice a shutdown
# within a millisecond, long enough that the loop around it costs nothing.
_WORK_CHUNK = np.ones(65536, np.float32)


def simulated_work(seconds: float, cancelled: Callable[[], bool]) -> None:
    """
    Keep one core busy for `seconds` of wall-clock time, or until cancelled() is true.

    numpy computes with the GIL released, as OpenCV and accelerator calls do, so the node's
    other thread keeps taking messages meanwhile, as it would beside real vision code.
    """
    out = np.empty_like(_WORK_CHUNK)
    deadline = time.monotonic() + seconds
    while time.monotonic() < deadline and not cancelled():
        np.sin(_WORK_CHUNK, out=out)


class ProcessingStats:
    """The output stream's statistics and the worker's, safe to use from both threads."""

    def __init__(self, worker: LatestFrameWorker):
        self.worker = worker
        self._output = StreamStats(window_s=STATS_PERIOD_S)
        self._lock = threading.Lock()

    def add_output(self, age_s: Optional[float], width: int, height: int) -> int:
        """Record one published frame and how old it was (None: not stamped); return how many."""
        if age_s is not None:
            self.worker.record_age(age_s)
        with self._lock:
            self._output.add(age_s, width, height, 'bgr8')
            return self._output.frames

    def add_error(self) -> int:
        """Record one frame that could not be converted; return how many so far."""
        with self._lock:
            self._output.add_error()
            return self._output.errors

    def snapshot(self) -> dict:
        """Return the output's rate, latency and size, with the worker's counts and times."""
        with self._lock:
            output = self._output.snapshot()
        return dict(output, **self.worker.snapshot())


class CvBridgeTest(Node):
    """The processing node (node_main.NodeProgram): a red circle on the newest frame."""

    NODE_NAME = 'cv_bridge_test'
    COMMANDS = {}
    PUBLISHES = dds.INPUT_SIZE
    RECEIVES_IMAGES = True
    SUMMARY = ('Draws a red circle on every frame of usb_camera/image and publishes it on '
               'cv_bridge_image, always working on the newest frame.')
    PARAMETERS = viewer_specs('none', DISPLAYS) + (
        Spec('image_transport', 'raw', 'raw: sensor_msgs/Image on usb_camera/image; '
             'compressed: sensor_msgs/CompressedImage on usb_camera/image/compressed',
             choices=TRANSPORTS),
        MAX_IMAGE,
        Spec('simulated_work_ms', 0.0, 'busy processing time added to every frame, to try '
             'the pipeline with a slow step', (0.0, MAX_SIMULATED_WORK_MS), live=True),
    )

    worker = display = None  # what close() finds when start-up was interrupted
    failed = False           # it never stops of an error of its own
    _too_large_said = False  # the warning about frames larger than the segment

    def __init__(self):
        super().__init__(self.NODE_NAME)
        params = Parameters(self)
        values = {spec.name: params.declare(
            spec, self._set_simulated_work if spec.name == 'simulated_work_ms' else None)
            for spec in self.PARAMETERS}
        self.simulated_work_s = values['simulated_work_ms'] / 1e3

        self.bridge_ = CvBridge()
        self.display = Display(self.get_logger(), values['display'], values['web_host'],
                               values['web_port'], 'cv_bridge_image', values['web_token'])
        # Reliable with a queue of 10, the ROS 2 default: what the seed's rospy publisher
        # gives, and both reliable and best-effort subscribers (rqt_image_view) receive it.
        self.images = ImagePublisher(params, 'cv_bridge_image', publisher_qos(), self.bridge_,
                                     lazy_raw=False)
        self.publisher_ = self.images.raw
        # Frames can wait in three places: the subscription's DDS history, the executor
        # (which takes one message per callback) and the worker's slot. The callback only
        # offers, so the executor never falls behind; keep-last 1 means that even when it is
        # held up, DDS keeps only the newest frame for it; the slot holds one frame.
        self.worker = LatestFrameWorker(self.process, on_error=self._step_failed,
                                        window_s=STATS_PERIOD_S, name='processing')
        self.stats = ProcessingStats(self.worker)
        self.subscription_ = subscribe(self, 'usb_camera/image', values['image_transport'],
                                       self.worker.offer, depth=1,
                                       max_image_mb=values['max_image_mb'])
        self._shown_lock = threading.Lock()
        self._to_show: Optional[np.ndarray] = None
        # OpenCV windows belong to the executor's thread: the worker hands frames over.
        self._show_request = self.create_guard_condition(self._show_newest)
        self.create_timer(STATS_PERIOD_S, self.report_stats)
        # The panel shows the camera these frames come from, upstream of this node.
        self.display.attach(self, self.stats, self.publisher_.topic_name,
                            camera_topic=self.subscription_.topic_name)
        self._recent = Recent()
        self.diagnostics = Diagnostics(params, hardware_id=self.subscription_.topic_name)
        self.diagnostics.add('processing', self.processing_status)
        self.get_logger().info('drawing on images from %s, publishing them on %s%s' % (
            self.subscription_.topic_name, self.publisher_.topic_name,
            self._work_note(self.simulated_work_s)))

    @staticmethod
    def _work_note(seconds):
        return ', simulated work %g ms a frame' % (seconds * 1e3) if seconds else ''

    def _set_simulated_work(self, milliseconds):
        self.simulated_work_s = milliseconds / 1e3
        self.get_logger().info('simulated work is now %g ms a frame' % milliseconds)

    def process(self, msg):
        """Convert, draw and publish one frame (on the worker's thread)."""
        try:
            if isinstance(msg, CompressedImage):
                what = 'compressed image (format "%s")' % msg.format
                image = self.bridge_.compressed_imgmsg_to_cv2(msg, 'bgr8')
            else:
                what = '%dx%d "%s" image' % (msg.width, msg.height, msg.encoding)
                image = self.bridge_.imgmsg_to_cv2(msg, 'bgr8')
        except CvBridgeError as error:
            errors = self.stats.add_error()
            self.get_logger().error(
                'cannot convert a %s to bgr8, skipped: %s (%d skipped so far)' % (
                    what, error, errors), throttle_duration_sec=ERROR_LOG_PERIOD_S)
            return
        if self.simulated_work_s > 0:
            simulated_work(self.simulated_work_s, lambda: self.worker.closed)
            if self.worker.closed:
                return  # close() was called: the node is being torn down, drop the frame
        # The bridge returns a writable image the node owns (a view of this message's data,
        # or a converted copy), so the circle is drawn in place.
        rows, cols = image.shape[:2]
        if cols > 60 and rows > 60:
            cv2.circle(image, CIRCLE_CENTER, CIRCLE_RADIUS, CIRCLE_BGR, -1)
        self.images.publish(msg.header, lambda: image)
        age = stamp_age_s(self.get_clock().now().nanoseconds, msg.header.stamp)
        if self.stats.add_output(age, cols, rows) == 1:
            self.get_logger().info('first image: %dx%d %s' % (
                cols, rows, 'jpeg' if isinstance(msg, CompressedImage) else msg.encoding))
        if not self._too_large_said and not dds.frame_fits(image.nbytes):
            self._too_large_said = True
            self.get_logger().warning(
                '%dx%d frames do not fit the shared memory this node sized at start-up for '
                "the camera's default size: same-host subscribers get them late or not at "
                'all; start it with -p image_width:=%d -p image_height:=%d (or the '
                "camera's parameter file)" % (cols, rows, cols, rows))
        if self.display.active:
            with self._shown_lock:
                self._to_show = image
            self._show_request.trigger()

    def _show_newest(self):
        with self._shown_lock:
            image, self._to_show = self._to_show, None
        if image is not None:
            self.display.show(image)

    def _step_failed(self, error):
        self.get_logger().error('processing a frame failed: %s: %s' % (
            type(error).__name__, error), throttle_duration_sec=ERROR_LOG_PERIOD_S)

    def report_stats(self):
        """Log one line: frames in, processed, skipped, processing time and output age."""
        s = self.stats.snapshot()
        line = 'frames in %d, processed %d, skipped %d' % (
            s['frames_in'], s['processed'], s['skipped'])
        if s['processing_ms_p50'] is not None:
            line += ', processing p50 %.1f ms p99 %.1f ms' % (
                s['processing_ms_p50'], s['processing_ms_p99'])
        if s['age_ms_p50'] is not None:
            line += ', output age p50 %.1f ms p99 %.1f ms, %.1f fps out' % (
                s['age_ms_p50'], s['age_ms_p99'], s['fps'])
        self.get_logger().info('%s on %s' % (line, self.publisher_.topic_name))

    def processing_status(self):
        """Return the processing step's status for /diagnostics; WARN when it falls behind."""
        s = self.stats.snapshot()
        recent = self._recent.update(frames_in=s['frames_in'], skipped=s['skipped'],
                                     errors=s['errors'])
        values = {'input': self.subscription_.topic_name, 'output': self.publisher_.topic_name,
                  'frames in': s['frames_in'], 'processed': s['processed'],
                  'skipped': s['skipped'], 'not converted': s['errors'],
                  'processing p50 ms': s['processing_ms_p50'],
                  'processing p99 ms': s['processing_ms_p99'],
                  'output age p50 ms': s['age_ms_p50'], 'output age p99 ms': s['age_ms_p99'],
                  'output rate': float(s['fps']),
                  'simulated work ms': self.simulated_work_s * 1e3}
        if recent['frames_in'] and recent['skipped'] > SKIPPED_WARN_FRACTION * recent['frames_in']:
            return Status(WARN, 'cannot keep up: skipped %d of the last %d frames' % (
                recent['skipped'], recent['frames_in']), values)
        if recent['errors']:
            return Status(WARN, '%d frame(s) could not be converted lately' % recent['errors'],
                          values)
        if s['processing_ms_p50'] is None:
            return Status(OK, 'no frames on %s lately' % self.subscription_.topic_name, values)
        return Status(OK, 'keeping up: processing p50 %.1f ms' % s['processing_ms_p50'],
                      values)

    def close(self):
        """Stop the worker (abandoning a step in progress), then the window or viewer."""
        if self.worker is not None:
            self.worker.close()
        if self.display is not None:
            self.display.close()


main = main_for(CvBridgeTest)


if __name__ == '__main__':
    main()
