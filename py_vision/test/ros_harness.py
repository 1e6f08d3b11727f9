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
stopped by the test; waits poll for a condition with a deadline. Two hosts on one LAN are two
network namespaces (`TwoHosts`). The benchmarks (bench/) run on this harness too: the same
environment, domain reservations, processes and hosts.
"""

import contextlib
import fcntl
import importlib.util
import os
from pathlib import Path
import random
import re
import shutil
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


# What a shell may have set for DDS: a benchmark chooses each of these per case itself.
DDS_CHOICES = ('FASTRTPS_DEFAULT_PROFILES_FILE', 'FASTDDS_DEFAULT_PROFILES_FILE',
               'RMW_IMPLEMENTATION', 'ROS_STATIC_PEERS', 'ROS_LOCALHOST_ONLY',
               'ROS_AUTOMATIC_DISCOVERY_RANGE')


def plain_env():
    """Return installed_env() without the shell's DDS choices (DDS_CHOICES), output unbuffered."""
    env = installed_env()
    for name in DDS_CHOICES:
        env.pop(name, None)
    env['PYTHONUNBUFFERED'] = '1'
    return env


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


def signal_name(number):
    """Return the name of signal `number` (SIGSEGV for 11), or 'signal N' for one Python lacks."""
    try:
        return signal.Signals(number).name
    except ValueError:
        return 'signal %d' % number


def status_values(arrays, name):
    """Return {key: value} of the newest status `name` in collected DiagnosticArrays, or {}."""
    for array in reversed(list(arrays)):
        for status in array.status:
            if status.name == name:
                return {kv.key: kv.value for kv in status.values}
    return {}


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


# What the tests stop a process with: Ctrl-C, `kill`, a closed terminal.
STOP_SIGNALS = (signal.SIGINT, signal.SIGTERM, signal.SIGHUP)


@contextlib.contextmanager
def signals_ignored(*signals):
    """
    Ignore signals in this process for the block (main thread only), then restore them.

    A process that a non-interactive shell starts with `&` (a CI runner's script, an init
    script) starts so, with SIGINT and SIGQUIT ignored; `nohup` leaves SIGHUP ignored.
    """
    previous = {sig: signal.signal(sig, signal.SIG_IGN) for sig in signals}
    try:
        yield
    finally:
        for sig, handler in previous.items():
            # None: set outside Python, which cannot put it back; the default is closest.
            signal.signal(sig, signal.SIG_DFL if handler is None else handler)


def _ignored_stop_signals():
    return [sig for sig in STOP_SIGNALS if signal.getsignal(sig) is signal.SIG_IGN]


def _signal_resetter():
    """Return the `env` that resets signals to their default (GNU coreutils 8.31 on)."""
    if not hasattr(_signal_resetter, 'cache'):
        env = shutil.which('env')
        usable = env is not None and subprocess.run(
            [env, '--default-signal=INT', 'true'], capture_output=True).returncode == 0
        _signal_resetter.cache = env if usable else None
    if _signal_resetter.cache is None:
        raise RuntimeError(
            'the tests run with %s ignored (a script started them with `&`, or nohup did), '
            "and this machine's env cannot reset it for the processes they start: that needs "
            "GNU coreutils' env 8.31 or later (--default-signal)" % ', '.join(
                signal.Signals(sig).name for sig in _ignored_stop_signals()))
    return _signal_resetter.cache


def with_stop_signals_default(cmd):
    """
    Return cmd so that it starts with the default action for every stop signal (STOP_SIGNALS).

    A process inherits the signals its parent ignores, and a program may keep them so: Humble's
    `ros2 launch` then ignores Ctrl-C for good (it reads SIGINT through Python's own handler,
    which Python does not install where SIGINT was ignored at its start). When the tests
    themselves were started with a stop signal ignored (scripts/test.sh started by a script in
    the background), cmd is run through `env --default-signal`, which resets it and execs cmd:
    the process id is cmd's. Otherwise cmd is returned as it is.
    """
    ignored = _ignored_stop_signals()
    if not ignored:
        return list(cmd)
    names = ','.join(signal.Signals(sig).name[len('SIG'):] for sig in ignored)
    return [_signal_resetter(), '--default-signal=' + names] + list(cmd)


