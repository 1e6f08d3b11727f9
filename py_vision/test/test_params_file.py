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
config/params.yaml against the installed nodes, through their ROS parameter services.

The file must hold every parameter each node declares, and nothing else, with the node's
default; and started with `--params-file`, a node must run with exactly the file's values.
Both checks are driven by what the nodes declare, so a new parameter without its line in the
file fails here.
"""

import re

import pytest
from rcl_interfaces.srv import GetParameters, ListParameters
from rclpy.parameter import parameter_value_to_python
import ros_harness
import yaml

PARAMS_FILE = ros_harness.SHARE / 'config' / 'params.yaml'
# What a node needs to run on a test machine: no camera, and ports other tests may hold.
RUN_HERE = {
    'usbcam_publisher': {'video_device': 'synthetic'},
    'usbcam_subscriber': {'display': 'none', 'web_port': 0},
    'cv_bridge_test': {'web_port': 0},
}
START_TIMEOUT_S = 30.0


def file_sections():
    """Return the installed params.yaml as {node name: {parameter: value}}."""
    with open(PARAMS_FILE) as handle:
        content = yaml.safe_load(handle)
    return {node: section['ros__parameters'] for node, section in content.items()}


def typed(values):
    """Return {name: (type name, value)}, so that 10 and 10.0 compare unequal."""
    return {name: (type(value).__name__, value) for name, value in values.items()}


def running_parameters(peer, proc, node):
    """Return {name: value} of the parameters node declares beyond ROS's own, as it runs."""
    names = peer.call(ListParameters, '/%s/list_parameters' % node, ListParameters.Request(),
                      START_TIMEOUT_S).result.names
    response = peer.call(GetParameters, '/%s/get_parameters' % node,
                         GetParameters.Request(names=names))
    if proc.proc.poll() is not None:
        proc.fail('%s exited while its parameters were read' % node)
    # Every rclpy node has ROS's own parameters (use_sim_time, ...): the peer has them too.
    ros_own = set(peer.node.get_parameters_by_prefix(''))
    return {name: parameter_value_to_python(value) for name, value in zip(names, response.values)
            if name not in ros_own}


def test_the_file_has_a_section_for_every_installed_executable():
    installed = sorted(path.name for path in ros_harness.EXECUTABLES.iterdir())
    assert sorted(file_sections()) == installed
    assert sorted(RUN_HERE) == installed


@pytest.mark.parametrize('node', sorted(RUN_HERE))
def test_the_file_holds_every_declared_parameter_with_its_default(launch, peer, node):
    proc = launch(node, params=RUN_HERE[node])
    declared = running_parameters(peer, proc, node)
    # A parameter that is not set (a camera control left at the camera's own value) has no
    # value to write: the file names it in a comment instead.
    not_set = sorted(name for name, value in declared.items() if value is None)
    text = PARAMS_FILE.read_text()
    unnamed = [name for name in not_set if not re.search(r'#\s*%s:' % name, text)]
    assert not unnamed, 'params.yaml does not mention %s (not set by default)' % unnamed
    declared = {name: value for name, value in declared.items() if value is not None}
    expected = dict(file_sections()[node], **RUN_HERE[node])
    missing = sorted(set(declared) - set(expected))
    extra = sorted(set(expected) - set(declared))
    assert not missing, '%s declares %s, missing in params.yaml: add with the default' % (
        node, missing)
    assert not extra, 'params.yaml has %s, which %s does not declare' % (extra, node)
    assert typed(declared) == typed(expected), \
        'the defaults of %s (left) differ from params.yaml (right)' % node


@pytest.mark.parametrize('node', sorted(RUN_HERE))
def test_a_node_runs_with_exactly_the_values_of_its_params_file(launch, peer, node, tmp_path):
    # The installed file, changed only where the node could not run here: those values also
    # differ from the defaults, which shows that the file, not a default, reached the node.
    content = yaml.safe_load(PARAMS_FILE.read_text())
    content[node]['ros__parameters'].update(RUN_HERE[node])
    params_file = tmp_path / 'params.yaml'
    params_file.write_text(yaml.safe_dump(content))
    proc = launch(node, extra_args=['--params-file', str(params_file)])
    running = running_parameters(peer, proc, node)
    assert typed({k: v for k, v in running.items() if v is not None}) == \
        typed(content[node]['ros__parameters'])
