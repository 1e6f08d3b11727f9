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
import importlib.util
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

PACKAGE = 'py_vision'
REPO = Path(__file__).resolve().parents[2]
_INDEX_MARKER = Path('share', 'ament_index', 'resource_index', 'packages', PACKAGE)


def _find_prefix():
    """
    Return the colcon prefix py_vision is installed in, and whether the environment has it.

    PY_VISION_INSTALL (a colcon install base) comes first, then install/ beside the package
    source (what scripts/setup.sh builds), then the environment: what `colcon test` gives the
    tests, or a sourced install/setup.bash (AMENT_PREFIX_PATH). Without any of them the first
    two name the place conftest.py reports as missing.
    """
    base = os.environ.get('PY_VISION_INSTALL')
    if base:
        return Path(base).resolve() / PACKAGE, False
    beside = REPO / 'install' / PACKAGE
    if beside.is_dir():
        return beside, False
    for prefix in os.environ.get('AMENT_PREFIX_PATH', '').split(os.pathsep):
        if prefix and (Path(prefix) / _INDEX_MARKER).is_file():
            return Path(prefix).resolve(), True
    return beside, False


PREFIX, FROM_ENVIRONMENT = _find_prefix()
EXECUTABLES = PREFIX / 'lib' / PACKAGE
SITE_PACKAGES = PREFIX / 'lib' / ('python%d.%d' % sys.version_info[:2]) / 'site-packages'
SHARE = PREFIX / 'share' / PACKAGE
# How many lines of a node's log a failure message shows.
LOG_TAIL_LINES = 40


def _rclpy_version():
    """Return the (major, minor, patch) of the rclpy tests import, from its package.xml."""
    # <prefix>/lib/pythonX.Y/site-packages/rclpy/__init__.py; <prefix>/share/rclpy/package.xml
    prefix = Path(importlib.util.find_spec('rclpy').origin).parents[4]
    text = (prefix / 'share' / 'rclpy' / 'package.xml').read_text()
    return tuple(int(part) for part in re.search(
        r'<version>(\d+)\.(\d+)\.(\d+)</version>', text).groups())


RCLPY_VERSION = _rclpy_version()
# rclpy 3.x is ROS 2 Humble's (the boards'); Iron has 4.x, Jazzy 7.x.
ON_HUMBLE = RCLPY_VERSION < (4,)
# Why a test of a discovery setting Humble does not have is skipped there.
FROM_IRON = 'ROS_AUTOMATIC_DISCOVERY_RANGE and ROS_STATIC_PEERS exist from Iron on (Humble: ' \
    'ROS_LOCALHOST_ONLY)'


def with_discovery(env, scope='localhost', peers=''):
    """
    Set ROS discovery in env (a dict, or os.environ) to scope, as this distribution spells it.

    scope: 'localhost' (this host only), 'subnet' (the network) or 'off' (this process only,
    Iron on). Humble knows only ROS_LOCALHOST_ONLY, which Iron on deprecate (with a warning at
    every start) for ROS_AUTOMATIC_DISCOVERY_RANGE. peers: ROS_STATIC_PEERS, from Iron on;
    Humble's discovery is multicast alone. Returns env.
    """
    for name in ('ROS_LOCALHOST_ONLY', 'ROS_AUTOMATIC_DISCOVERY_RANGE', 'ROS_STATIC_PEERS'):
        env.pop(name, None)
    if ON_HUMBLE:
        if scope == 'off':
            raise ValueError('discovery off needs Iron or later: ' + FROM_IRON)
        if scope == 'localhost':
            env['ROS_LOCALHOST_ONLY'] = '1'
    else:
        env['ROS_AUTOMATIC_DISCOVERY_RANGE'] = scope.upper()
        if peers:
            env['ROS_STATIC_PEERS'] = peers
    return env


# Fast DDS accepts domain ids up to 232 with the default port mapping.
_DOMAIN_RANGE = range(1, 200)
_LOCK_DIR = Path(tempfile.gettempdir()) / 'py_vision_test_domains'


def installed_env():
    """
    Return the environment the installed executables run in (computed once).

    That is os.environ plus what `source install/setup.bash` adds, or, when the environment
    already has the package (`colcon test`, a sourced workspace), os.environ with the package's
    Python path made sure of.
    """
    if not hasattr(installed_env, 'cache'):
        if FROM_ENVIRONMENT:
            env = dict(os.environ)
            paths = env.get('PYTHONPATH', '').split(os.pathsep)
            if str(SITE_PACKAGES) not in paths:
                env['PYTHONPATH'] = os.pathsep.join([str(SITE_PACKAGES)] + [p for p in paths if p])
        else:
            setup = PREFIX.parent / 'setup.bash'
            if not setup.is_file():
                raise RuntimeError('%s is missing: build first with scripts/setup.sh' % setup)
            out = subprocess.run(['bash', '-c', 'source "$0" && env -0', str(setup)],
                                 check=True, capture_output=True).stdout
            env = dict(item.split('=', 1) for item in out.decode().split('\0') if '=' in item)
        installed_env.cache = env
    return dict(installed_env.cache)