def _popen(cmd, env, log_fd, log_path):
    """
    Start cmd in a session of its own, its output into log_fd.

    It gets the stop signals' default action whatever this process ignores, as a command typed
    at a terminal has: the test stops it with them, and no terminal's Ctrl-C reaches its session.
    """
    return subprocess.Popen(with_stop_signals_default(cmd), env=env, stdout=log_fd,
                            stderr=subprocess.STDOUT, stdin=subprocess.DEVNULL,
                            start_new_session=True)


class NodeProcess:
    """
    One installed executable running in its own process, output captured to a file.

    `executable` is one of the package's, or a path (a Python, `ip`). Every failure it raises
    ends with the tail of the node's own log; kill() ends the process and deletes that log,
    unless it was written to `log_dir` (as `<name>.log`, kept for the caller).
    """

    def __init__(self, executable, args, env, name=None, log_dir=None, spawn=None):
        """
        Start it.

        `spawn(cmd, env, log_fd, log_path)`, when given, starts it instead of subprocess.Popen
        and returns what stands for the Popen (poll, wait, send_signal, pid, returncode).
        """
        self.name = name or executable
        if log_dir is None:
            handle, self.log_path = tempfile.mkstemp(prefix='py_vision_%s_' % self.name,
                                                     suffix='.log')
        else:
            self.log_path = str(Path(log_dir) / ('%s.log' % self.name))
            handle = os.open(self.log_path, os.O_WRONLY | os.O_CREAT | os.O_TRUNC, 0o644)
        self._keep_log = log_dir is not None
        path = executable if os.sep in executable else str(EXECUTABLES / executable)
        self.cmd = [path] + list(args)
        try:
            self.proc = (spawn or _popen)(self.cmd, env, handle, self.log_path)
        except BaseException:
            if not self._keep_log:
                os.unlink(self.log_path)
            raise
        finally:
            os.close(handle)

    @property
    def pid(self):
        """Return the process id."""
        return self.proc.pid

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
        if status is None:
            state = 'running'
        elif status < 0:  # a signal: by name, SIGSEGV says more than -11
            state = 'ended by %s' % signal_name(-status)
        else:
            state = 'exit status %s' % status
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

    def end(self, sig=signal.SIGINT, timeout=5.0):
        """
        Send sig and wait for the exit; SIGKILL the whole group if it does not end in time.

        Return True when it ended by itself (or had already), False when it had to be killed.
        """
        if self.proc.poll() is not None:
            return True
        self.proc.send_signal(sig)
        try:
            self.proc.wait(timeout)
            return True
        except subprocess.TimeoutExpired:
            os.killpg(self.proc.pid, signal.SIGKILL)
            self.proc.wait()
            return False

    def stop(self, sig=signal.SIGINT, timeout=5.0):
        """Send sig and wait for the exit; fail, the whole group killed, if it does not end."""
        if not self.end(sig, timeout):
            self.fail('%s ignored %s for %.1f s' % (
                self.name, signal.Signals(sig).name, timeout))
        return self.proc.returncode

    def kill(self):
        """
        End the process if it still runs (Ctrl-C, then SIGKILL); delete its log.

        A SIGKILLed node leaves its Fast DDS shared-memory segment in /dev/shm behind.
        """
        self.end(signal.SIGINT, timeout=5.0)
        if not self._keep_log:
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
        self._closing = threading.Event()
        self._thread = threading.Thread(target=self._spin, daemon=True)
        self._thread.start()

    def _spin(self):
        while not self._closing.is_set() and self.context.ok():
            try:
                self.executor.spin_once(timeout_sec=0.05)
            except Exception:  # the context was shut down under the executor
                if self.context.ok() and not self._closing.is_set():
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
        """Stop the executor's thread, then destroy the node and shut its context down."""
        import rclpy
        self._closing.set()
        self._thread.join(5.0)
        self.executor.shutdown()
        self.node.destroy_node()
        rclpy.shutdown(context=self.context)


