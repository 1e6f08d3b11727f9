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
vision_step: runs one processing step (py_vision.steps) on the newest camera frame.

Every image from usb_camera/image (or usb_camera/image/compressed with
``image_transport:=compressed``) is converted to an OpenCV bgr8 image with the bridge and
handed to the step `-p step:=NAME` names (a built-in by short name, or the user's own
`module.path:Class`; steps/loader.py finds it). What the step returns goes out on
vision_step/image with the header the frame came with while that topic has subscribers (as
JPEG on vision_step/image/compressed while that one has); None publishes nothing. What the
step publishes itself (hand_signs' commands) goes out whoever listens. A message the bridge
cannot convert is logged (at most once per ERROR_LOG_PERIOD_S) and skipped; a step that raises
is logged once per kind of failure and period, counted and shown in /diagnostics, and its
frame_failed() is called; the node keeps going. With `display` set, the processed frames are
also shown, like the subscriber shows its own.

The processing runs on a LatestFrameWorker, not in the subscription callback: a step slower
than the camera works on the newest frame and counts the ones it skips, instead of working
through a backlog of old frames. docs/processing.md explains it. The frames are taken on the
subscription's own thread (transport.subscribe), which offers them to the worker; the
executor runs the rest. cv_bridge_test is this node running the `circle` step under its own
name and topic.

The statistics line (every STATS_PERIOD_S) and /diagnostics give a frame's processing time,
split into the time inside the step's models (their runtimes time each run on the worker's
thread: steps.api.models_clock) and the rest: converting, the step's own work, publishing.

