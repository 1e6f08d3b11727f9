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

"""py_vision: USB camera streaming, display and a pure-Python cv_bridge for ROS 2."""

import os
import signal
import sys
import threading

EXECUTABLES = ('usbcam_publisher', 'usbcam_subscriber', 'cv_bridge_test')


def _exit_quietly(signum, frame):
    # Nothing exists yet that needs cleaning up (no node, device or DDS participant), and an
    # exception raised here could surface inside a C extension's import as an ImportError.
    sys.stdout.flush()
    os._exit(0)


# Importing rclpy, numpy and OpenCV takes a second or more on a board. When this package is
# imported by one of its own executables, Ctrl-C or SIGTERM during that time ends the process
# quietly instead of printing a KeyboardInterrupt traceback; node_main.run() then installs its
# own handler, which makes a signal a request to stop the node. Library users keep their own
# signal handling.
if (os.path.basename(sys.argv[0] if sys.argv else '') in EXECUTABLES
        and threading.current_thread() is threading.main_thread()):
    for _signal in (signal.SIGINT, signal.SIGTERM):
        signal.signal(_signal, _exit_quietly)
