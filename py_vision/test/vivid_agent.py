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
The agent inside the vivid VM: runs the functions the host-side tests send it (vivid_vm.py).

The VM boots with this file as its program, on the host's own file system (PY_VISION_INSTALL
names the colcon install base). The agent brings the loopback up, loads vivid, imports Python,
rclpy, numpy, OpenCV and py_vision once, says it is ready (`ready.json` in the directory it
shares with the host) and then, for each request the host writes to `requests/`, forks a child
that calls the requested function with a `Vm` (the device, nodes, a peer, a ROS domain of its
own) and writes what the function returned, or why it failed, to `answers/`.

A program started afresh takes tens of seconds on the emulated CPU (the interpreter, then
rclpy, numpy and OpenCV: thousands of files and page faults), so nodes are not exec'ed: the
agent forks them from itself, where nothing is initialised yet, and the child runs the
installed executable's own script as `__main__` with its arguments and environment. That is
what exec would run, less the interpreter's start-up. Only the agent forks nodes, never a
function's child, which has a ROS context and DDS threads that a fork must not copy: the
child asks the agent over a socket.
"""

import atexit
import contextlib
import importlib.util
import json
import os
from pathlib import Path
import pickle
import runpy
import select
import shutil
import signal
import socket
import subprocess
import sys
import tempfile
import time
import traceback

import ros_harness
from ros_harness import NodeProcess
import v4l2_ioctl

POLL_S = 0.05
SYSFS_DRIVER = Path('/sys/bus/platform/drivers/vivid')
VIDEO4LINUX = Path('/sys/class/video4linux')


def log(message):
    """Print a line on the VM's console, which the host keeps for its failure messages."""
    print('[vivid agent] %s' % message, flush=True)


def run(cmd, check=True):
    """Run a command and return its output; RuntimeError with that output if it fails."""
    result = subprocess.run(cmd, capture_output=True, text=True)
    if check and result.returncode != 0:
        raise RuntimeError('%s failed (status %d): %s' % (
            ' '.join(cmd), result.returncode, (result.stdout + result.stderr).strip()))
    return result.stdout


def write_atomically(path, data):
    tmp = path.with_name('.' + path.name)
    tmp.write_bytes(data)
    os.replace(tmp, path)


class Vivid:
    """The vivid module and its devices: loaded with options, reset, unbound and bound."""

    def __init__(self):
        self.options = None
        self.unbound = []

    def load(self, options):
        """Load vivid with these module options (again, if they changed); return the device."""
        if options != self.options:
            if self.options is not None:
                run(['rmmod', 'vivid'])
            self.options = None
            run(['modprobe', 'vivid'] + options.split())
            self.options = options
        return self.device()

    def unbind(self):
        """Unbind every vivid instance from its driver: its devices vanish, as unplugged."""
        names = sorted(p.name for p in SYSFS_DRIVER.iterdir() if p.name.startswith('vivid.'))
        for name in names:
            (SYSFS_DRIVER / 'unbind').write_text(name)
        self.unbound += names

    def bind(self):
        """Bind them again: the devices come back, every control at its default."""
        while self.unbound:
            (SYSFS_DRIVER / 'bind').write_text(self.unbound.pop(0))
        return self.device()

    def reset(self):
        """Every control back to its default, as a device unplugged and plugged again."""
        self.unbind()
        return self.bind()

    def device(self, timeout=30.0):
        """Return /dev/videoN of vivid's first capture node, waiting for it to appear."""
        deadline = time.monotonic() + timeout
        while True:
            for node in sorted(VIDEO4LINUX.glob('video*')):
                with contextlib.suppress(OSError):
                    name = (node / 'name').read_text().strip()
                    path = Path('/dev', node.name)
                    if name.endswith('-vid-cap') and path.exists():
                        return str(path)
            if time.monotonic() > deadline:
                raise RuntimeError('no vivid capture device appeared within %.0f s' % timeout)
            time.sleep(0.05)


