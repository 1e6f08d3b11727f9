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

"""Shared fixtures: the tests import and run the colcon-installed py_vision, not the sources."""

import os
import shutil
import signal
import tempfile

from emulated_camera import CompilerMissing, EmulatedCamera
from hypothesis import settings
import pytest
import ros_harness
from vivid_vm import SessionVm

# A property test that fails prints the @reproduce_failure line that replays its example: the
# falsifying example alone may not (a numpy array's repr rounds). On top of the current
# profile: hypothesis's own for CI (derandomized) or the default one.
settings.register_profile('py_vision', print_blob=True)
settings.load_profile('py_vision')

# Tests never hear each other or the network: every ROS participant (in-process peers and the
# node processes, which inherit os.environ) keeps discovery on this host.
ros_harness.with_discovery(os.environ, 'localhost')

if not ros_harness.SITE_PACKAGES.is_dir():
    raise pytest.UsageError(
        '%s is missing: build the package first (scripts/setup.sh, or colcon build in a '
        'workspace before colcon test)' % ros_harness.SITE_PACKAGES)
ros_harness.import_installed_package()
# The in-process peers' rcl log files go to a directory removed when the session ends.
_SESSION_ROS_LOG_DIR = tempfile.mkdtemp(prefix='py_vision_test_ros_log_')
os.environ['ROS_LOG_DIR'] = _SESSION_ROS_LOG_DIR


# Environment variables that leave out every test using a fixture: the board-version run
# (scripts/test.sh) has no Playwright, and leaves the vivid VM's tests to the main run (the
# kernel's answers do not depend on the Python side's versions). Left out, not skipped:
# nothing claims they ran.
LEFT_OUT_BY = {'PY_VISION_BROWSER': 'browser', 'PY_VISION_VIVID': 'vivid_session'}
# The same for the tests with a marker: PY_VISION_LINTERS=off leaves out the linters, whose
# answer is about the files, the same whatever Python, numpy, OpenCV or ROS runs them (the
# board-version run; docs/tests.md says why).
LEFT_OUT_MARKED = {'PY_VISION_LINTERS': 'linter'}
# Under pytest-xdist (scripts/test.sh: -n 2 --dist load) a session-scoped fixture is
# made once per worker: the vivid VM's tests are all given to one worker, so the VM boots once
# in the run. The scheduler (below) tells them by their files' names, and a test of the VM in
# another file fails with the reason.
VIVID_FILES = 'test_vivid'


def _uses(item, fixture):
    return fixture in getattr(item, 'fixturenames', ())


def _in_vivid_file(nodeid):
    return nodeid.split('::', 1)[0].rsplit('/', 1)[-1].startswith(VIVID_FILES)


def pytest_collection_modifyitems(config, items):
    """Leave out what PY_VISION_*=off says."""
    for variable, fixture in LEFT_OUT_BY.items():
        if os.environ.get(variable) != 'off':
            continue
        left_out = [item for item in items if _uses(item, fixture)]
        if left_out:
            config.hook.pytest_deselected(items=left_out)
            items[:] = [item for item in items if item not in left_out]
    for variable, marker in LEFT_OUT_MARKED.items():
        if os.environ.get(variable) != 'off':
            continue
        left_out = [item for item in items if item.get_closest_marker(marker)]
        if left_out:
            config.hook.pytest_deselected(items=left_out)
            items[:] = [item for item in items if item not in left_out]


@pytest.hookimpl(tryfirst=True)
def pytest_runtest_setup(item):
    """Fail a test of the vivid VM outside its files, before it boots a VM of its own."""
    if _uses(item, 'vivid_session') and not _in_vivid_file(item.nodeid):
        pytest.fail('a test of the vivid VM must be in a file named %s*.py, so that one test '
                    'worker runs them all and the VM boots once (conftest.py)' % VIVID_FILES,
                    pytrace=False)


@pytest.hookimpl(trylast=True)
def pytest_runtest_teardown(item, nextitem):
    """
    Power the vivid VM off after the last of its tests in this process.

    The VM is emulated (no KVM): idle, it still takes most of a core, which the tests after it
    need. The VM's tests come one after the other (one worker runs them all), so the next test
    not using it means its work is done; a later one would boot it again.
    """
    if _uses(item, 'vivid_session') and (nextitem is None
                                         or not _uses(nextitem, 'vivid_session')):
        session = item.funcargs.get('vivid_session')
        if session is not None:
            session.close()


@pytest.hookimpl(optionalhook=True)
def pytest_xdist_make_scheduler(config, log):
    """
    Give each test to the next free xdist worker, and all the vivid VM's tests to one.

    Under pytest-xdist with --dist load (or loadgroup). xdist's own xdist_group marks do not
    group on pytest 9.2: xdist 3.8 renames the tests' node ids for them, which pytest 9.2 no
    longer lets it do. So its scope scheduler is given the groups from here instead.
    """
    if config.getvalue('dist') not in ('load', 'loadgroup'):
        return None
    from xdist.scheduler import LoadScopeScheduling

    class VividInOneWorker(LoadScopeScheduling):
        """xdist's scope scheduling: the largest scope (the VM's tests) first, then the rest."""

        def _split_scope(self, nodeid):
            return VIVID_FILES if _in_vivid_file(nodeid) else nodeid

    return VividInOneWorker(config, log)


def pytest_unconfigure(config):
    shutil.rmtree(_SESSION_ROS_LOG_DIR, ignore_errors=True)


