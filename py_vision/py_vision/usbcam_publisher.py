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
usbcam_publisher: a USB camera as sensor_msgs/Image, CompressedImage and CameraInfo.

The ROS 2 port of the tutorial's publisher, grown into a driver. Frames are read on a capture
thread (the camera paces itself), stamped with their capture time and published at once: raw
on usb_camera/image (bgr8, or the `output_encoding` asked for: the camera's own pixels with
`native`), JPEG on usb_camera/image/compressed (the camera's own JPEG untouched in MJPEG
mode), each only while it has subscribers, and the CameraInfo of every frame on
usb_camera/camera_info with exactly the image's header. The node is a thin adapter: it
keeps the parameters, publishers and services; opening, reading, losing and reopening the camera
is the camera layer's CaptureLoop (py_vision.capture), which calls publish_image() with each new
frame.

One node, managed or not. Its work follows the ROS 2 lifecycle (rclpy.lifecycle, the same on
Humble 3.3 and Jazzy 7.1):

- configure: parameters checked, publishers made, the camera opened and negotiated;
- activate: the capture thread starts; frames, compressed and camera_info are published;
- deactivate: the capture thread stops and so does the stream (VIDIOC_STREAMOFF), which frees
  the camera's USB bandwidth; the device stays open with its buffers and controls, so nobody
  else can take it and activate resumes at once;
- cleanup: the camera and the publishers are released (back to unconfigured);
- shutdown, from any state: everything released, and the process ends (status 0).

