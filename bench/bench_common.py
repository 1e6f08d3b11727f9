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
What the benchmark's helper processes share: stop on a signal, write results.

Each helper (bare publisher and subscriber, instrumented py_vision nodes) records one event per
frame in memory and writes them as JSON to the file named by its caller when it stops.
"""

import json
import os
from pathlib import Path
import platform
import signal
import threading
import time

RESULTS = Path(__file__).resolve().parent / 'results'


FIRST_FRAME_MARK = 'BENCH first frame'


class StopFlag:
    """Set by SIGINT or SIGTERM, so that a process can write its results before it exits."""

    def __init__(self):
        self.event = threading.Event()
        for sig in (signal.SIGINT, signal.SIGTERM):
            signal.signal(sig, self._handle)

    def _handle(self, signum, frame):
        self.event.set()

    def is_set(self):
        return self.event.is_set()


def write_json(path, data):
    """Write data to path atomically (the caller polls for the file)."""
    tmp = path + '.tmp'
    with open(tmp, 'w') as stream:
        json.dump(data, stream)
    os.replace(tmp, path)


def save_results(name, result):
    """Write bench/results/<name>.json: result plus the versions it was measured with."""
    import cv2
    import numpy as np
    result = dict(result, python=platform.python_version(), numpy=np.__version__,
                  opencv=cv2.__version__, machine=platform.machine())
    RESULTS.mkdir(exist_ok=True)
    out = RESULTS / (name + '.json')
    out.write_text(json.dumps(result, indent=2) + '\n')
    print('\nwrote %s' % out)


def image_qos(reliability):
    """Return the reference's QoS: keep last 10, 'reliable' or best effort."""
    from rclpy.qos import HistoryPolicy, QoSProfile, ReliabilityPolicy
    return QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=10, reliability=(
        ReliabilityPolicy.RELIABLE if reliability == 'reliable'
        else ReliabilityPolicy.BEST_EFFORT))


def announce_first_frame():
    """Tell the benchmark (which reads this process' output) that frames are arriving."""
    print(FIRST_FRAME_MARK, flush=True)


def monotonic():
    """Return the time every helper records events with (system-wide, also in namespaces)."""
    return time.monotonic()


def local_node_env():
    """
    Return the environment of the node processes a benchmark starts, discovery on this host.

    The node processes get the installed package; this process joins them the same way, on
    the nodes' transport. For benchmarks that have put the tests' directory (ros_harness) and
    the installed py_vision on sys.path.
    """
    import ros_harness
    from py_vision import dds
    env = ros_harness.installed_env()
    env.update(ROS_AUTOMATIC_DISCOVERY_RANGE='LOCALHOST', PYTHONUNBUFFERED='1',
               RCUTILS_COLORIZED_OUTPUT='0')
    env.pop('ROS_LOCALHOST_ONLY', None)
    os.environ.update(AMENT_PREFIX_PATH=env['AMENT_PREFIX_PATH'],
                      ROS_AUTOMATIC_DISCOVERY_RANGE='LOCALHOST')
    dds.use_packaged_profile()
    return env