@pytest.hookimpl(hookwrapper=True)
def pytest_runtest_makereport(item, call):
    """Add the tail of every node's log to the failure of a test that started nodes."""
    outcome = yield
    report = outcome.get_result()
    processes = getattr(item, 'node_processes', ())
    if report.when == 'call' and report.failed and hasattr(report.longrepr, 'addsection'):
        message = str(call.excinfo.value) if call.excinfo else ''
        for proc in processes:
            tail = proc.tail()
            if tail not in message:  # a NodeProcess failure already shows its own log
                report.longrepr.addsection('log of %s' % proc.name, tail)


@pytest.fixture
def domain_id():
    """Reserve a ROS_DOMAIN_ID that no other running test uses."""
    reserved = ros_harness.DomainId()
    yield reserved.value
    reserved.release()


@pytest.fixture
def ros_env(domain_id):
    """
    Return the environment for node processes: installed package, own domain, local host.

    The nodes' rcl log files (ROS_LOG_DIR) go to a directory deleted after the test.
    """
    log_dir = tempfile.mkdtemp(prefix='py_vision_ros_log_')
    yield ros_harness.node_env(domain_id, log_dir)
    shutil.rmtree(log_dir, ignore_errors=True)


@pytest.fixture
def launch(ros_env, request):
    """
    Start installed executables by name, with parameters and remappings as dicts.

    Every process is stopped, and its log deleted, at the end of the test, whatever happened;
    when the test fails, its report ends with the tail of each process's log.
    """
    started = request.node.node_processes = []

    def start(executable, params=None, remaps=None, extra_args=(), env=None, name=None):
        args = ros_harness.ros_args(params, remaps) + list(extra_args)
        proc = ros_harness.NodeProcess(executable, args, env or ros_env, name)
        started.append(proc)
        return proc
    yield start
    for proc in started:
        proc.kill()


@pytest.fixture
def started_in_the_background():
    """
    Run the test as scripts/test.sh runs when a script starts it in the background.

    A non-interactive shell starts a command with `&` (a CI runner's or an init script) with
    SIGINT and SIGQUIT ignored, which every process it starts inherits: this test's process
    ignores both until the test ends. Processes started through ros_harness still get their
    default action (ros_harness.with_stop_signals_default).
    """
    with ros_harness.signals_ignored(signal.SIGINT, signal.SIGQUIT):
        yield


@pytest.fixture
def peer(domain_id):
    """Provide an in-process rclpy node on this test's domain, spinning in a thread."""
    node = ros_harness.RosPeer(domain_id)
    yield node
    node.close()


@pytest.fixture
def emulated_camera():
    """
    Give a factory of emulated UVC cameras, called as EmulatedCamera is, without its directory.

    For example ``emulated_camera(model='vga_yuyv', node=41)``. Each camera is an
    `EmulatedCamera` (emulated_camera.py) in a directory of this test's own, unplugged and
    removed after the test; a process sees it when started with ``camera.env(base_env)``
    (e.g. ``launch('usbcam_publisher', env=camera.env(ros_env))``). Without a C compiler the
    test is skipped with the reason, and fails in CI.
    """
    state_dir = tempfile.mkdtemp(prefix='py_vision_uvc_')
    made = []

    def make(model='webcam_1080p', node=40, **faults):
        try:
            camera = EmulatedCamera(state_dir, model, node, **faults)
        except CompilerMissing as error:
            if os.environ.get('CI') == 'true':
                pytest.fail(str(error))
            pytest.skip(str(error))
        made.append(camera)
        return camera
    yield make
    for camera in made:
        camera.close()
    shutil.rmtree(state_dir, ignore_errors=True)


@pytest.fixture(scope='session')
def vivid_session():
    """Give the session's vivid VM (vivid_vm.SessionVm), powered off when the session ends."""
    session = SessionVm()
    yield session
    session.close()


@pytest.fixture
def vivid(vivid_session):
    """
    Give the vivid VM of this session (booted at the first test that asks): a VividVm.

    ``vivid.run(function, **kwargs)`` calls ``function(vm, **kwargs)`` in the VM, on a vivid
    device with every control at its default and a ROS domain of the call's own, and returns
    what it returned (docs/vivid.md). Where no VM can start (vivid_vm.missing()) the test is
    skipped with the reason, and fails in CI.
    """
    return vivid_session.vm_or_skip()


# The browser tests' Chromium: headless, no first-run work, nothing fetched from the network.
CHROMIUM_ARGS = ['--headless', '--no-sandbox', '--disable-gpu', '--disable-quic',
                 '--no-first-run', '--disable-background-networking',
                 '--disable-component-update', '--disable-sync']


def chromium_path():
    """Return the Chromium executable, or None when there is none."""
    explicit = os.environ.get('CHROMIUM')
    if explicit:
        return explicit
    return shutil.which('chromium') or shutil.which('chromium-browser')


@pytest.fixture
def browser(tmp_path):
    """
    Yield a fresh headless Chromium context (with its own profile directory).

    Needs Playwright and Chromium: without them the test is skipped with the reason, and fails
    in CI (CI=true), which must run it.
    """
    try:
        from playwright.sync_api import sync_playwright
    except ImportError:
        sync_playwright = None
    missing = None
    if sync_playwright is None:
        missing = 'Playwright is not installed (pip install playwright)'
    elif chromium_path() is None:
        missing = 'Chromium is not installed (apt-get install chromium)'
    if missing:
        if os.environ.get('CI', '').lower() in ('1', 'true', 'yes'):
            pytest.fail('%s, and CI requires the browser test' % missing)
        pytest.skip('%s; CI runs this test' % missing)
    with sync_playwright() as playwright:
        context = playwright.chromium.launch_persistent_context(
            str(tmp_path / 'profile'), executable_path=chromium_path(), headless=True,
            args=CHROMIUM_ARGS, viewport={'width': 1280, 'height': 800}, device_scale_factor=1)
        try:
            yield context
        finally:
            context.close()
