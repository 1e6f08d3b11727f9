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
Localhost only means localhost: frames reach subscribers on this host and no other.

Two "hosts" are two network namespaces joined by a veth pair. The board runs usbcam_publisher
and a subscriber on the same host (sharing its /dev/shm); the PC runs a subscriber with Fast
DDS' defaults, discovering by multicast as any PC on the LAN does and also asking the board's
address directly (ROS_STATIC_PEERS, from Iron on). With the user's localhost-only setting the
board's subscriber gets every frame, intact, and the PC none.
"""

import json
import os
from pathlib import Path
import shutil
import subprocess
import sys

from py_vision import dds
import pytest
import ros_harness
from ros_harness import wait_until

NETNS_READY = os.geteuid() == 0 and shutil.which('ip') and shutil.which('unshare')
CHECKER = str(Path(__file__).parents[1] / 'frame_checker.py')
SAME_HOST_FRAMES = 30
# How long the PC keeps listening after the board's subscriber has its frames: the control
# cases (no localhost setting) deliver their first frame across the veth well within it.
NOTHING_FOR_S = 6.0

pytestmark = pytest.mark.skipif(
    not NETNS_READY and not os.environ.get('CI'),
    reason='network namespaces need root, ip and unshare (CI has them)')


class TwoHosts:
    """Network namespaces 'board' and 'pc' joined by a veth pair; processes run in them."""

    def __init__(self, domain_id, workdir):
        tag = '%d%d' % (os.getpid() % 1000, domain_id)
        net = domain_id % 250
        self.addr = {'board': '10.214.%d.1' % net, 'pc': '10.214.%d.2' % net}
        self.ns = {'board': 'pvlb%s' % tag, 'pc': 'pvlp%s' % tag}
        self.workdir = workdir
        self.procs = []
        for ns in self.ns.values():
            self._ip('netns', 'add', ns)
        veth = {'board': 'vlb%s' % tag, 'pc': 'vlp%s' % tag}
        self._ip('link', 'add', veth['board'], 'netns', self.ns['board'], 'type', 'veth',
                 'peer', 'name', veth['pc'], 'netns', self.ns['pc'])
        for host, ns in self.ns.items():
            self._ip('-n', ns, 'addr', 'add', self.addr[host] + '/24', 'dev', veth[host])
            self._ip('-n', ns, 'link', 'set', veth[host], 'up')
            self._ip('-n', ns, 'link', 'set', 'lo', 'up')
            # Discovery multicast leaves through the veth (there is no default route).
            self._ip('-n', ns, 'route', 'add', '224.0.0.0/4', 'dev', veth[host])
        # Fast DDS picks its interfaces at start-up: the veth must be up before the nodes are.
        for host, ns in self.ns.items():
            wait_until(lambda: 'state UP' in subprocess.run(
                ['ip', '-n', ns, '-o', 'link', 'show', 'dev', veth[host]],
                capture_output=True, text=True).stdout, 10, what='veth up in %s' % ns)

    @staticmethod
    def _ip(*args):
        subprocess.run(('ip',) + args, check=True, capture_output=True)

    def start(self, host, name, cmd, env):
        """Start cmd on a host; the PC gets a /dev/shm of its own, as a real PC has."""
        if host == 'pc':
            cmd = ['unshare', '--mount', 'sh', '-c',
                   'mount -t tmpfs tmpfs /dev/shm && exec "$@"', 'sh'] + cmd
        log = open(self.workdir / ('%s.log' % name), 'w+')
        proc = subprocess.Popen(['ip', 'netns', 'exec', self.ns[host]] + cmd, env=env,
                                stdout=log, stderr=subprocess.STDOUT, start_new_session=True)
        proc.log = log
        self.procs.append(proc)
        return proc

    def logs(self):
        text = []
        for proc in self.procs:
            proc.log.seek(0)
            text.append('--- %s\n%s' % (Path(proc.log.name).name, proc.log.read()[-3000:]))
        return '\n'.join(text)

    def close(self):
        for proc in self.procs:
            ros_harness.end_process_group(proc)
            proc.log.close()
        for ns in self.ns.values():
            subprocess.run(['ip', 'netns', 'del', ns], capture_output=True)


@pytest.fixture
def hosts(domain_id, tmp_path):
    two = TwoHosts(domain_id, tmp_path)
    yield two
    two.close()


def checker_result(proc):
    proc.log.seek(0)
    lines = proc.log.read().strip().splitlines()
    return json.loads(lines[-1]) if lines else None


def humble_profile(localhost, ros_env):
    """Return the profile py_vision's publisher would use with or without ROS_LOCALHOST_ONLY."""
    env = ros_harness.with_discovery(dict(ros_env), 'subnet')
    env['ROS_LOCALHOST_ONLY'] = '1' if localhost else '0'
    return dds.use_packaged_profile(dds.OWN_SIZE, [], 'usbcam_publisher', env)


