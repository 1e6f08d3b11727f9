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
import sys

import pytest
import ros_harness

# Tests never hear each other or the network: every ROS participant (in-process peers and the
# node processes, which inherit os.environ) keeps discovery on this host.
os.environ['ROS_AUTOMATIC_DISCOVERY_RANGE'] = 'LOCALHOST'
os.environ.pop('ROS_LOCALHOST_ONLY', None)
os.environ.pop('ROS_STATIC_PEERS', None)

if not ros_harness.SITE_PACKAGES.is_dir():
    raise pytest.UsageError('%s is missing: build the package first (scripts/setup.sh)'
                            % ros_harness.SITE_PACKAGES)
sys.path.insert(0, str(ros_harness.SITE_PACKAGES))
# As after `source install/setup.bash`, for code that looks itself up through the ament index.
os.environ['AMENT_PREFIX_PATH'] = ros_harness.installed_env()['AMENT_PREFIX_PATH']


@pytest.fixture
def domain_id():
    """Reserve a ROS_DOMAIN_ID that no other running test uses."""
    reserved = ros_harness.DomainId()
    yield reserved.value
    reserved.release()


@pytest.fixture
def ros_env(domain_id):
    """Return the environment for node processes: installed package, own domain, local host."""
    env = ros_harness.installed_env()
    env.update(ROS_DOMAIN_ID=str(domain_id), ROS_AUTOMATIC_DISCOVERY_RANGE='LOCALHOST',
               PYTHONUNBUFFERED='1', RCUTILS_COLORIZED_OUTPUT='0')
    env.pop('ROS_LOCALHOST_ONLY', None)
    return env


@pytest.fixture
def launch(ros_env):
    """
    Start installed executables by name, with parameters and remappings as dicts.

    Every process is stopped at the end of the test, whatever happened.
    """
    started = []

    def start(executable, params=None, remaps=None, extra_args=(), env=None, name=None):
        args = ros_harness.ros_args(params, remaps) + list(extra_args)
        proc = ros_harness.NodeProcess(executable, args, env or ros_env, name)
        started.append(proc)
        return proc
    yield start
    for proc in started:
        proc.kill()


@pytest.fixture
def peer(domain_id):
    """Provide an in-process rclpy node on this test's domain, spinning in a thread."""
    node = ros_harness.RosPeer(domain_id)
    yield node
    node.close()
