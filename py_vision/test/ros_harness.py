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
Run the colcon-installed py_vision executables and real ROS 2 peers from tests.

Every test gets its own ROS_DOMAIN_ID (reserved with a lock file, so concurrent pytest runs on
one machine never share one) and discovery stays on the local host. Processes a test starts are
stopped by the test; waits poll for a condition with a deadline.
"""

import fcntl
import os
from pathlib import Path
import random
import re
import signal
import subprocess
import sys
import tempfile
import threading
import time

REPO = Path(__file__).resolve().parents[2]
INSTALL = Path(os.environ.get('PY_VISION_INSTALL', REPO / 'install')).resolve()
EXECUTABLES = INSTALL / 'py_vision' / 'lib' / 'py_vision'
SITE_PACKAGES = INSTALL / 'py_vision' / 'lib' / ('python%d.%d' % sys.version_info[:2]) / \
    'site-packages'

# Fast DDS accepts domain ids up to 232 with the default port mapping.
_DOMAIN_RANGE = range(1, 200)
_LOCK_DIR = Path(tempfile.gettempdir()) / 'py_vision_test_domains'


def installed_env():
    """Return os.environ plus what `source install/setup.bash` adds (computed once)."""
    if not hasattr(installed_env, 'cache'):
        setup = INSTALL / 'setup.bash'
        if not setup.is_file():
            raise RuntimeError('%s is missing: build first with scripts/setup.sh' % setup)
        out = subprocess.run(['bash', '-c', 'source "$0" && env -0', str(setup)],
                             check=True, capture_output=True).stdout
        installed_env.cache = dict(
            item.split('=', 1) for item in out.decode().split('\0') if '=' in item)
    return dict(installed_env.cache)


class DomainId:
    """An exclusive ROS_DOMAIN_ID for one test, held through a lock file."""

    def __init__(self):
        _LOCK_DIR.mkdir(exist_ok=True)
        ids = list(_DOMAIN_RANGE)
        random.shuffle(ids)
        for candidate in ids:
            handle = open(_LOCK_DIR / ('%d.lock' % candidate), 'w')
            try:
                fcntl.flock(handle, fcntl.LOCK_EX | fcntl.LOCK_NB)
            except OSError:
                handle.close()
                continue
            self.value, self._handle = candidate, handle
            return
        raise RuntimeError('no free ROS_DOMAIN_ID for the test')

    def release(self):
        self._handle.close()


def wait_until(predicate, timeout, interval=0.02, what='condition'):
    """Poll predicate until it returns something truthy; fail after timeout seconds."""
    deadline = time.monotonic() + timeout
    while True:
        result = predicate()
        if result:
            return result
        if time.monotonic() > deadline:
            raise AssertionError('timed out after %.1f s waiting for %s' % (timeout, what))
        time.sleep(interval)


def ros_args(params=None, remaps=None):
    """Build a `--ros-args` command line tail from parameter and remapping dicts."""
    args = ['--ros-args']
    for name, value in (params or {}).items():
        if isinstance(value, bool):
            value = 'true' if value else 'false'
        args += ['-p', '%s:=%s' % (name, value)]
    for old, new in (remaps or {}).items():
        args += ['-r', '%s:=%s' % (old, new)]
    return args


class NodeProcess:
    """One installed executable running in its own process, output captured to a file."""

    def __init__(self, executable, args, env, name=None):
        self.name = name or executable
        self._log = tempfile.NamedTemporaryFile(prefix='py_vision_%s_' % self.name,
                                                suffix='.log', delete=False)
        path = executable if os.sep in executable else str(EXECUTABLES / executable)
        self.cmd = [path] + list(args)
        self.proc = subprocess.Popen(self.cmd, env=env, stdout=self._log,
                                     stderr=subprocess.STDOUT, stdin=subprocess.DEVNULL,
                                     start_new_session=True)

    def output(self):
        """Everything the process printed so far (stdout and stderr interleaved)."""
        return Path(self._log.name).read_text(errors='replace')

    def wait_for_output(self, pattern, timeout=20.0):
        """Wait until the output matches the regex pattern; return the match."""
        regex = re.compile(pattern)

        def found():
            match = regex.search(self.output())
            if not match and self.proc.poll() is not None:
                raise AssertionError('%s exited with %s before printing %r:\n%s' % (
                    self.name, self.proc.returncode, pattern, self.output()))
            return match
        return wait_until(found, timeout, 0.05, 'output %r from %s' % (pattern, self.name))

    def wait_exit(self, timeout=10.0):
        """Wait for the process to end by itself; return its exit status."""
        try:
            return self.proc.wait(timeout)
        except subprocess.TimeoutExpired:
            raise AssertionError('%s still running after %.1f s:\n%s' % (
                self.name, timeout, self.output()))

    def stop(self, sig=signal.SIGINT, timeout=5.0):
        """Send sig and wait for the exit; kill the whole group if it does not end in time."""
        if self.proc.poll() is None:
            self.proc.send_signal(sig)
            try:
                self.proc.wait(timeout)
            except subprocess.TimeoutExpired:
                os.killpg(self.proc.pid, signal.SIGKILL)
                self.proc.wait()
                raise AssertionError('%s ignored %s for %.1f s:\n%s' % (
                    self.name, signal.Signals(sig).name, timeout, self.output()))
        return self.proc.returncode

    def kill(self):
        """
        End the process if it still runs: Ctrl-C first, SIGKILL only if that fails.

        A SIGKILLed node leaves its Fast DDS shared-memory segment in /dev/shm behind.
        """
        if self.proc.poll() is None:
            try:
                self.stop(signal.SIGINT, timeout=5.0)
            except AssertionError:
                pass  # stop() has killed it
        self._log.close()


class RosPeer:
    """An in-process rclpy node on its own context and executor thread, for test probes."""

    def __init__(self, domain_id, name='test_peer'):
        import rclpy
        from rclpy.executors import SingleThreadedExecutor
        self.context = rclpy.Context()
        rclpy.init(context=self.context, domain_id=domain_id)
        self.node = rclpy.create_node(name, context=self.context)
        self.executor = SingleThreadedExecutor(context=self.context)
        self.executor.add_node(self.node)
        self._thread = threading.Thread(target=self._spin, daemon=True)
        self._thread.start()

    def _spin(self):
        while self.context.ok():
            try:
                self.executor.spin_once(timeout_sec=0.05)
            except Exception:  # the context was shut down under the executor
                if self.context.ok():
                    raise
                return

    def collect(self, msg_type, topic, qos=None):
        """Subscribe and return the list every received message is appended to."""
        from rclpy.qos import QoSProfile, ReliabilityPolicy
        received = []
        if qos is None:
            qos = QoSProfile(depth=100, reliability=ReliabilityPolicy.BEST_EFFORT)
        self.node.create_subscription(msg_type, topic, received.append, qos)
        return received

    def close(self):
        import rclpy
        self.executor.shutdown()
        self.node.destroy_node()
        rclpy.shutdown(context=self.context)
        self._thread.join(2.0)