def two_hosts_unavailable():
    """Return why two hosts (network namespaces) cannot be made here, or None."""
    if os.geteuid() != 0:
        return 'network namespaces need root'
    missing = [tool for tool in ('ip', 'unshare') if shutil.which(tool) is None]
    if missing:
        return 'network namespaces need the %s command' % ' and '.join(missing)
    return None


class TwoHosts:
    """
    Two hosts on one LAN: two network namespaces joined by a veth pair (root only).

    `names` are the hosts' names ('board', 'pc'); `tag` (a few digits, e.g. a domain id) keeps
    the namespaces and links of concurrent runs apart. Each host has its own address on one /24,
    its loopback, and a route for discovery's multicast out of the veth; the links are up
    before the constructor returns (Fast DDS picks its interfaces at start-up).
    `command(host, cmd)` is cmd run in a host; `close()` removes both namespaces.
    """

    def __init__(self, names=('board', 'pc'), tag=None):
        tag = str(os.getpid() % 100000 if tag is None else tag)
        subnet = int(tag) % 250
        self.names = tuple(names)
        self.namespace = {name: 'pvh%d%s' % (index, tag) for index, name in enumerate(names)}
        self.device = {name: 'pvv%d%s' % (index, tag) for index, name in enumerate(names)}
        self.address = {name: '10.215.%d.%d' % (subnet, index + 1)
                        for index, name in enumerate(names)}
        first, second = self.names
        self.close()   # what a run killed before its cleanup left
        try:
            for name in self.names:
                self._ip('netns', 'add', self.namespace[name])
            self._ip('link', 'add', self.device[first], 'netns', self.namespace[first],
                     'type', 'veth', 'peer', 'name', self.device[second],
                     'netns', self.namespace[second])
            for name in self.names:
                ns, dev = self.namespace[name], self.device[name]
                self._ip('-n', ns, 'addr', 'add', self.address[name] + '/24', 'dev', dev)
                self._ip('-n', ns, 'link', 'set', dev, 'up')
                self._ip('-n', ns, 'link', 'set', 'lo', 'up')
                # Discovery multicast leaves through the veth (there is no default route).
                self._ip('-n', ns, 'route', 'add', '224.0.0.0/4', 'dev', dev)
            for name in self.names:
                wait_until(lambda: 'state UP' in self.read(name, [
                    'ip', '-o', 'link', 'show', 'dev', self.device[name]]),
                    10, what='%s up in %s' % (self.device[name], self.namespace[name]))
        except subprocess.CalledProcessError as error:
            self.close()
            raise RuntimeError('cannot make two hosts: %s' % (
                error.stderr or error).strip()) from None

    @staticmethod
    def _ip(*args):
        subprocess.run(('ip',) + args, check=True, capture_output=True, text=True)

    def command(self, host, cmd, own_shm=True):
        """
        Return cmd as run in a host.

        own_shm: with a /dev/shm of its own (a private mount), so that Fast DDS cannot carry
        data through shared memory to the other host; processes that should share memory
        on one host run without.
        """
        wrapped = [shutil.which('ip'), 'netns', 'exec', self.namespace[host]]
        if own_shm:
            # ip netns exec, unshare and sh all exec: the pid stays the command's own.
            wrapped += ['unshare', '--mount', '--propagation', 'private', 'sh', '-c',
                        'mount -t tmpfs tmpfs /dev/shm && exec "$@"', 'sh']
        return wrapped + list(cmd)

    def read(self, host, cmd):
        """Return what cmd prints run in a host (a /proc or /sys file, a link's state)."""
        return subprocess.run(['ip', 'netns', 'exec', self.namespace[host]] + list(cmd),
                              capture_output=True, text=True).stdout

    def close(self):
        """Remove both namespaces (and so the veth pair)."""
        for ns in self.namespace.values():
            subprocess.run(['ip', 'netns', 'del', ns], capture_output=True)
