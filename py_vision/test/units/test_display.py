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

"""Choosing where frames are shown: a window only where one can really be opened."""

import socket

from py_vision.viewer import display
import pytest


@pytest.fixture
def x_listener():
    """Listen where an X server with some display number would (TCP port 6000 + number)."""
    for number in range(50, 100):
        listener = socket.socket()
        try:
            listener.bind(('127.0.0.1', 6000 + number))
        except OSError:
            listener.close()
            continue
        listener.listen()
        yield number
        listener.close()
        return
    pytest.fail('no free port in 6050..6099 to stand in for an X server')


def test_no_display_means_no_window(monkeypatch):
    monkeypatch.delenv('DISPLAY', raising=False)
    monkeypatch.delenv('WAYLAND_DISPLAY', raising=False)
    assert 'no DISPLAY' in display.window_unavailable_reason()


def test_a_stale_display_is_detected_before_opencv_touches_it(monkeypatch):
    monkeypatch.delenv('WAYLAND_DISPLAY', raising=False)
    with socket.socket() as probe:
        probe.bind(('127.0.0.1', 0))
        port = probe.getsockname()[1]
    # Nothing listens on that port any more: an X display that has gone away.
    monkeypatch.setenv('DISPLAY', '127.0.0.1:%d' % (port - 6000))
    assert 'cannot be reached' in display.window_unavailable_reason()
    monkeypatch.setenv('DISPLAY', ':987')
    assert 'cannot be reached' in display.window_unavailable_reason()


def test_a_reachable_display_with_headless_opencv_says_so(monkeypatch, x_listener):
    monkeypatch.delenv('WAYLAND_DISPLAY', raising=False)
    monkeypatch.setenv('DISPLAY', '127.0.0.1:%d' % x_listener)
    assert 'no GUI support' in display.window_unavailable_reason()


def test_a_gui_opencv_that_cannot_open_a_window_says_why(monkeypatch, x_listener):
    # The boards' OpenCV 4.6.0 has GTK3: a display GTK cannot open is not a headless OpenCV.
    monkeypatch.delenv('WAYLAND_DISPLAY', raising=False)
    monkeypatch.setenv('DISPLAY', '127.0.0.1:%d' % x_listener)
    gtk3 = 'General configuration for OpenCV 4.6.0\n  GUI:                           GTK3\n' \
           '    GTK+:                        YES (ver 3.24.38)\n'

    def gtk_cannot_start(title, flags):
        raise display.cv2.error(
            'OpenCV(4.6.0) ./modules/highgui/src/window_gtk.cpp:635: error: (-2:Unspecified '
            "error) Can't initialize GTK backend in function 'cvInitSystem'\n")
    monkeypatch.setattr(display.cv2, 'getBuildInformation', lambda: gtk3)
    monkeypatch.setattr(display.cv2, 'namedWindow', gtk_cannot_start)
    reason = display.window_unavailable_reason()
    assert reason == "OpenCV's GTK3 GUI cannot open a window on DISPLAY=127.0.0.1:%d: Can't " \
        'initialize GTK backend' % x_listener
    assert 'headless' not in reason
