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
The Linux kernel's virtual video driver, vivid, in a QEMU VM, for the capture tests.

`VividVm.boot()` starts Debian's kernel with virtme-ng (`vng`) in QEMU without KVM (TCG: KVM
does not nest on the CI machines), on this machine's own file system shared read-only, and
runs vivid_agent.py in it. `run(function, **kwargs)` has the agent call `function(vm,
**kwargs)` in the VM, where `vm` (vivid_agent.Vm) gives the vivid device, installed nodes, an
rclpy peer and a ROS domain of the call's own, and returns what the function returned
(pickled: numbers, text, lists, dicts, numpy arrays). A function is named by its module's
file and qualified name, so it must be a module-level function of an importable file (a test
module). A failure in the VM is raised here with its traceback, the nodes' logs, the VM's
kernel log and console.

What it needs, and `missing()` names when absent: qemu-system-x86_64, busybox and kmod on this
machine, vng in this Python's environment (requirements-test.txt), and a kernel: Debian's
kernel package unpacked by scripts/vivid_vm.sh into the cache (`cache_dir()`), or the image
PY_VISION_VIVID_KERNEL names (its modules beside it, as in /boot and /lib/modules). How it
works: docs/vivid.md.
"""

import json
import os
from pathlib import Path
import pickle
import shlex
import shutil
import signal
import subprocess
import sys
import tempfile
import time

import pytest
import ros_harness

HERE = Path(__file__).resolve().parent
AGENT = HERE / 'vivid_agent.py'
ENV_KERNEL = 'PY_VISION_VIVID_KERNEL'
ENV_CACHE = 'PY_VISION_VIVID_CACHE'
# One capture node (node_types bit 0), its webcam input first.
VIVID_OPTIONS = 'n_devs=1 node_types=0x1'
MEMORY = '2G'
CPUS = 2
# Only reached when something is broken: on a loaded 2-core machine the VM boots in about
# half a minute and the agent's imports take as long again.
BOOT_TIMEOUT_S = 360.0
CALL_TIMEOUT_S = 240.0
CONSOLE_TAIL_LINES = 40
# Where the VM sees the host's root a second time, mounted with the page cache on (see BOOT).
HOST_VIEW = '/run/py_vision_host'
# What the VM runs. vng shares the host's root read-only over 9p without caching, where a
# Python start-up takes minutes: so the host's root is shared once more, mounted again with
# cache=loose, and the directories Python and the package live in are bound from there over
# their own paths. Then the agent starts, in the environment env.sh gives (see _agent_env).
BOOT = """set -e
tag=$(awk '$2 == "{view}" {{print $1}}' /proc/mounts)
umount {view}
mount -t 9p -o ro,trans=virtio,version=9p2000.L,msize=512000,cache=loose "$tag" {view}
for path in {binds}; do mount --bind "{view}$path" "$path"; done
. {shared}/env.sh
exec {python} {agent} {shared}
"""


class VmUnavailable(RuntimeError):
    """No VM can start on this machine: what is missing, and how to get it."""


def cache_dir():
    """Return the directory scripts/vivid_vm.sh unpacks Debian's kernel into."""
    explicit = os.environ.get(ENV_CACHE)
    if explicit:
        return Path(explicit)
    base = os.environ.get('XDG_CACHE_HOME') or os.path.join(os.path.expanduser('~'), '.cache')
    return Path(base, 'py_vision', 'vivid')


def find_kernel():
    """Return the kernel image to boot, or None: PY_VISION_VIVID_KERNEL, else the cache's."""
    explicit = os.environ.get(ENV_KERNEL)
    if explicit:
        return Path(explicit)
    kernels = sorted(cache_dir().glob('*/boot/vmlinuz-*'))
    # The script marks an unpacked package complete only once its modules are indexed.
    complete = [k for k in kernels if (k.parent.parent / '.complete').exists()]
    return complete[-1] if complete else None


def vng():
    """Return virtme-ng's command in this Python's environment (or on PATH), or None."""
    beside = Path(sys.executable).parent / 'vng'
    return str(beside) if beside.exists() else shutil.which('vng')


def _system_tool(name):
    return shutil.which(name, path=os.pathsep.join(
        [os.environ.get('PATH', ''), '/usr/sbin', '/sbin']))