def from_iron(case):
    """Mark a case of a variable Humble does not have: skipped there, with the reason."""
    return pytest.param(case, marks=pytest.mark.skipif(ros_harness.ON_HUMBLE,
                                                       reason=ros_harness.FROM_IRON))


# Each case: the board's environment, and whether the PC should receive frames.
CASES = {
    'ROS_LOCALHOST_ONLY=1': ({'ROS_LOCALHOST_ONLY': '1'}, False),
    'ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST': ({'ROS_AUTOMATIC_DISCOVERY_RANGE': 'LOCALHOST'},
                                                False),
    # Humble's rmw_fastrtps keeps multicast discovery with ROS_LOCALHOST_ONLY=1 and adds a
    # localhost transport beside the profile's: only the profile stands between the frames and
    # the network. Network discovery with the profile py_vision picks there does the same on
    # any distribution.
    'Humble ROS_LOCALHOST_ONLY=1': ('humble localhost', False),
    # The controls: without a localhost setting the PC does receive frames.
    'control: Humble, no setting': ('humble network', True),
    'control: ROS_AUTOMATIC_DISCOVERY_RANGE=SUBNET': (
        {'ROS_AUTOMATIC_DISCOVERY_RANGE': 'SUBNET'}, True),
}
PARAMETERS = [from_iron(case) if 'ROS_AUTOMATIC_DISCOVERY_RANGE' in case else case
              for case in CASES]


def board_env(ros_env, setting):
    env = ros_harness.with_discovery(dict(ros_env), 'subnet')
    if isinstance(setting, str):
        env['FASTRTPS_DEFAULT_PROFILES_FILE'] = humble_profile(
            setting.endswith('localhost'), ros_env)
    else:
        env.update(setting)
    return env


def pc_env(hosts, ros_env):
    """Return the PC's environment: network discovery, asking the board's address too."""
    return ros_harness.with_discovery(dict(ros_env), 'subnet', peers=hosts.addr['board'])


def start_publisher(hosts, env):
    publisher = hosts.start('board', 'usbcam_publisher', [
        str(ros_harness.EXECUTABLES / 'usbcam_publisher'), '--ros-args',
        '-p', 'video_device:=synthetic', '-p', 'framerate:=15.0'], env)
    return publisher


def receives_nothing(proc):
    """Return True when proc (a frame checker for 1 frame) got nothing for NOTHING_FOR_S."""
    try:
        wait_until(lambda: proc.poll() is not None, NOTHING_FOR_S, what='no frame')
    except AssertionError:
        return checker_result(proc) is None
    return False


@pytest.mark.parametrize('case', PARAMETERS)
def test_localhost_only_keeps_frames_on_this_host(hosts, ros_env, case):
    setting, pc_receives = CASES[case]
    env = board_env(ros_env, setting)
    pc = hosts.start('pc', 'pc_subscriber', [sys.executable, CHECKER, '1'], pc_env(hosts, ros_env))
    same_host = hosts.start('board', 'board_subscriber',
                            [sys.executable, CHECKER, str(SAME_HOST_FRAMES)], env)
    start_publisher(hosts, env)
    try:
        wait_until(lambda: same_host.poll() is not None, 60,
                   what='%d frames on the same host' % SAME_HOST_FRAMES)
        result = checker_result(same_host)
        assert result and result['frames'] == SAME_HOST_FRAMES, result
        assert result['intact'] == SAME_HOST_FRAMES, result
        if pc_receives:
            wait_until(lambda: pc.poll() is not None, 30, what='a frame on the PC')
            assert checker_result(pc)['frames'] == 1
        else:
            assert receives_nothing(pc), 'a frame reached the other host'
    except AssertionError as error:
        raise AssertionError('%s\n%s' % (error, hosts.logs())) from None


@pytest.mark.skipif(ros_harness.ON_HUMBLE, reason=ros_harness.FROM_IRON)
def test_discovery_off_keeps_frames_in_the_process(hosts, ros_env):
    """OFF is stricter than localhost: ROS discovers no other process, on any host."""
    env = board_env(ros_env, {'ROS_AUTOMATIC_DISCOVERY_RANGE': 'OFF'})
    pc = hosts.start('pc', 'pc_subscriber', [sys.executable, CHECKER, '1'], pc_env(hosts, ros_env))
    same_host = hosts.start('board', 'board_subscriber', [sys.executable, CHECKER, '1'],
                            ros_harness.with_discovery(dict(ros_env), 'localhost'))
    publisher = start_publisher(hosts, env)
    try:
        wait_until(lambda: 'publishing on' in open(publisher.log.name).read(), 30,
                   what='the publisher to open its camera')
        assert receives_nothing(pc), 'a frame reached the other host'
        assert receives_nothing(same_host), 'a frame reached another process'
    except AssertionError as error:
        raise AssertionError('%s\n%s' % (error, hosts.logs())) from None