With ``managed:=false`` (the default) the node takes configure and activate itself while it
starts, has no lifecycle services, and a failure is a start-up error (one line, status 1). With
``managed:=true`` it starts unconfigured and serves the lifecycle services (`ros2 lifecycle
set`, launch_ros's LifecycleNode, any lifecycle manager): a failed transition says why in one
line and leaves the node ready to try again. Only the capture thread publishes, and it runs only
while active; /diagnostics is published in every state. Ctrl-C ends the node cleanly in any
state (node_main calls close()).
"""

import sys
import time
from typing import Tuple

from builtin_interfaces.msg import Time as TimeMsg
import cv2
from py_vision import dds, ros_arguments
from py_vision.calibration import CameraInfoManager, is_valid_camera_name
from py_vision.camera_diagnostics import CameraMonitor
from py_vision.camera_video import CameraVideo
from py_vision.capture import (
    Camera, CaptureLoop, pixel_format_accepted, SourceError, SyntheticDevices)
from py_vision.capture.devices import AUTO
from py_vision.capture.pixel_formats import find, names_accepted, OUTPUTS
from py_vision.control_names import pixel_format_fourcc, USB_CAM_PIXEL_FORMATS
from py_vision.control_params import ALIAS_HELP, ControlParameters
from py_vision.cv_bridge import CvBridge
from py_vision.diagnostics import Diagnostics, PERIOD_S as DIAGNOSTICS_PERIOD_S
from py_vision.listing import device_listing, devices_listing
from py_vision.node_main import ConfigError, main_for
from py_vision.params import Parameters, Spec
from py_vision.qos import create_publisher, publisher_qos, RELIABILITY
from py_vision.serialized_publisher import StampedPublisher
from py_vision.transport import ImagePublisher, sibling_topic
import rclpy
from rclpy.lifecycle import LifecycleNodeMixin, TransitionCallbackReturn
from rclpy.logging import get_logger
from rclpy.node import Node
from sensor_msgs.msg import CameraInfo
from sensor_msgs.srv import SetCameraInfo
from std_msgs.msg import Header

IMAGE_TOPIC = 'usb_camera/image'
MANAGED = Spec('managed', False, 'run as a lifecycle node: configure opens the camera, activate '
               'publishes, deactivate stops streaming (the camera kept open), cleanup '
               'releases the camera and the publishers (ros2 lifecycle set)')
SUCCESS = TransitionCallbackReturn.SUCCESS
FAILURE = TransitionCallbackReturn.FAILURE
# How often the control parameters are brought up to date with the device's values; every
# DIAGNOSTICS_TICKS-th time /diagnostics is published too (once a second): one timer, one
# executor wake-up for both (a wake-up of rclpy's executor costs this node more than either).
CONTROL_SYNC_PERIOD_S = 0.5
DIAGNOSTICS_TICKS = round(DIAGNOSTICS_PERIOD_S / CONTROL_SYNC_PERIOD_S)
# After shutdown the process ends this much later, once the answer to the transition request
# has gone out (ending rclpy at once could lose it, and `ros2 lifecycle set` would wait).
EXIT_AFTER_SHUTDOWN_S = 0.5
# A TF frame name: what tf2 and every viewer take, and what survives a C string (no NUL).
FRAME_ID_RULE = '1 to 256 printable characters, without spaces'
_MAX_FRAME_ID = 256
_NS = 1000000000


def good_frame_id(frame_id: str) -> bool:
    """Return True when frame_id follows FRAME_ID_RULE."""
    return 0 < len(frame_id) <= _MAX_FRAME_ID and frame_id.isprintable() and (
        not any(character.isspace() for character in frame_id))


class USBImagePublisher(LifecycleNodeMixin, Node):
    """The camera node; its camera follows the lifecycle state (see the module's text)."""

    NODE_NAME = 'usbcam_publisher'
    PUBLISHES = dds.OWN_SIZE
    IMAGE_INPUT = None
    SUMMARY = ('Publishes a USB camera (or a video file, or the built-in synthetic camera) as '
               'sensor_msgs/Image on usb_camera/image, JPEG on usb_camera/image/compressed '
               'and CameraInfo on usb_camera/camera_info. Every control the camera reports is '
               "a parameter too, with the camera's range (ros2 param describe); "
               '--list-formats prints what the camera offers and exits, --list-devices every '
               'video device.')
    OWN_PARAMETERS = (
        Spec('video_device', '/dev/video0',
             'V4L2 device path, camera index, auto (the first USB camera), video file, or '
             '"synthetic[?options]"',
             check=bool, accepted='a device path, an index, a file or synthetic'),
        Spec('image_width', 640, 'requested frame width in pixels', (1, 8192)),
        Spec('image_height', 480, 'requested frame height in pixels', (1, 8192)),
        Spec('framerate', 10.0, 'requested frames per second', (0.0, 1000.0),
             check=lambda v: v > 0, accepted='a number > 0 and <= 1000'),
        Spec('pixel_format', 'auto', 'what the camera sends, by the FourCC --list-formats '
             'prints; auto: what reaches the requested size and rate with the least work',
             check=lambda v: pixel_format_accepted(pixel_format_fourcc(v)),
             accepted="auto, or a FourCC: %s, or usb_cam's %s" % (
                 names_accepted(), ', '.join(USB_CAM_PIXEL_FORMATS))),
        Spec('output_encoding', 'bgr8', 'the encoding of usb_camera/image: native publishes '
             "the camera's pixels as sent wherever sensor_msgs has an encoding for them",
             choices=OUTPUTS),
        Spec('jpeg_quality', 80, 'JPEG quality of usb_camera/image/compressed when encoded '
             "here (an MJPEG camera's own JPEG is published as it is)", (1, 100), live=True),
        Spec('frame_id', 'usb_camera', 'header.frame_id of the images', check=good_frame_id,
             accepted=FRAME_ID_RULE, live=True),
        Spec('camera_name', 'usb_camera', 'camera name for the calibration (${NAME})',
             check=is_valid_camera_name, accepted='letters, digits and _'),
        Spec('camera_info_url', '', 'calibration file: file:///path.yaml or '
             'package://pkg/path.yaml; empty: ~/.ros/camera_info/${NAME}.yaml if it exists'),
        Spec('reliability', 'reliable', 'publisher QoS reliability', choices=tuple(RELIABILITY)),
        Spec('depth', 10, 'publisher QoS queue depth', (1, 1000)),
        MANAGED,
    )
    # --help lists usb_cam's control names too; the camera's own are declared once it is open.
    PARAMETERS = OWN_PARAMETERS + ALIAS_HELP

    # What close() finds when start-up was interrupted before these were made.
    capture = controls = images = video = None
    failed = False
    _log_name = NODE_NAME
    _state = 'unconfigured'
    raw_published = compressed_published = frames_decoded = 0

    def __init__(self, **node_options):
        # node_options: rclpy Node's keyword arguments (context, parameter_overrides...).
        Node.__init__(self, self.NODE_NAME, **node_options)
        self._params = Parameters(self)
        self.managed = self._params.declare(MANAGED)
        # A managed node checks them at configure: an unusable value fails configure instead
        # of ending the node.
        self._parameter_errors = [] if self.managed else None
        self._failure = None   # why the last transition failed, in one line
        self._setup(self._declare_parameters(self._parameter_errors))
        if self.managed:
            LifecycleNodeMixin.__init__(self)
            self.get_logger().info(
                'managed: unconfigured; waiting for configure (ros2 lifecycle set %s '
                'configure)' % self.get_fully_qualified_name())
            return
        # Not managed: no state machine, no lifecycle services; the node takes the two
        # transitions itself, and a failure is a start-up error.
        for step in (self.on_configure, self.on_activate):
            if step(None) != SUCCESS:
                raise ConfigError(self._failure)

    def _declare_parameters(self, errors=None):
        """
        Declare the node's own parameters but `managed`; return their checked values.

        With a list for errors, an unusable value is added to it (and the default used)
        instead of raising ConfigError. The camera's controls are declared once it is open.
        """
        live = {'jpeg_quality': self._set_jpeg_quality, 'frame_id': self._set_frame_id}
        values = {}
        for spec in self.OWN_PARAMETERS:
            if spec is MANAGED:
                continue
            try:
                values[spec.name] = self._params.declare(spec, live.get(spec.name))
            except ConfigError as error:
                if errors is None:
                    raise
                errors.append(str(error))
                values[spec.name] = None if spec.optional else spec.default
        return values

    def _setup(self, values):
        """Take the parameters' values; make the capture loop (closed) and /diagnostics."""
        # rclpy may be shut down when close() logs (Ctrl-C): a logger that does not publish
        # to /rosout, named after the node's real name.
        self._log_name = self.get_logger().name
        # One conversion or decode per frame gains nothing from OpenCV's worker threads,
        # which spin after every parallel call: one thread halves the capture's CPU
        # (bench/bench_transport.py).
        cv2.setNumThreads(1)
        self.values = values
        self.video_device = values['video_device']
        self.size = (values['image_width'], values['image_height'])
        self.framerate = values['framerate']
        self.pixel_format = pixel_format_fourcc(values['pixel_format'])
        self.output_encoding = values['output_encoding']
        self.frame_id = values['frame_id']
        self.jpeg_quality = values['jpeg_quality']
        self._synthetic = SyntheticDevices()
        self.capture = CaptureLoop(self._open_camera, self.publish_image, self.get_logger(),
                                   name=self.video_device, on_failure=self._capture_failed,
                                   on_refused=self._controls_refused)
        self._monitor = CameraMonitor()
        self._clock = self.get_clock()
        self._header = Header(frame_id=self.frame_id)
        self.diagnostics = Diagnostics(self._params, hardware_id=self.video_device,
                                       period_s=None)
        self.diagnostics.add('camera', self.camera_status)
        self._ticks = 0
        self.create_timer(CONTROL_SYNC_PERIOD_S, self._tick)

    def _make_publishers(self):
        """Create the image, compressed and camera_info publishers."""
        qos = publisher_qos(self.values['reliability'], self.values['depth'])
        self.images = ImagePublisher(self._params, IMAGE_TOPIC, qos, CvBridge())
        self.images.jpeg_quality = self.jpeg_quality
        asked = find(self.pixel_format)
        if asked is not None and asked.video:
            self.video = CameraVideo(self._params, IMAGE_TOPIC, qos, asked.fourcc, self.images,
                                     self.output_encoding)
        self.info_publisher = create_publisher(
            self._params, CameraInfo, sibling_topic(self, IMAGE_TOPIC, 'camera_info'), qos)
        self.camera_infos = StampedPublisher(self.info_publisher)

    def _configure_camera(self):
        """Open and negotiate the camera, with the controls set; ConfigError if it fails."""
        try:
            self.capture.open()
        except SourceError as error:
            raise ConfigError(str(error))

    def _declare_controls(self):
        """Declare the open camera's controls as parameters (once; the loop keeps the values)."""
        if self.controls is not None:  # configured again after a cleanup
            return
        controls = ControlParameters(self._params, self.capture, self.get_logger(),
                                     self.video_device)
        controls.declare(set(self.values))  # ConfigError: a mistyped value, declared nothing
        self.controls = controls

    def _tick(self):
        """Bring the control parameters up to date (once configured); publish /diagnostics."""
        self._ticks += 1
        try:
            if self.controls is not None:
                self.controls.sync()
        finally:
            if self._ticks % DIAGNOSTICS_TICKS == 0:
                self.diagnostics.publish()

    def _controls_refused(self, refusals):
        """Say which controls a reopened camera did not take again (the capture loop's)."""
        if self.controls is not None:
            self.controls.warn(refusals)

    def _load_calibration(self):
        """Load the calibration; serve set_camera_info."""
        self.calibration = CameraInfoManager(
            self.values['camera_name'], self.values['camera_info_url'], self.get_logger())
        self.calibration.load()
        self.set_info_service = self.create_service(
            SetCameraInfo, sibling_topic(self, IMAGE_TOPIC, 'set_camera_info'),
            self._set_camera_info)

    def camera_status(self):
        """Return the camera's status on /diagnostics (camera_diagnostics.CameraMonitor)."""
        subscribers = {}
        if self.images is not None:
            for publisher in self._topic_publishers():
                subscribers[publisher.topic_name] = publisher.get_subscription_count()
        return self._monitor.status(self.capture.stats(), self.video_device, self.framerate,
                                    subscribers, self.lifecycle_state())

    def _topic_publishers(self):
        """Return the topics' publishers: images, compressed, camera_info, a camera's video."""
        own = [self.images.raw, self.images.compressed, self.info_publisher]
        return own + ([self.video.publisher.publisher] if self.video is not None else [])

    def lifecycle_state(self):
        """Return the lifecycle state of a managed node; None: the plain node, always on."""
        return self._state if self.managed else None

    # --- parameters ------------------------------------------------------------------

    def _set_frame_id(self, frame_id):
        self.frame_id = frame_id

    def _set_jpeg_quality(self, quality):
        self.jpeg_quality = quality
        if self.images is not None:
            self.images.jpeg_quality = quality

    # --- calibration -----------------------------------------------------------------

    def _set_camera_info(self, request, response):
        response.success, response.status_message = self.calibration.set_camera_info(
            request.camera_info)
        # One call site per severity: rclpy refuses one whose severity changes (ValueError).
        if response.success:
            self.get_logger().info('set_camera_info: %s' % response.status_message)
        else:
            self.get_logger().warning('set_camera_info: %s' % response.status_message)
        return response

    # --- capture ---------------------------------------------------------------------

    def _open_camera(self):
        """Open the camera the parameters name (called by the capture loop at each (re)open)."""
        camera = Camera.open(self.video_device, self.size[0], self.size[1], self.framerate,
                             self.pixel_format, self.output_encoding,
                             synthetic=self._synthetic)
        if self.output_encoding == 'native' and camera.buffer_bytes and camera.sends_messages:
            # The camera writes its frames into the raw messages themselves: published as
            # they come, never copied here (a driver without user memory: its own buffers).
            buffers = self.images.frame_buffers(camera.buffer_count, camera.buffer_bytes)
            if buffers is not None:
                camera.capture_into(buffers)
        where = self.video_device
        if where.strip().lower() == AUTO:
            where = '%s (%s)' % (where, camera.node)
        encoding = self.output_encoding
        if encoding == 'native':
            encoding = camera.pixel_format.native_encoding
        topic = self.images.raw.topic_name
        if camera.pixel_format.video and self.video is not None:
            topic = '%s (images decoded on %s while subscribed)' % (
                self.video.publisher.name, topic)
        self.get_logger().info('opened %s: %s, publishing on %s%s' % (
            where, camera.describe(), topic, '' if encoding == 'bgr8' else ' as %s' % encoding))
        for line in camera.notes:
            self.get_logger().warning(line)
        return camera

    def _capture_failed(self, error):
        """Say that a frame could not be published, and end the node."""
        if self.context.ok():
            self.get_logger().error('capturing from %s failed: %s: %s' % (
                self.video_device, type(error).__name__, error))
            self.failed = True
            try:
                rclpy.try_shutdown(context=self.context)
            except Exception:  # a signal shut it down at the same moment
                pass
        # else: Ctrl-C or SIGTERM shut rclpy down while a frame was being published.

    def _capture_stamp(self, captured) -> Tuple[int, int]:
        """
        Return the capture time (time.monotonic(), or None) of a frame on the node's clock.

        As (sec, nanosec): the node's clock now, less the frame's age. Without a simulation
        the node's clock (ROS time) is the system's (CLOCK_REALTIME), which time.time_ns()
        reads without the rclpy objects clock.now() makes. A simulated clock (use_sim_time,
        /clock) does not run with the camera's time: there, and on a clock too young to hold
        the age (a simulation starting at 0), the frame is stamped with the clock's time now,
        so that stamps follow the clock wherever it goes (also back, when a bag loops).
        """
        clock = self._clock
        if captured is None or clock.ros_time_is_active:
            # No capture time (the read has just returned it), or simulated.
            return divmod(clock.now().nanoseconds, _NS)
        # The two clocks read as close together as the thread is let: a read pair cut by a
        # preemption (a loaded machine) would move the stamp by as much, so it is read again.
        for _ in range(3):
            before = time.monotonic()
            now = time.time_ns()
            after = time.monotonic()
            if after - before < 2e-4:
                break
        age_ns = int(((before + after) / 2 - captured) * 1e9)
        if not 0 <= age_ns < _NS or age_ns > now:
            return divmod(now, _NS)
        return divmod(now - age_ns, _NS)

    def publish_image(self, camera, frame):
        """Publish one frame: image (raw and compressed, as subscribed) and its CameraInfo."""
        sec, nanosec = self._capture_stamp(frame.capture_time)
        if frame.pixel_format.video:
            # An access unit: out as it is; images come from its decoder (camera_video), which
            # keeps the unit's header until its picture comes out: a header of its own.
            header = Header(stamp=TimeMsg(sec=sec, nanosec=nanosec), frame_id=self.frame_id)
            raw = compressed = False
            self.video.publish(header, frame.data)
        else:
            # One header for every frame: what holds it (the image, its compressed form, the
            # CameraInfo) is published before the next frame changes it.
            header = self._header
            stamp = header.stamp
            stamp.sec, stamp.nanosec = sec, nanosec
            if header.frame_id != self.frame_id:
                header.frame_id = self.frame_id
            output, picture = self.output_encoding, frame.pixel_format.picture
            raw, compressed = self.images.publish(
                header, lambda: frame.image(output), frame.jpeg, frame.encoding(output),
                lambda: frame.image(picture), lambda out: frame.image(output, out),
                frame.user_buffer)
            self.frames_decoded += frame.decoded
        info = self.calibration.camera_info(camera.width, camera.height)
        info.header = header
        self.camera_infos.publish(info)
        self.raw_published += raw
        self.compressed_published += compressed

    # --- lifecycle transitions (on the executor's thread, or in __init__ when not managed) -

    def _fail(self, what, reason):
        """Remember why a transition failed; a managed node says it now (one line)."""
        self._failure = reason
        if self.managed:
            self.get_logger().error('%s failed: %s' % (what, reason))
        return FAILURE

    def on_configure(self, state):
        """Check the parameters, make the publishers, open and negotiate the camera."""
        if self._parameter_errors:
            for error in self._parameter_errors[:-1]:
                self.get_logger().error('configure failed: %s' % error)
            return self._fail('configure', self._parameter_errors[-1])
        self._make_publishers()
        try:
            self._configure_camera()
            # A value given for one of the camera's controls is checked only now.
            self._declare_controls()
        except ConfigError as error:
            self._release_all()
            return self._fail('configure', str(error))
        self._load_calibration()
        self._state = 'inactive'
        if self.managed:
            self.get_logger().info('configured: camera open, not streaming')
        return SUCCESS

    def on_activate(self, state):
        """Start streaming, capturing and publishing (resuming the stream after a deactivate)."""
        try:
            self.capture.start()
        except SourceError as error:
            return self._fail('activate', str(error))
        self._state = 'active'
        if self.managed:
            self.get_logger().info('activated: publishing on %s' % self.images.raw.topic_name)
        return SUCCESS

    def on_deactivate(self, state):
        """Stop capturing and streaming; the device stays open with its buffers and controls."""
        if not self.capture.pause():
            get_logger(self._log_name + '.camera').warning(
                'the capture thread of %s is still in a read; streaming stops when it ends'
                % self.video_device)
        self._state = 'inactive'
        self.get_logger().info('deactivated: streaming stopped after %d frames; the camera '
                               'stays open' % self.capture.stats().frames)
        return SUCCESS

    def on_cleanup(self, state):
        """Release the camera and the publishers; fail, keeping both, if it will not close."""
        if not self._release_all():
            return self._fail('cleanup', 'the capture thread of %s did not end; the camera and '
                              'its topics are kept (try cleanup again)' % self.video_device)
        self._state = 'unconfigured'
        self.get_logger().info('cleaned up: camera released')
        return SUCCESS

    def on_shutdown(self, state):
        """Release everything, then end the process once the answer has gone out."""
        self._release_all()
        self._state = 'finalized'
        self.get_logger().info('shut down from %s: camera released; exiting' % state.label)
        self._exit_timer = self.create_timer(EXIT_AFTER_SHUTDOWN_S, self._exit)
        return SUCCESS

    def on_error(self, state):
        """Release everything after a transition raised; the node goes back to unconfigured."""
        self.get_logger().error('a transition from %s failed; releasing the camera' %
                                state.label)
        self._release_all()
        self._state = 'unconfigured'
        return SUCCESS

    # --- releasing -------------------------------------------------------------------

    def _close_camera(self):
        """Stop capturing and release the device; False if the capture thread is stuck."""
        if self.capture.close():
            return True
        get_logger(self._log_name + '.camera').warning(
            '%s is still busy; the system releases it at exit' % self.video_device)
        return False

    def _release_topics(self):
        if self.images is None:
            return
        if self.video is not None:
            self.video.close()
        for publisher in self._topic_publishers():
            self.destroy_publisher(publisher)
        self.images = self.video = None
        service = getattr(self, 'set_info_service', None)
        if service is not None:
            self.destroy_service(service)
            self.set_info_service = None

    def _release_all(self):
        """Close the camera, then the topics; False, keeping the topics, if it did not close."""
        # A capture thread still running may publish at any moment: its publishers stay.
        if not self._close_camera():
            return False
        self._release_topics()
        return True

    def _exit(self):
        self.destroy_timer(self._exit_timer)
        rclpy.try_shutdown(context=self.context)

    def close(self):
        """Release whatever this state holds (Ctrl-C, SIGTERM, a failed start, the end)."""
        capture = self.capture
        if capture is None:  # start-up was interrupted before the capture loop existed
            return
        started, opened = capture.running, capture.camera is not None
        if not self._close_camera():
            return
        logger = get_logger(self._log_name + '.camera')
        if self.managed:
            if started or opened:
                logger.info('camera released in state %s after %d frames' % (
                    self._state, capture.stats().frames))
            else:
                logger.info('stopped in state %s; no camera was open' % self._state)
        elif started and self.video is not None:
            logger.info('camera released after %d frames (%d %s published; %d decoded for '
                        'the image topics)' % (capture.stats().frames, self.video.published,
                                               self.video.publisher.format.upper(),
                                               self.video.decoded))
        elif started:
            logger.info('camera released after %d frames (%d raw, %d compressed published; '
                        '%d JPEG encoded, %d decoded)' % (
                            capture.stats().frames, self.raw_published,
                            self.compressed_published, self.images.encoded,
                            self.frames_decoded))
        elif opened:
            logger.info('camera released before capturing began')


def list_formats(argv):
    """Print what the camera offers (--list-formats); return the exit status."""
    name = USBImagePublisher.NODE_NAME
    try:
        device = ros_arguments.given_parameters(argv, ros_arguments.node_name(argv, name)).get(
            'video_device', next(spec.default for spec in USBImagePublisher.OWN_PARAMETERS
                                 if spec.name == 'video_device'))
    except ros_arguments.UnreadableArguments as error:
        sys.stderr.write('%s: invalid command line arguments: %s\n' % (name, error))
        return 2
    try:
        sys.stdout.write(device_listing(str(device)))
    except SourceError as error:
        sys.stderr.write('%s: %s\n' % (USBImagePublisher.NODE_NAME, error))
        return 1
    return 0


def list_devices(argv):
    """Print every video device in one line each (--list-devices); return the exit status."""
    sys.stdout.write(devices_listing())
    return 0


USBImagePublisher.COMMANDS = {'--list-formats': list_formats, '--list-devices': list_devices}


main = main_for(USBImagePublisher)


if __name__ == '__main__':
    main()