def missing():
    """Return what this machine lacks to boot the VM (empty when nothing)."""
    lacks = []
    if vng() is None:
        lacks.append('virtme-ng (vng; pip install -r requirements-test.txt)')
    for tool, package in (('qemu-system-x86_64', 'qemu-system-x86'),
                          ('busybox', 'busybox-static'), ('modprobe', 'kmod')):
        if _system_tool(tool) is None:
            lacks.append('%s (Debian package %s)' % (tool, package))
    kernel = find_kernel()
    if kernel is None:
        lacks.append("a kernel (Debian's linux-image-amd64, unpacked into %s)" % cache_dir())
    elif not kernel.exists():
        lacks.append('the kernel %s=%s (no such file)' % (ENV_KERNEL, kernel))
    return lacks


def host_paths():
    """Return the directories the VM reads with its page cache on: Python's, the package's."""
    paths = sorted({os.path.realpath(p) for p in (
        sys.prefix, sys.base_prefix, ros_harness.REPO, ros_harness.PREFIX.parent)})
    # A directory inside another is already there once the outer one is bound.
    return [p for p in paths if not any(p.startswith(q + os.sep) for q in paths if q != p)]


def _agent_env():
    """
    Return the agent's environment, besides what the VM's init sets.

    Where the package is installed, vivid's options, and this process's library path with the
    mark of the ROS wheels' start-up hook, which otherwise starts Python a second time to set
    that path (on the emulated CPU, seconds).
    """
    env = {'PY_VISION_INSTALL': str(ros_harness.PREFIX.parent),
           'PY_VISION_VIVID_OPTIONS': VIVID_OPTIONS}
    for name in ('LD_LIBRARY_PATH', '_ROS_WHEELS_BOOTSTRAP_COMPLETE'):
        if name in os.environ:
            env[name] = os.environ[name]
    return env


def _tail(path, lines=CONSOLE_TAIL_LINES):
    try:
        text = Path(path).read_text(errors='replace')
    except OSError as error:
        return '(unavailable: %s)' % error
    return '\n'.join(text.splitlines()[-lines:])