class ForkedProcess:
    """What NodeProcess needs of a Popen, for a node the agent forked and reaps."""

    def __init__(self, pid, status_dir):
        self.pid = pid
        self.returncode = None
        self._status = Path(status_dir, str(pid))

    def poll(self):
        if self.returncode is None and self._status.exists():
            self.returncode = int(self._status.read_text())
        return self.returncode

    def wait(self, timeout=None):
        deadline = None if timeout is None else time.monotonic() + timeout
        while self.poll() is None:
            if deadline is not None and time.monotonic() > deadline:
                raise subprocess.TimeoutExpired(str(self.pid), timeout)
            time.sleep(0.02)
        return self.returncode

    def send_signal(self, sig):
        if self.poll() is None:
            with contextlib.suppress(ProcessLookupError):
                os.kill(self.pid, sig)


class Vm:
    """
    What a function running in the VM gets: the device, nodes, a peer, a ROS domain of its own.

    `device` is vivid's capture node (/dev/video0); `launch()` starts an installed executable
    as the `launch` fixture does and returns a NodeProcess (output, wait_for_output, stop, ...);
    `peer` is an in-process rclpy node on the domain; `control()` and `set_control()` read and
    write a control through the kernel, by its V4L2 name or parameter name; `unplug()` and
    `plug()` unbind and bind the driver through sysfs. Whatever the function started is
    stopped when it returns.
    """

    def __init__(self, vivid, device, launcher):
        self.vivid, self.device, self._launcher = vivid, device, launcher
        self._domain = ros_harness.DomainId()
        self.domain_id = self._domain.value
        self._log_dir = tempfile.mkdtemp(prefix='py_vision_ros_log_')
        self.env = ros_harness.node_env(self.domain_id, self._log_dir)
        # The peer, in this process, as the nodes: this host only, logs in the call's folder.
        os.environ.pop('ROS_LOCALHOST_ONLY', None)
        os.environ.update(ROS_AUTOMATIC_DISCOVERY_RANGE='LOCALHOST', ROS_LOG_DIR=self._log_dir)
        self.nodes = []
        self._peer = None

    def launch(self, executable, params=None, remaps=None, extra_args=(), name=None):
        """Start an installed executable with parameters and remappings given as dicts."""
        args = ros_harness.ros_args(params, remaps) + list(extra_args)
        node = NodeProcess(executable, args, self.env, name, spawn=self._launcher)
        self.nodes.append(node)
        return node

    @property
    def peer(self):
        """Return an in-process rclpy node on this function's domain, made at first use."""
        if self._peer is None:
            self._peer = ros_harness.RosPeer(self.domain_id)
        return self._peer

    @contextlib.contextmanager
    def _open(self):
        fd = v4l2_ioctl.open_device(self.device)
        try:
            yield fd
        finally:
            os.close(fd)

    def formats(self):
        """
        Return what the device offers, by the kernel: [(fourcc, description, sizes)].

        sizes maps each discrete (width, height) to its rates in frames per second.
        """
        found = []
        with self._open() as fd:
            for code, _, description in v4l2_ioctl.enum_formats(fd):
                found.append((code, description, {
                    size: [den / num for num, den in v4l2_ioctl.enum_intervals(fd, code, *size)]
                    for size in v4l2_ioctl.enum_sizes(fd, code)}))
        return found

    def controls(self):
        """
        Return every control the device lists (VIDIOC_QUERY_EXT_CTRL), classes too.

        A menu's entries are in `menu` ({index: name}), an integer menu's too ({index: value}).
        """
        found = []
        with self._open() as fd:
            for info in v4l2_ioctl.list_ext_controls(fd):
                if info['type'] in (v4l2_ioctl.CTRL_TYPE_MENU,
                                    v4l2_ioctl.CTRL_TYPE_INTEGER_MENU):
                    info['menu'] = menu_entries(fd, info)
                found.append(info)
        return found

    def _control(self, fd, name):
        from py_vision.control_names import param_name
        for control in v4l2_ioctl.list_ext_controls(fd):
            if name in (control['name'], param_name(control['name'])):
                return control['id'], control['type'] == v4l2_ioctl.CTRL_TYPE_INTEGER64
        raise AssertionError('%s has no control %r' % (self.device, name))

    def control(self, name):
        """Return a control's current value on the device (VIDIOC_G_EXT_CTRLS), by name."""
        with self._open() as fd:
            cid, wide = self._control(fd, name)
            return v4l2_ioctl.get_ext_controls(fd, [cid], wide)[0]

    def set_control(self, name, value=0):
        """Set a control on the device (VIDIOC_S_EXT_CTRLS), by name; a button is pressed."""
        with self._open() as fd:
            cid, wide = self._control(fd, name)
            return v4l2_ioctl.set_ext_controls(fd, [(cid, value)], wide)[0]

    def unplug(self):
        """Unbind the driver from the device, as an unplug: the /dev node vanishes."""
        self.vivid.unbind()

    def plug(self):
        """Bind it again: the device is back, every control at its default; its path."""
        self.device = self.vivid.bind()
        return self.device

    def open_by(self, pid):
        """Return whether process pid has a handle of the device, unplugged or not."""
        return any(held.startswith('fd ') for held in self.held_by(pid))

    def held_by(self, pid):
        """
        Return what of the device process pid holds: its handles and its mappings of it.

        An unplugged device's node is gone: a handle or mapping of it reads
        '/dev/videoN (deleted)'.
        """
        held = []
        with contextlib.suppress(OSError):
            for fd in Path('/proc', str(pid), 'fd').iterdir():
                with contextlib.suppress(OSError):
                    target = os.readlink(fd)
                    if target.split(' (deleted)')[0] == self.device:
                        held.append('fd %s -> %s' % (fd.name, target))
            for line in Path('/proc', str(pid), 'maps').read_text().splitlines():
                if line.split(' (deleted)')[0].endswith(' ' + self.device):
                    held.append('mapped: ' + line)
        return held

    def dmesg(self, lines=20):
        """Return the kernel log's last lines (vivid logs there what it was made to do)."""
        return run(['dmesg'], check=False).splitlines()[-lines:]

    def close(self):
        for node in self.nodes:
            node.kill()
        if self._peer is not None:
            self._peer.close()
        self._domain.release()
        shutil.rmtree(self._log_dir, ignore_errors=True)


