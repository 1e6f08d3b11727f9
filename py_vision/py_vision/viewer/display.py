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
Where a node shows frames: an OpenCV window, the browser viewer, or nowhere.

`auto` takes a window where this machine can open one (a screen and an OpenCV with GUI
support) and the browser viewer otherwise, which is what a board without a screen needs.

A camera's H.264 (`show_video`) goes to the browser as it is, for the page to decode itself;
it is decoded here (`video_decoder`) only while someone needs pixels: a window, or a browser
that cannot decode it (MJPEG clients, snapshots). Where this machine cannot decode, it says so
once.

Frames may be shown from any thread (a subscription's receive thread, the decoder's): the
browser viewer takes them there; a window is drawn on the node's executor thread alone (the
one that attached the display), to which the newest picture is handed.
"""

import os
import re
import socket
import sys
import threading
import time

import cv2
import numpy as np
from py_vision.annexb import UnitInfo
from py_vision.params import ConfigError
from py_vision.video_decoder import VideoDecoder

DISPLAYS = ('auto', 'window', 'web', 'none')
WEB_STATS_PERIOD_S = 1.0
WINDOW_EVENTS_PERIOD_S = 0.05


def _x_server_reachable(display):
    """Return True when the X server DISPLAY names accepts connections."""
    host, _, screen = display.rpartition(':')
    number = screen.split('.')[0]
    if not number.isdigit():
        return False
    if host in ('', 'unix'):
        return os.path.exists('/tmp/.X11-unix/X' + number)
    try:
        socket.create_connection((host, 6000 + int(number)), timeout=0.5).close()
    except OSError:
        return False
    return True


def window_unavailable_reason():
    """Return why no OpenCV window can be opened here, or None when one can."""
    display = os.environ.get('DISPLAY')
    wayland = os.environ.get('WAYLAND_DISPLAY')
    if sys.platform.startswith('linux'):
        if not (display or wayland):
            return 'no DISPLAY is set (no screen, or ssh without X forwarding)'
        # A GUI OpenCV aborts the whole process when its X server is gone (a stale DISPLAY
        # after an ssh reconnect): check before it tries.
        if display and not wayland and not _x_server_reachable(display):
            return 'the X server of DISPLAY=%s cannot be reached' % display
    try:
        cv2.namedWindow('py_vision', cv2.WINDOW_AUTOSIZE)
        cv2.destroyWindow('py_vision')
    except cv2.error as error:
        backend = gui_backend()
        if backend is None or 'not implemented' in str(error):
            return 'this OpenCV has no GUI support (opencv-python-headless)'
        # A GUI OpenCV (the boards' has GTK3) that cannot open a window on this display:
        # say so with OpenCV's own reason, e.g. "Can't initialize GTK backend".
        return "OpenCV's %s GUI cannot open a window on %s: %s" % (
            backend, 'DISPLAY=%s' % display if display else 'WAYLAND_DISPLAY=%s' % wayland,
            _opencv_reason(error))
    return None


def gui_backend():
    """Return the GUI this OpenCV was built with ('GTK3', 'QT5', ...), or None without one."""
    for line in cv2.getBuildInformation().splitlines():
        name, _, value = line.strip().partition(':')
        if name == 'GUI':
            value = value.strip()
            return None if value in ('', 'NONE') else value
    return None


def _opencv_reason(error):
    """Return the reason in a cv2.error's text, without where in OpenCV's sources it was raised."""
    text = str(error).strip()
    found = re.search(r'error: \([^)]*\) (.*?)(?: in function .*)?$', text)
    return found.group(1) if found else text


class Display:
    """Shows bgr8 frames in the way the `display` parameter asks for."""

    def __init__(self, logger, mode, web_host, web_port, title, web_token=''):
        self.window_title = None
        self.viewer = None
        self._logger = logger
        self._decoder = None           # decoding a camera's video while pixels are needed
        self._cannot_decode = None     # why it cannot, once said
        self._decoded = None           # the newest decoded picture, not shown yet
        self._for_window = None        # the newest picture from another thread, for the window
        self._handed_lock = threading.Lock()
        self._wake = None              # runs _show_handed on the node's executor
        self._home = None              # the executor's thread (the window's)
        if mode in ('auto', 'window'):
            reason = window_unavailable_reason()
            if reason is None:
                self.window_title = title
                cv2.namedWindow(title, cv2.WINDOW_AUTOSIZE)
                logger.info('showing frames in an OpenCV window')
                return
            if mode == 'window':
                logger.warning('display:=window is not possible: %s; showing statistics only '
                               '(display:=web shows the stream in a browser)' % reason)
                return
            mode = 'web'
        if mode == 'web':
            # Imported only here: the HTTP server brings OpenSSL along (about 7 MB of memory
            # per process, bench/bench_memory.py), which a node that shows nothing never needs.
            from py_vision.viewer.server import WebViewer, WebViewerError
            viewer = WebViewer(web_host, web_port, title='py_vision: %s' % title, logger=logger,
                               token=web_token)
            try:
                viewer.start()
            except WebViewerError as error:
                raise ConfigError(str(error))
            self.viewer = viewer

    def attach(self, node, stats, topic, camera_topic=None, runs_step=False):
        """
        Start the node's timers: the viewer's statistics of topic, the window's events.

        With camera_topic, the viewer's camera panel shows the camera of the node publishing it;
        runs_step: and the node's own step's parameters (it runs a processing step).
        """
        if self.viewer is not None:
            node.create_timer(WEB_STATS_PERIOD_S, lambda: self.viewer.set_stats(
                dict(stats.snapshot(), topic=topic)))
            if camera_topic is not None:
                from py_vision.viewer.camera_panel import CameraPanel
                self.viewer.set_camera(CameraPanel(node, camera_topic, runs_step=runs_step))
            # Once the page is complete.
            if self.viewer.token:
                self._say_url_with_token()
            else:
                self._logger.info('browser viewer at %s' % self.viewer.url)
        if self.window_title is not None:
            # The window repaints and answers its close button also when no frame arrives.
            node.create_timer(WINDOW_EVENTS_PERIOD_S, lambda: cv2.waitKey(1))
        # Pictures decoded on the decoder's thread, and those for the window from any other
        # thread, are shown on the executor's.
        self._home = threading.get_ident()
        self._wake = node.create_guard_condition(self._show_handed)

    def _say_url_with_token(self):
        """
        Write the URL with the token on this console only: the one place it is ever written.

        The node's log goes to /rosout too (where every member of the ROS domain, late joiners
        included, reads it) and to its log file: there the line leaves the token out.
        """
        url = self.viewer.url
        sys.stderr.write('[INFO] [%.9f] [%s]: browser viewer at %s (needs this token: whoever '
                         'has the URL can watch and tune the camera)\n' % (
                             time.time(), self._logger.name, url))
        sys.stderr.flush()
        self._logger.info('browser viewer on %s with a token: the URL to open is printed on '
                          'the console only' % url.split('?', 1)[0])

    @property
    def active(self):
        """Return True when frames are shown somewhere (so they need converting)."""
        return self.window_title is not None or self.viewer is not None

    @property
    def needs_pixels(self):
        """Return True when showing a JPEG needs it decoded (a window; the viewer does not)."""
        return self.window_title is not None

    def show(self, image):
        """Show one bgr8 (or mono8) frame; cheap when nobody watches the browser viewer."""
        if self.window_title is not None:
            self._show_in_window(image)
        if self.viewer is not None:
            self.viewer.submit(image)

    def show_jpeg(self, jpeg, image=None):
        """Show a JPEG frame: the viewer forwards its bytes, a window shows image (decoded)."""
        if self.window_title is not None and image is not None:
            self._show_in_window(image)
        if self.viewer is not None:
            self.viewer.submit_jpeg(np.asarray(jpeg, np.uint8).tobytes())

    def show_video(self, unit: bytes, info: UnitInfo, codec: str) -> None:
        """
        Show one access unit of a camera's video (codec 'h264' or 'hevc').

        The browser viewer gets H.264 as it is; the unit is decoded here only while pixels
        are needed (a window, MJPEG clients or a snapshot of the viewer).
        """
        viewer = self.viewer
        if viewer is not None and codec == 'h264':
            viewer.submit_video(unit, info.decodable_start, info.codec_string)
        wanted = self.window_title is not None or (viewer is not None and viewer.wants_pixels)
        if self._decoder is not None and (not wanted or self._decoder.codec != codec):
            self._decoder.close(timeout=0)
            self._decoder = None
        if not wanted:
            return
        if self._decoder is None:
            if self._cannot_decode is not None:
                return
            self._decoder = VideoDecoder(codec, self._decoded_picture, self._decoder_failed)
            if self._decoder.failed:
                self._decoder_failed(self._decoder.failed)
                return
            if viewer is not None and codec == 'h264':
                # From the newest keyframe the viewer keeps: a picture at once.
                for kept, _ in viewer.video.since(0, 0)[1][:-1]:
                    self._decoder.decode(kept)
        self._decoder.decode(unit)

    def _decoder_failed(self, reason):
        if self._cannot_decode is None:
            self._cannot_decode = reason
            if self.viewer is not None:
                self.viewer.video_decoder_missing = reason
            self._logger.error(
                "cannot decode the camera's video here, so %s shows none of it: %s%s" % (
                    'the window' if self.window_title is not None else
                    'a browser without WebCodecs', reason,
                    '' if self.window_title is not None else
                    ' (Chromium and Edge decode H.264 themselves on a secure page: the viewer '
                    'on localhost, or through ssh -L)'))

    def _show_in_window(self, image):
        if self._wake is None or threading.get_ident() == self._home:
            cv2.imshow(self.window_title, image)
            cv2.waitKey(1)
            return
        with self._handed_lock:
            self._for_window = image
        self._wake.trigger()

    def _decoded_picture(self, picture, tag):
        with self._handed_lock:
            self._decoded = picture
        if self._wake is not None:
            self._wake.trigger()

    def _show_handed(self):
        with self._handed_lock:
            picture, self._decoded = self._decoded, None
            for_window, self._for_window = self._for_window, None
        if for_window is not None:
            self._show_in_window(for_window)
        if picture is not None:
            self.show(picture)

    def close(self):
        """Close the window, or stop the viewer and release its port."""
        if self.window_title is not None:
            try:
                cv2.destroyWindow(self.window_title)
            except cv2.error:
                pass
        if self._decoder is not None:
            self._decoder.close()
        if self.viewer is not None:
            self.viewer.close()