class VividVm:
    """One VM running the agent; `run()` calls functions in it; `close()` powers it off."""

    def __init__(self, shared, console, proc, ready):
        self.shared, self.console, self.proc, self.ready = shared, console, proc, ready
        self._calls = 0

    @classmethod
    def boot(cls, timeout=BOOT_TIMEOUT_S):
        """Boot the VM and wait for its agent; VmUnavailable if this machine cannot."""
        lacks = missing()
        if lacks:
            raise VmUnavailable(
                'no vivid VM on this machine: missing %s (scripts/vivid_vm.sh sets them up; '
                'as root with apt for the Debian packages)' % ', '.join(lacks))
        shared = tempfile.mkdtemp(prefix='py_vision_vivid_')
        Path(shared, 'installed_env.json').write_text(json.dumps(ros_harness.installed_env()))
        Path(shared, 'env.sh').write_text(''.join(
            'export %s=%s\n' % (name, shlex.quote(value))
            for name, value in _agent_env().items()))
        console = os.path.join(shared, 'console.log')
        boot = BOOT.format(
            view=HOST_VIEW, binds=' '.join(shlex.quote(p) for p in host_paths()),
            python=shlex.quote(sys.executable),
            agent=shlex.quote(str(AGENT)), shared=shlex.quote(shared))
        cmd = [vng(), '--disable-kvm', '--force-9p', '--memory', MEMORY, '--cpus', str(CPUS),
               '--user', 'root', '--run', str(find_kernel()), '--rwdir', shared,
               '--rodir', '%s=/' % HOST_VIEW, '--exec', 'sh -c %s' % shlex.quote(boot)]
        env = dict(os.environ)
        # vng runs virtme-run, and the VM's tools, from PATH.
        env['PATH'] = os.pathsep.join([str(Path(vng()).parent), env.get('PATH', ''),
                                       '/usr/sbin', '/sbin'])
        with open(console, 'wb') as out:
            proc = subprocess.Popen(cmd, stdout=out, stderr=subprocess.STDOUT,
                                    stdin=subprocess.DEVNULL, env=env, cwd=shared,
                                    start_new_session=True)
        vm = cls(shared, console, proc, None)
        started = time.monotonic()
        try:
            vm.ready = vm._wait_for('ready.json', timeout, 'the VM to boot and its agent to start')
        except BaseException:
            vm.close()
            raise
        vm.ready['boot_s'] = round(time.monotonic() - started, 1)
        return vm

    def _wait_for(self, name, timeout, what):
        """Wait for a file from the agent; AssertionError with the console if none comes."""
        path = os.path.join(self.shared, name)
        failed = os.path.join(self.shared, 'failed.txt')
        deadline = time.monotonic() + timeout
        while not os.path.exists(path):
            if os.path.exists(failed):
                self._fail('the VM agent could not start:\n%s' % Path(failed).read_text())
            if self.proc.poll() is not None:
                self._fail('the VM stopped (vng exit status %d) while waiting for %s' % (
                    self.proc.returncode, what))
            if time.monotonic() > deadline:
                self._fail('timed out after %.0f s waiting for %s' % (timeout, what))
            time.sleep(0.05)
        data = Path(path).read_bytes()
        os.unlink(path)
        return json.loads(data) if name.endswith('.json') else pickle.loads(data)

    def _fail(self, message):
        raise AssertionError('%s\n--- the VM console (%s), last lines:\n%s' % (
            message, ' '.join(self.proc.args[:1]), _tail(self.console))) from None

    def alive(self):
        return self.proc.poll() is None

    def run(self, function, vivid_options=VIVID_OPTIONS, timeout=CALL_TIMEOUT_S, **kwargs):
        """
        Call function(vm, **kwargs) in the VM and return its result.

        The device is reset first (every control at its default) or, with other
        vivid_options, vivid loaded again with them. A failure in the VM is an AssertionError
        here with the VM's traceback and logs; a call that does not end within timeout seconds
        powers the VM off (the next boot starts afresh).
        """
        self._calls += 1
        ident = '%06d' % self._calls
        request = {'kind': 'call', 'id': ident, 'path': function.__code__.co_filename,
                   'name': function.__qualname__, 'kwargs': kwargs,
                   'vivid_options': vivid_options}
        self._request(ident, request)
        try:
            answer = self._wait_for(os.path.join('answers', ident), timeout,
                                    'the VM to answer %s' % function.__qualname__)
        except AssertionError:
            self.close()
            raise
        if 'error' in answer:
            raise AssertionError('%s failed in the VM:\n%s' % (
                function.__qualname__, answer['error'])) from None
        return answer['value']

    def _request(self, ident, request):
        folder = os.path.join(self.shared, 'requests')
        tmp = os.path.join(folder, '.' + ident)
        with open(tmp, 'wb') as out:
            pickle.dump(request, out)
        os.replace(tmp, os.path.join(folder, ident))

    def close(self, timeout=60.0):
        """Ask the agent to quit, which powers the VM off; kill it if it does not."""
        if self.alive() and os.path.isdir(os.path.join(self.shared, 'requests')):
            self._calls += 1
            self._request('%06d' % self._calls, {'kind': 'quit'})
            try:
                self.proc.wait(timeout)
            except subprocess.TimeoutExpired:
                pass
        if self.alive():
            os.killpg(self.proc.pid, signal.SIGKILL)
            self.proc.wait()
        shutil.rmtree(self.shared, ignore_errors=True)


class SessionVm:
    """
    The test session's VM: booted at first use, booted again once it was powered off.

    A boot that failed is not tried again in the session: the tests after it fail at once
    with the same reason.
    """

    def __init__(self):
        self.vm = None
        self.error = None

    def get(self):
        """Return the running VM (VmUnavailable: this machine cannot boot one)."""
        if self.error is not None:
            raise type(self.error)('%s (earlier in this session)' % self.error)
        if self.vm is None or not self.vm.alive():
            try:
                self.vm = VividVm.boot()
            except (VmUnavailable, AssertionError) as error:
                self.error = error
                raise
        return self.vm

    def vm_or_skip(self):
        """Return the running VM; where none can start, skip the test (fail it in CI)."""
        try:
            return self.get()
        except VmUnavailable as error:
            if os.environ.get('CI') == 'true':
                pytest.fail(str(error))
            pytest.skip(str(error))

    def close(self):
        if self.vm is not None:
            self.vm.close()