def import_installed_package():
    """Make this process import the installed py_vision and find it in the ament index."""
    # Before the source folder that `python -m pytest` (and so `colcon test`) puts on sys.path.
    sys.path.insert(0, str(SITE_PACKAGES))
    # As after `source install/setup.bash`, for code that looks itself up in the ament index.
    os.environ['AMENT_PREFIX_PATH'] = installed_env()['AMENT_PREFIX_PATH']


def node_env(domain_id, log_dir):
    """
    Return the environment for node processes on a test's domain.

    That is the installed package, that domain, discovery kept on this host, and the nodes'
    rcl log files in log_dir.
    """
    env = installed_env()
    env.update(ROS_DOMAIN_ID=str(domain_id), PYTHONUNBUFFERED='1', RCUTILS_COLORIZED_OUTPUT='0',
               ROS_LOG_DIR=log_dir)
    return with_discovery(env, 'localhost')


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


def end_process_group(proc, timeout=5.0):
    """End a process started with start_new_session: Ctrl-C to its group, SIGKILL if need be."""
    if proc.poll() is None:
        os.killpg(proc.pid, signal.SIGINT)
        try:
            proc.wait(timeout)
        except subprocess.TimeoutExpired:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.wait()


class NodeProcess:
    """
    One installed executable running in its own process, output captured to a file.

    Every failure it raises ends with the tail of the node's own log; kill() ends the process
    and deletes that log.
    """

    def __init__(self, executable, args, env, name=None):
        self.name = name or executable
        handle, self.log_path = tempfile.mkstemp(prefix='py_vision_%s_' % self.name,
                                                 suffix='.log')
        path = executable if os.sep in executable else str(EXECUTABLES / executable)
        self.cmd = [path] + list(args)
        try:
            self.proc = subprocess.Popen(self.cmd, env=env, stdout=handle,
                                         stderr=subprocess.STDOUT, stdin=subprocess.DEVNULL,
                                         start_new_session=True)
        except BaseException:
            os.unlink(self.log_path)
            raise
        finally:
            os.close(handle)

    def output(self):
        """Everything the process printed so far (stdout and stderr interleaved)."""
        return Path(self.log_path).read_text(errors='replace')

    def tail(self, lines=LOG_TAIL_LINES):
        """Return the last lines of the output, headed by the command and its state."""
        try:
            text = self.output()
        except OSError as error:  # already deleted by kill()
            text = '(log unavailable: %s)' % error
        kept = text.splitlines()[-lines:]
        status = self.proc.poll()
        state = 'running' if status is None else 'exit status %s' % status
        return '--- %s (%s), last %d lines of its log: %s\n%s' % (
            self.name, state, len(kept), ' '.join(self.cmd), '\n'.join(kept))

    def fail(self, message):
        """Raise AssertionError with message followed by the tail of the node's log."""
        # from None: a timeout re-raised here is one message, not a chain of two.
        raise AssertionError('%s\n%s' % (message, self.tail())) from None

    def wait_for_output(self, pattern, timeout=20.0):
        """Wait until the output matches the regex pattern; return the match."""
        regex = re.compile(pattern)
        try:
            wait_until(lambda: regex.search(self.output()) or self.proc.poll() is not None,
                       timeout, 0.05, 'output %r from %s' % (pattern, self.name))
        except AssertionError as error:
            self.fail(str(error))
        match = regex.search(self.output())
        if not match:
            self.fail('%s exited with %s before printing %r' % (
                self.name, self.proc.returncode, pattern))
        return match

    def wait_exit(self, timeout=10.0):
        """Wait for the process to end by itself; return its exit status."""
        try:
            return self.proc.wait(timeout)
        except subprocess.TimeoutExpired:
            self.fail('%s still running after %.1f s' % (self.name, timeout))

    def stop(self, sig=signal.SIGINT, timeout=5.0):
        """Send sig and wait for the exit; kill the whole group if it does not end in time."""
        if self.proc.poll() is None:
            self.proc.send_signal(sig)
            try:
                self.proc.wait(timeout)
            except subprocess.TimeoutExpired:
                os.killpg(self.proc.pid, signal.SIGKILL)
                self.proc.wait()
                self.fail('%s ignored %s for %.1f s' % (
                    self.name, signal.Signals(sig).name, timeout))
        return self.proc.returncode

    def kill(self):
        """
        End the process if it still runs (Ctrl-C, then SIGKILL); delete its log.

        A SIGKILLed node leaves its Fast DDS shared-memory segment in /dev/shm behind.
        """
        if self.proc.poll() is None:
            try:
                self.stop(signal.SIGINT, timeout=5.0)
            except AssertionError:
                pass  # stop() has killed it
        try:
            os.unlink(self.log_path)
        except FileNotFoundError:
            pass


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