At stop (close()), in this order: no frame is taken any more; what the step publishes
through its context from the worker thread is dropped from then on (StepPublishers); the
step's stopping() stops what it drives at once (hand_signs: its zero command), without waiting
for the frame under way; the worker is given STOP_GRACE_S to finish that frame, then abandoned
(the step is never called again); the step's close() releases what it holds; the node waits
up to DELIVERY_TIMEOUT_S for reliable subscribers to acknowledge the step's last messages;
run() destroys the node.
"""

import dataclasses
from pathlib import Path
import threading
import time
import traceback
from typing import Any, List, Optional, Sequence, Tuple

import cv2
import numpy as np
from py_vision import dds, ros_arguments
from py_vision.control_descriptor import step_constraints
from py_vision.cv_bridge import CvBridge, CvBridgeError
from py_vision.diagnostics import Diagnostics, ERROR, OK, Recent, Status, WARN
from py_vision.latest_frame import LatestFrameWorker
from py_vision.node_main import main_for
from py_vision.params import Parameters, Spec, viewer_specs
from py_vision.qos import publisher_qos
from py_vision.stats import stamp_age_s, StreamStats
from py_vision.steps import loader
from py_vision.steps.api import DELIVERY_TIMEOUT_S, models_clock, ProcessesFrames
from py_vision.steps.api import step_parameters, StepContext, STOP_GRACE_S
from py_vision.throttled_log import ThrottledLog
from py_vision.transport import ImagePublisher, MAX_IMAGE, subscribe, TRANSPORTS
from py_vision.viewer.display import Display, DISPLAYS
from rclpy.duration import Duration
from rclpy.node import Node
from sensor_msgs.msg import CompressedImage

ERROR_LOG_PERIOD_S = 5.0
STATS_PERIOD_S = 5.0
MAX_THREADS = 64
# Skipping more than this fraction of the input lately is "cannot keep up" (WARN); a frame
# skipped now and then on a loaded machine is not.
SKIPPED_WARN_FRACTION = 0.1

# The parameters of every node that runs a step, in the order --help shows them.
INPUT_SPECS = viewer_specs('none', DISPLAYS) + (
    Spec('image_transport', 'raw', 'raw: sensor_msgs/Image on usb_camera/image; '
         'compressed: sensor_msgs/CompressedImage on usb_camera/image/compressed',
         choices=TRANSPORTS),
    MAX_IMAGE,
)
STEP_SPECS = (
    Spec('step', 'circle', 'the processing step: a built-in one (%s) or your own as '
         'module.path:Class (docs/processing.md)' % ', '.join(loader.BUILT_IN), check=bool,
         accepted='%s or module.path:Class' % ', '.join(loader.BUILT_IN)),
    Spec('threads', 1, "CPU threads a step may give its model runtime (and OpenCV's own in "
         'this process)', (1, MAX_THREADS)),
)


class ProcessingStats:
    """The output stream's statistics and the worker's, safe to use from both threads."""

    def __init__(self, worker: LatestFrameWorker):
        self.worker = worker
        self._output = StreamStats(window_s=STATS_PERIOD_S)
        self._lock = threading.Lock()
        self.failed = 0   # frames the step raised on
        self.empty = 0    # frames the step returned None for
        self.published = 0  # outputs published on the image topic (it had subscribers)

    def add_output(self, age_s: Optional[float], width: int, height: int) -> int:
        """Record one output (published or not) and its age (None: unstamped); return how many."""
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

    def add_failure(self) -> int:
        """Record one frame the step failed on; return how many so far."""
        with self._lock:
            self.failed += 1
            return self.failed

    def add_empty(self) -> None:
        """Record one frame the step returned nothing for."""
        with self._lock:
            self.empty += 1

    def add_published(self) -> None:
        """Record one output published as an image (raw, compressed or both)."""
        with self._lock:
            self.published += 1

    def snapshot(self) -> dict:
        """
        Return the output's rate, latency and size, with the worker's counts and times.

        The processing times split into the models' (time inside their runs, as the runtimes
        measure it) and the rest, each frame's: models_ms_p50/p99, rest_ms_p50/p99, and
        frames_with_models, how many frames of the window ran a model at all. Since start, the
        worker thread's CPU time in processing (processing_cpu_ms) and of it in models
        (models_cpu_ms).
        """
        with self._lock:
            output = self._output.snapshot()
            output.update(failed=self.failed, nothing_returned=self.empty,
                          published=self.published)
        worker = self.worker.snapshot()
        split = {'models_ms_p50': worker.pop('part_ms_p50'),
                 'models_ms_p99': worker.pop('part_ms_p99'),
                 'frames_with_models': worker.pop('part_items'),
                 'processing_cpu_ms': worker.pop('cpu_ms'),
                 'models_cpu_ms': worker.pop('part_cpu_ms')}
        return dict(output, **worker, **split)


def _where(error: BaseException) -> str:
    """Return where error was raised, as `function (folder/file.py:line)`."""
    frames = traceback.extract_tb(error.__traceback__)
    if not frames:
        return ''
    last = frames[-1]
    path = Path(last.filename)
    return '%s (%s/%s:%d)' % (last.name, path.parent.name, path.name, last.lineno)


def _given_step(argv: Sequence[str], node_name: str) -> str:
    """Return the step the command line names (the default when none or unreadable)."""
    try:
        given = ros_arguments.given_parameters(
            argv, ros_arguments.node_name(argv, node_name)).get('step')
    except ValueError:  # --help still prints the node's own parameters
        given = None
    return str(given) if given else STEP_SPECS[0].default


class _StepPublisher:
    """A publisher of the step's, as StepPublishers hands it out: publish() goes through it."""

    def __init__(self, publisher, owner: 'StepPublishers'):
        self._publisher = publisher
        self._owner = owner

    def publish(self, msg) -> bool:
        """Publish msg, unless the node is stopping and this is not its stop; say if sent."""
        return self._owner.publish(self._publisher, msg)

    def __getattr__(self, name):
        return getattr(self._publisher, name)  # topic_name, get_subscription_count, ...