def menu_entries(fd, info):
    """Return {index: name, or value for an integer menu} of the entries the driver has."""
    query = v4l2_ioctl.query_int_menu if info['type'] == v4l2_ioctl.CTRL_TYPE_INTEGER_MENU \
        else v4l2_ioctl.query_menu
    entries = {}
    for index in range(info['min'], info['max'] + 1):
        with contextlib.suppress(OSError):
            entries[index] = query(fd, info['id'], index)
    return entries


class Agent:
    """Serves the host's requests one at a time, each in a child, and forks nodes for it."""

    def __init__(self, shared, vivid):
        self.shared = Path(shared)
        self.requests = self.shared / 'requests'
        self.answers = self.shared / 'answers'
        for folder in (self.requests, self.answers):
            folder.mkdir(exist_ok=True)
        self.status_dir = Path(tempfile.mkdtemp(prefix='py_vision_vivid_status_'))
        self.vivid = vivid
        self.call = None      # (request id, child pid, the agent's end of its socket)
        self.call_nodes = []  # the nodes forked for the running call
        self.used = False     # the device has served a call since it was last reset

    def serve(self):
        """Run requests until the host asks to quit."""
        while True:
            self.reap()
            if self.call is not None:
                self.serve_call()
                continue
            request = self.next_request()
            if request is None:
                time.sleep(POLL_S)
            elif request['kind'] == 'quit':
                return
            else:
                self.start_call(request)

    def next_request(self):
        names = sorted(p.name for p in self.requests.iterdir() if not p.name.startswith('.'))
        if not names:
            return None
        path = self.requests / names[0]
        request = pickle.loads(path.read_bytes())
        path.unlink()
        return request

    def start_call(self, request):
        try:
            if self.used and request['vivid_options'] == self.vivid.options:
                self.vivid.reset()
            device = self.vivid.load(request['vivid_options'])
        except Exception:
            self.answer(request['id'], {'error': traceback.format_exc()})
            return
        self.used = True
        ours, theirs = socket.socketpair()
        pid = os.fork()
        if pid == 0:
            code = 1
            try:
                ours.close()
                run_call(request, self.vivid, device, theirs, self.status_dir, self.answers)
                code = 0
            except BaseException:  # the call's own clean-up failed: that is its answer
                self.answer(request['id'], {'error': traceback.format_exc()})
            finally:
                os._exit(code)
        theirs.close()
        self.call = (request['id'], pid, ours)
        self.call_nodes = []

    def answer(self, ident, answer):
        write_atomically(self.answers / ident, pickle.dumps(answer))

    def serve_call(self):
        """Fork the nodes the running call asks for; end it once its child has ended."""
        ident, pid, sock = self.call
        ready, _, _ = select.select([sock], [], [], POLL_S)
        if ready:
            asked = recv_message(sock)
            if asked is not None:
                node = os.fork()
                if node == 0:
                    sock.close()
                    run_node(*asked)  # never returns
                self.call_nodes.append(node)
                send_message(sock, node)
        status = self.status_dir / str(pid)
        if not status.exists():
            return
        sock.close()
        for node in self.call_nodes:  # whatever the call left running
            with contextlib.suppress(ProcessLookupError):
                os.killpg(node, signal.SIGKILL)
        if not (self.answers / ident).exists():
            self.answer(ident, {'error': 'the call ended without an answer (exit status %s)'
                                % status.read_text()})
        self.call = None

    def reap(self):
        while True:
            try:
                pid, status = os.waitpid(-1, os.WNOHANG)
            except ChildProcessError:
                return
            if pid == 0:
                return
            write_atomically(self.status_dir / str(pid),
                             str(os.waitstatus_to_exitcode(status)).encode())


