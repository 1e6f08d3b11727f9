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
What the benchmarks share beyond the tests' harness, which they run on.

Importing this module puts the tests' directory and the installed py_vision (what the nodes
run) on sys.path: `ros_harness` (the installed package's environment, ROS domain reservations,
node processes, two hosts) is the benchmarks' harness too. Here: what a benchmark measures a
process by (/proc CPU ticks), its helper processes (`start_helper`: a command whose results
file is '{out}'), and what the helpers themselves share: stop on a signal, announce the first
frame, write results. Each helper (bare
publisher and subscriber, instrumented py_vision nodes) records one event per frame in memory
and writes them as JSON to the file named by its caller when it stops.
"""

from contextlib import contextmanager
import json
import os
from pathlib import Path
import platform
import signal
import sys
import threading
import time

BENCH = Path(__file__).resolve().parent
REPO = BENCH.parent
RESULTS = BENCH / 'results'
TESTS = REPO / 'py_vision' / 'test'
if str(TESTS) not in sys.path:
    sys.path.insert(0, str(TESTS))
import ros_harness  # noqa: E402 (found through the path set just above)
if str(ros_harness.SITE_PACKAGES) not in sys.path:
    sys.path.insert(0, str(ros_harness.SITE_PACKAGES))

FIRST_FRAME_MARK = 'BENCH first frame'
CLK_TCK = os.sysconf('SC_CLK_TCK')


def cpu_ticks(pid):
    """Return utime + stime of a process in clock ticks, or None when it is gone."""
    try:
        with open('/proc/%d/stat' % pid) as stream:
            fields = stream.read().rsplit(')', 1)[1].split()
    except OSError:
        return None
    return int(fields[11]) + int(fields[12])


def machine_ticks():
    """Return (busy, total) jiffies of the whole machine."""
    with open('/proc/stat') as stream:
        values = [int(v) for v in stream.readline().split()[1:]]
    idle = values[3] + values[4]
    total = sum(values[:8])
    return total - idle, total


def start_helper(name, cmd, env, workdir, wrap=None):
    """
    Start a helper process: '{out}' in cmd is its results file, workdir/<name>.json.

    Its output goes to workdir/<name>.log (`output()`); wrap, if given, turns the command
    into another (TwoHosts.command: run on a host). Stop it with `end()`, read what it wrote
    with `read_results(proc)`.
    """
    out = Path(workdir) / ('%s.json' % name)
    cmd = [part.replace('{out}', str(out)) for part in cmd]
    if wrap is not None:
        cmd = wrap(cmd)
    proc = ros_harness.NodeProcess(cmd[0], cmd[1:], env, name=name, log_dir=workdir)
    proc.results_path = out
    return proc


def read_results(proc):
    """Return what a helper wrote to its results file, or None."""
    try:
        return json.loads(proc.results_path.read_text())
    except (OSError, ValueError):
        return None


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
    the nodes' transport.
    """
    from py_vision import dds
    env = ros_harness.installed_env()
    env.update(ROS_AUTOMATIC_DISCOVERY_RANGE='LOCALHOST', PYTHONUNBUFFERED='1',
               RCUTILS_COLORIZED_OUTPUT='0')
    env.pop('ROS_LOCALHOST_ONLY', None)
    os.environ.update(AMENT_PREFIX_PATH=env['AMENT_PREFIX_PATH'],
                      ROS_AUTOMATIC_DISCOVERY_RANGE='LOCALHOST')
    dds.use_packaged_profile()
    return env


class Ended:
    """How the processes of stopped_after ended: their exit statuses and the node's log."""

    status: tuple = ()
    log: str = ''


@contextmanager
def stopped_after(domain, peer, node, *others):
    """
    Run the with-block, then close the peer, stop the node and the others, free the domain.

    The block gets an `Ended`, which holds the exit statuses and the node's log afterwards.

    Each process gets SIGINT and 15 s, then is killed. When the block ended normally, a process
    that did not exit 0, or a traceback in the node's log, ends the benchmark (SystemExit with
    the node's log); an exception of the block's own goes on as it is.
    """
    ended = Ended()
    try:
        yield ended
    finally:
        peer.close()
        ended.status = tuple(proc.stop(signal.SIGINT, 15.0) for proc in (node,) + others)
        ended.log = node.output()
        for proc in (node,) + others:
            proc.kill()
        domain.release()
    if any(ended.status) or 'Traceback' in ended.log:
        raise SystemExit('%s ended with %s:\n%s' % (node.name, ended.status, ended.log))


# vision_step's status in /diagnostics, and how long a fresh report may take (one a second).
PROCESSING = 'vision_step: processing'
REPORT_S = 10.0


def processing_values(arrays):
    """Return the newest {key: value} of vision_step's processing status, or {}."""
    return ros_harness.status_values(arrays, PROCESSING)


def fresh_report(arrays):
    """Wait for a report of vision_step's newer than those collected; return its values."""
    def reports():  # other nodes' /diagnostics come on the same topic
        return sum(1 for array in list(arrays)
                   if any(status.name == PROCESSING for status in array.status))
    count = reports()
    ros_harness.wait_until(lambda: reports() > count, REPORT_S, 0.01,
                           "a report of vision_step's on /diagnostics")
    return processing_values(arrays)


def print_shares(title, shares, total_ms, digits=2):
    """Print a table of {name: share of total_ms} as shares and ms a frame, largest first."""
    print('\n| %s | share | ms a frame |\n|---|---:|---:|' % title)
    for name, share in sorted(shares.items(), key=lambda item: -item[1]):
        print('| %s | %.0f%% | %.*f |' % (name, 100.0 * share, digits, share * total_ms))