class StepPublishers:
    """
    The publishers a step makes through its context: silent after stop(), but for its close().

    Once stop() was called, only the thread that called it (the node's close(), which calls the
    step's close()) publishes through them: a process() still under way, abandoned, publishes
    nothing more (its frame's image is dropped too). One lock orders every message sent with
    stop(), so nothing published from another thread can follow the step's last word.
    `deliver()` waits for reliable subscribers to acknowledge what was sent.
    """

    def __init__(self):
        self._lock = threading.Lock()
        self._stopper: Optional[threading.Thread] = None
        self.publishers: List[Any] = []
        self.dropped = 0

    def create(self, node, msg_type, topic: str, depth: int):
        """Create a publisher of the node (reliable, keep-last depth) for the step."""
        publisher = node.create_publisher(msg_type, topic, depth)
        self.publishers.append(publisher)
        return _StepPublisher(publisher, self)

    def publish(self, publisher, msg) -> bool:
        """Publish msg on publisher; return False when it was dropped (after stop())."""
        with self._lock:
            if self._stopper is not None and threading.current_thread() is not self._stopper:
                self.dropped += 1
                return False
            publisher.publish(msg)
            return True

    def stop(self) -> None:
        """From now on only the calling thread publishes."""
        with self._lock:
            self._stopper = threading.current_thread()

    def deliver(self, timeout_s: float) -> bool:
        """Wait until reliable subscribers acknowledged everything sent; False at timeout_s."""
        deadline = time.monotonic() + timeout_s
        delivered = True
        for publisher in self.publishers:
            left = max(0.0, deadline - time.monotonic())
            try:
                delivered = publisher.wait_for_all_acked(
                    Duration(nanoseconds=int(left * 1e9))) and delivered
            except Exception:  # noqa: B902 - a publisher rclpy already let go of
                delivered = False
        return delivered