def send_message(sock, value):
    data = pickle.dumps(value)
    sock.sendall(len(data).to_bytes(8, 'little') + data)


def recv_message(sock):
    """Return one message, or None once the other end has closed."""
    head = _recv_exactly(sock, 8)
    return None if head is None else pickle.loads(
        _recv_exactly(sock, int.from_bytes(head, 'little')))


def _recv_exactly(sock, size):
    data = b''
    while len(data) < size:
        chunk = sock.recv(size - len(data))
        if not chunk:
            return None
        data += chunk
    return data


def run_node(cmd, env, log_path):
    """In a child of the agent: be the executable cmd[0] as exec would make it. No return."""
    code = 1
    try:
        os.setsid()
        out = os.open(log_path, os.O_WRONLY | os.O_APPEND)
        null = os.open(os.devnull, os.O_RDONLY)
        for fd, target in ((null, 0), (out, 1), (out, 2)):
            os.dup2(fd, target)
        os.close(out)
        os.close(null)
        signal.signal(signal.SIGINT, signal.default_int_handler)
        signal.signal(signal.SIGTERM, signal.SIG_DFL)
        os.environ.clear()
        os.environ.update(env)
        sys.argv = list(cmd)
        try:
            runpy.run_path(cmd[0], run_name='__main__')
            code = 0
        except SystemExit as done:
            if done.code is None or isinstance(done.code, int):
                code = done.code or 0
            else:
                print(done.code, file=sys.stderr)
        except BaseException:  # as the interpreter would report it, exiting with 1
            traceback.print_exc()
        atexit._run_exitfuncs()
        sys.stdout.flush()
        sys.stderr.flush()
    finally:
        os._exit(code)