class VisionStep(Node):
    """The processing node (node_main.NodeProgram): one step on the newest frame."""

    NODE_NAME = 'vision_step'
    OUTPUT_TOPIC = 'vision_step/image'
    FIXED_STEP: Optional[str] = None  # a node that always runs one step has no `step`
    COMMANDS = {}
    PUBLISHES = dds.INPUT_SIZE
    IMAGE_INPUT = 'usb_camera/image'
    SUMMARY = ('Runs a processing step (-p step:=circle, hand_signs, faces or your own '
               'module.path:Class) on the newest frame of usb_camera/image and publishes what '
               'it returns on vision_step/image. With -p step:=NAME, --help also lists that '
               "step's parameters.")
    NODE_PARAMETERS: Tuple[Spec, ...] = INPUT_SPECS + STEP_SPECS
    PARAMETERS: Tuple[Spec, ...] = NODE_PARAMETERS

    worker = display = subscription_ = None  # what close() finds when start-up was interrupted
    step_publishers: Optional[StepPublishers] = None
    step: Optional[ProcessesFrames] = None
    failed = False           # it never stops of an error of its own
    _too_large_said = False  # the warning about frames larger than the segment

    @classmethod
    def help_parameters(cls, argv: Sequence[str]) -> Tuple[Spec, ...]:
        """Return the parameters --help lists: the node's, then its step's (when it loads)."""
        name = cls.FIXED_STEP or _given_step(argv, cls.NODE_NAME)
        try:
            step_class = loader.find(name)[1]
        except loader.StepError:
            return cls.NODE_PARAMETERS
        return cls.NODE_PARAMETERS + step_parameters(step_class)

    def __init__(self):
        super().__init__(self.NODE_NAME)
        params = Parameters(self)
        values = {spec.name: params.declare(spec) for spec in self.NODE_PARAMETERS}
        if 'threads' in values:
            # OpenCV's pool too: with more threads than the step may use, a model's input
            # (a 224x224 crop) was warped on two, the second spinning between frames (OpenCV
            # 5: 0.2 ms of CPU more a warp); OpenCV's DNN runtime takes its threads from here.
            cv2.setNumThreads(values['threads'])
        self.step_name = self.FIXED_STEP or values['step']
        self.step_target, step_class = loader.find(self.step_name)
        specs = step_parameters(step_class)
        loader.check_parameters(self.step_name, specs, self.NODE_PARAMETERS)
        specs = tuple(marked(spec, self.step_name) for spec in specs)
        self.step = loader.make(self.step_name, step_class)
        step_values = {spec.name: params.declare(
            spec, self._parameter_applier(spec.name) if spec.live else None) for spec in specs}

        self.bridge_ = CvBridge()
        self.display = Display(self.get_logger(), values['display'], values['web_host'],
                               values['web_port'], self.OUTPUT_TOPIC, values['web_token'])
        # Reliable with a queue of 10, the ROS 2 default: what the seed's rospy publisher
        # gives, and both reliable and best-effort subscribers (rqt_image_view) receive it.
        # Raw and JPEG each only while someone subscribes: with nobody watching, a frame costs
        # the step alone (bench/bench_vision_step.py --lazy).
        self.images = ImagePublisher(params, self.OUTPUT_TOPIC, publisher_qos(), self.bridge_)
        self.publisher_ = self.images.raw
        # Frames can wait in three places: the subscription's DDS history, the executor
        # (which takes one message per callback) and the worker's slot. The callback only
        # offers, so the executor never falls behind; keep-last 1 means that even when it is
        # held up, DDS keeps only the newest frame for it; the slot holds one frame.
        self.worker = LatestFrameWorker(self.process, on_error=self._worker_failed,
                                        window_s=STATS_PERIOD_S, name='processing',
                                        part_clock=models_clock)
        self.stats = ProcessingStats(self.worker)
        self._failures = ThrottledLog(self.get_logger(), ERROR_LOG_PERIOD_S)
        self._last_failure = ''
        self.step_publishers = StepPublishers()
        note = loader.start(self.step_name, self.step, StepContext(
            node=self, logger=self.get_logger(), parameters=step_values,
            threads=values.get('threads', 1), cancelled=lambda: self.worker.closed,
            frame_age=self.worker.frame_age, publisher_factory=self.step_publishers.create,
            output_wanted=self._output_wanted))
        self.subscription_ = subscribe(self, 'usb_camera/image', values['image_transport'],
                                       self.worker.offer, depth=1,
                                       max_image_mb=values['max_image_mb'])
        self._shown_lock = threading.Lock()
        self._to_show: Optional[np.ndarray] = None
        # OpenCV windows belong to the executor's thread: the worker hands frames over.
        self._show_request = self.create_guard_condition(self._show_newest)
        self.create_timer(STATS_PERIOD_S, self.report_stats)
        # The panel shows the camera these frames come from, upstream of this node, and the
        # step's parameters.
        self.display.attach(self, self.stats, self.publisher_.topic_name,
                            camera_topic=self.subscription_.topic_name, runs_step=True)
        self._recent = Recent()
        self.diagnostics = Diagnostics(params, hardware_id=self.subscription_.topic_name)
        self.diagnostics.add('processing', self.processing_status)
        self.get_logger().info(self.startup_line(note))

    def startup_line(self, note: Optional[str]) -> str:
        """Return the start-up line: the step, what it reads and writes, and the step's note."""
        target = '' if self.step_target == self.step_name else ' (%s)' % self.step_target
        return 'running step %s%s on images from %s, publishing them on %s%s' % (
            self.step_name, target, self.subscription_.topic_name,
            self.publisher_.topic_name, '; %s' % note if note else '')

    def _output_wanted(self) -> bool:
        """Return True while the step's output is published or shown (StepContext's)."""
        return (self.display.active or self.images.wants_raw()
                or self.images.wants_compressed())

    def _parameter_applier(self, name):
        def apply(value):
            changed = getattr(self.step, 'parameters_changed', None)
            if changed is None:
                return None
            try:
                return changed({name: value})
            except Exception as error:  # noqa: B902 - the step's own code
                return 'step %s refused %s: %s: %s' % (
                    self.step_name, name, type(error).__name__, error)
        return apply

    def process(self, msg):
        """Convert, run the step on and publish one frame (on the worker's thread)."""
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
        # The bridge returns a writable image the node owns (a view of this message's data,
        # or a converted copy): the step may draw on it in place.
        try:
            out = self.step.process(image, msg.header)
            if out is not None and not (isinstance(out, np.ndarray) and out.dtype == np.uint8
                                        and out.ndim == 3 and out.shape[2] == 3):
                raise TypeError('process() returned %s, not a bgr8 image (height x width x 3 '
                                'uint8 numpy array) or None' % _described(out))
        except Exception as error:  # noqa: B902 - the step's own code: log, count, go on
            if not self.worker.closed:
                self._step_raised(error)
                self._frame_failed(msg.header, error)
            return
        if self.worker.closed:
            return  # close() was called: the node is being torn down, drop the frame
        if out is None:
            self.stats.add_empty()
            return
        rows, cols = out.shape[:2]
        if any(self.images.publish(msg.header, lambda: out)):
            self.stats.add_published()
        age = stamp_age_s(self.get_clock().now().nanoseconds, msg.header.stamp)
        if self.stats.add_output(age, cols, rows) == 1:
            self.get_logger().info('first image: %dx%d %s' % (
                cols, rows, 'jpeg' if isinstance(msg, CompressedImage) else msg.encoding))
        if not self._too_large_said and not dds.frame_fits(out.nbytes):
            self._too_large_said = True
            self.get_logger().warning(
                '%dx%d frames do not fit the shared memory this node sized at start-up for '
                "the camera's default size: same-host subscribers get them late or not at "
                'all; start it with -p image_width:=%d -p image_height:=%d (or the '
                "camera's parameter file)" % (cols, rows, cols, rows))
        if self.display.active:
            with self._shown_lock:
                self._to_show = out
            self._show_request.trigger()

    def _step_raised(self, error: Exception):
        failed = self.stats.add_failure()
        where = _where(error)
        kind = '%s: %s' % (type(error).__name__, ' '.join(str(error).split()))
        self._last_failure = kind
        self._failures.error(
            (type(error).__name__, where),
            'step %s failed on a frame%s: %s; the frame is skipped, the node goes on '
            '(%d failed so far)' % (self.step_name, ' in %s' % where if where else '', kind,
                                    failed))

    def _frame_failed(self, header, error: Exception):
        """Tell the step (its frame_failed hook, where it has one) that it failed on a frame."""
        hook = getattr(self.step, 'frame_failed', None)
        if hook is None:
            return
        try:
            hook(header, error)
        except Exception as failure:  # noqa: B902 - the step's own code
            self._failures.error(
                ('frame_failed', type(failure).__name__),
                'step %s failed in frame_failed(): %s: %s' % (
                    self.step_name, type(failure).__name__, failure))

    def _show_newest(self):
        with self._shown_lock:
            image, self._to_show = self._to_show, None
        if image is not None:
            self.display.show(image)

    def _worker_failed(self, error):
        self.get_logger().error('processing a frame failed: %s: %s' % (
            type(error).__name__, error), throttle_duration_sec=ERROR_LOG_PERIOD_S)

    def report_stats(self):
        """Log one line: frames in, processed, skipped, processing time and output age."""
        s = self.stats.snapshot()
        line = 'frames in %d, processed %d, skipped %d' % (
            s['frames_in'], s['processed'], s['skipped'])
        if s['failed']:
            line += ', step failed on %d' % s['failed']
        if s['processing_ms_p50'] is not None:
            line += ', processing p50 %.1f ms p99 %.1f ms (%s)' % (
                s['processing_ms_p50'], s['processing_ms_p99'], _split_text(s))
        if s['age_ms_p50'] is not None:
            line += ', output age p50 %.1f ms p99 %.1f ms, %.1f fps out' % (
                s['age_ms_p50'], s['age_ms_p99'], s['fps'])
        self.get_logger().info('%s on %s' % (line, self.publisher_.topic_name))

    def processing_status(self):
        """Return the step's status for /diagnostics: WARN when it falls behind or fails."""
        s = self.stats.snapshot()
        recent = self._recent.update(frames_in=s['frames_in'], skipped=s['skipped'],
                                     errors=s['errors'], processed=s['processed'],
                                     failed=s['failed'])
        values = {'step': self.step_name,
                  'input': self.subscription_.topic_name, 'output': self.publisher_.topic_name,
                  'frames in': s['frames_in'], 'processed': s['processed'],
                  'skipped': s['skipped'], 'not converted': s['errors'],
                  'step failed': s['failed'], 'nothing returned': s['nothing_returned'],
                  'images published': s['published'],
                  'processing p50 ms': s['processing_ms_p50'],
                  'processing p99 ms': s['processing_ms_p99'],
                  'models p50 ms': s['models_ms_p50'], 'models p99 ms': s['models_ms_p99'],
                  'rest p50 ms': s['rest_ms_p50'], 'rest p99 ms': s['rest_ms_p99'],
                  'frames running models': s['frames_with_models'],
                  'processing CPU ms': s['processing_cpu_ms'],
                  'models CPU ms': s['models_cpu_ms'],
                  'output age p50 ms': s['age_ms_p50'], 'output age p99 ms': s['age_ms_p99'],
                  'output rate': float(s['fps'])}
        simulated = getattr(self.step, 'simulated_work_s', None)
        if simulated is not None:
            values['simulated work ms'] = simulated * 1e3
        if recent['failed']:
            values['last failure'] = self._last_failure
            if recent['failed'] >= recent['processed']:
                return Status(ERROR, 'step %s failed on every frame lately (%d): %s' % (
                    self.step_name, recent['failed'], self._last_failure), values)
            return Status(WARN, 'step %s failed on %d of the last %d frames: %s' % (
                self.step_name, recent['failed'], recent['processed'], self._last_failure),
                values)
        if recent['frames_in'] and recent['skipped'] > SKIPPED_WARN_FRACTION * recent['frames_in']:
            return Status(WARN, 'cannot keep up: skipped %d of the last %d frames' % (
                recent['skipped'], recent['frames_in']), values)
        if recent['errors']:
            return Status(WARN, '%d frame(s) could not be converted lately' % recent['errors'],
                          values)
        if s['processing_ms_p50'] is None:
            return Status(OK, 'no frames on %s lately' % self.subscription_.topic_name, values)
        return Status(OK, 'keeping up: processing p50 %.1f ms (%s)' % (
            s['processing_ms_p50'], _split_text(s)), values)

    def close(self):
        """
        Stop the step (at once), the worker (abandoning a step in progress), the window or viewer.

        The step's stopping() and close() have the last word on its publishers, and what they
        send there is waited for (the module's docstring says in which order).
        """
        if self.subscription_ is not None:
            self.subscription_.close()  # no frame is offered any more
        if self.step_publishers is not None:
            self.step_publishers.stop()
        self._step_hook('stopping', 'to stop')
        if self.worker is not None and not self.worker.close(STOP_GRACE_S):
            self.get_logger().warning(
                'step %s still processing a frame %g s after the stop: abandoned, nothing it '
                'publishes from now on goes out' % (self.step_name, STOP_GRACE_S))
        self._step_hook('close', 'to close')
        if self.step_publishers is not None and not self.step_publishers.deliver(
                DELIVERY_TIMEOUT_S):
            self.get_logger().warning(
                "step %s's last messages were not acknowledged by every reliable subscriber "
                'within %g s' % (self.step_name, DELIVERY_TIMEOUT_S))
        if self.display is not None:
            self.display.close()

    def _step_hook(self, name: str, what: str) -> None:
        """Call the step's stopping() or close() where it has one; its failure is one line."""
        hook = getattr(self.step, name, None) if self.step is not None else None
        if hook is None:
            return
        try:
            hook()
        except Exception as error:  # noqa: B902 - the step's own code
            self.get_logger().error('step %s failed %s: %s: %s' % (
                self.step_name, what, type(error).__name__, error))


def marked(spec: Spec, step_name: str) -> Spec:
    """Return spec with its descriptor marked as a parameter of the step (the viewer's panel)."""
    return dataclasses.replace(spec, constraints=step_constraints(
        step_name, spec.choices, spec.constraints or spec.accepted))


def _split_text(s: dict) -> str:
    """Return how a snapshot's processing time splits: models and the rest, p50 each."""
    if not s['frames_with_models']:
        return 'no model ran'
    return 'p50: models %.1f ms, rest %.1f ms' % (s['models_ms_p50'], s['rest_ms_p50'])


def _described(value: Any) -> str:
    if isinstance(value, np.ndarray):
        return 'a %s array of shape %s' % (value.dtype, value.shape)
    return 'a %s' % type(value).__name__


main = main_for(VisionStep)


if __name__ == '__main__':
    main()