def run_call(request, vivid, device, sock, status_dir, answers):
    """In a child of the agent: call the requested function with a Vm; write the answer."""
    def launch(cmd, env, log_fd, log_path):
        send_message(sock, (cmd, env, log_path))
        return ForkedProcess(recv_message(sock), status_dir)

    vm = None
    try:
        function = load_function(request['path'], request['name'])
        vm = Vm(vivid, device, launch)
        answer = {'value': function(vm, **request['kwargs'])}
    except BaseException:
        answer = {'error': failure_text(vm)}
    if vm is not None:
        try:
            vm.close()
        except BaseException:   # said after the function's own failure, if it had one
            answer = {'error': '%sstopping what the call started failed:\n%s' % (
                answer['error'] + '\n' if 'error' in answer else '', traceback.format_exc())}
    try:
        data = pickle.dumps(answer)
    except Exception as error:
        data = pickle.dumps({'error': 'the answer cannot be sent to the host: %r' % error})
    write_atomically(answers / request['id'], data)


def failure_text(vm):
    """Return the traceback, then each node's log tail and the kernel's last lines."""
    text = traceback.format_exc()
    if vm is not None:
        for node in vm.nodes:
            tail = node.tail()
            if tail not in text:  # a NodeProcess failure already shows its own log
                text += '\n' + tail
        text += '\n--- the VM kernel log, last lines:\n' + '\n'.join(vm.dmesg())
    return text


def load_function(path, name):
    """Return the function `name` of the module at `path` (a test module)."""
    spec = importlib.util.spec_from_file_location('vivid_call', path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    value = module
    for part in name.split('.'):
        value = getattr(value, part)
    return value


def loopback_up():
    """Bring lo up if it is down (DDS talks over it here); return its flags."""
    flags = Path('/sys/class/net/lo/flags')
    if not int(flags.read_text(), 16) & 0x1:
        run(['ip', 'link', 'set', 'lo', 'up'])
    if not int(flags.read_text(), 16) & 0x1:
        raise RuntimeError('the loopback interface does not come up')
    return flags.read_text().strip()


def preload():
    """Import once what nodes and functions import, so that every fork finds it ready."""
    took = {}
    for name in ('numpy', 'cv2', 'rclpy', 'sensor_msgs.msg', 'param_client',
                 'py_vision.usbcam_publisher'):
        started = time.monotonic()
        importlib.import_module(name)
        took[name] = round(time.monotonic() - started, 1)
    # The ROS middleware library is loaded at its first use, in each process: a participant
    # takes seconds to make the first time, one second after that. Asking its name loads it,
    # and starts nothing.
    started = time.monotonic()
    import rclpy
    rclpy.get_rmw_implementation_identifier()
    took['rmw'] = round(time.monotonic() - started, 1)
    return took


def main(shared):
    shared = Path(shared)
    started = time.monotonic()
    try:
        # What install/setup.bash sets, as the host computed it: sourcing it here would start
        # Python afresh, which the emulated CPU takes seconds for.
        ros_harness.installed_env.cache = json.loads((shared / 'installed_env.json').read_text())
        ros_harness.import_installed_package()
        # Seconds since the kernel started, when this agent did: the boot's own share.
        ready = {'kernel': os.uname().release, 'loopback_flags': loopback_up(),
                 'uptime_at_agent_s': float(Path('/proc/uptime').read_text().split()[0])}
        vivid = Vivid()
        ready['device'] = vivid.load(os.environ['PY_VISION_VIVID_OPTIONS'])
        log('vivid loaded at %s' % ready['device'])
        ready['vivid_s'] = round(time.monotonic() - started, 1)
        ready['imports_s'] = preload()
        ready['agent_s'] = round(time.monotonic() - started, 1)
        log('ready after %.1f s: vivid %.1f s, imports %s' % (
            ready['agent_s'], ready['vivid_s'], ready['imports_s']))
        agent = Agent(shared, vivid)
    except BaseException:
        write_atomically(shared / 'failed.txt', traceback.format_exc().encode())
        raise
    write_atomically(shared / 'ready.json', json.dumps(ready).encode())
    agent.serve()
    log('asked to quit')


if __name__ == '__main__':
    sys.stdout.reconfigure(line_buffering=True)
    main(sys.argv[1])
