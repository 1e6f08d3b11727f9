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
default. A camera's controls are the camera's own (the publisher declares them once the camera
is open): the file has usb_cam's control names as commented-out example lines, and each must be
a control of the synthetic camera. Started with `--params-file`, a node must run with exactly
the file's values, the examples set. Both checks are driven by what the nodes declare, so a new
parameter without its line in the file fails here, naming it.
"""

import re
import time

from param_client import describe_parameters
from py_vision.control_names import USB_CAM_ALIASES
import pytest
from rclpy.parameter import parameter_value_to_python
from rclpy.parameter_client import AsyncParameterClient
from ros_harness import EXECUTABLES, SHARE, wait_until
import yaml

PARAMS_FILE = SHARE / 'config' / 'params.yaml'
# What a node needs to run on a test machine: no camera, and ports other tests may hold.
RUN_HERE = {
    'usbcam_publisher': {'video_device': 'synthetic'},
    'usbcam_subscriber': {'display': 'none', 'web_port': 0},
    'cv_bridge_test': {'web_port': 0},
}
# A camera control example: `    # name: example value` in its node's section.
UNSET_LINE = re.compile(r'^    # ([a-z_]+): (\S.*)$', re.MULTILINE)
SECTION = re.compile(r'^([a-z_]+):\n(.*?)(?=^\S|\Z)', re.MULTILINE | re.DOTALL)
START_TIMEOUT_S = 30.0
RESEND_S = 2.0


def file_sections():
    """Return the installed params.yaml as {node name: {parameter: value}}."""
    content = yaml.safe_load(PARAMS_FILE.read_text())
    return {node: section['ros__parameters'] for node, section in content.items()}


def unset_examples(text=None):
    """Return {node name: {parameter: example value}} of the commented-out parameter lines."""
    sections = SECTION.findall(text or PARAMS_FILE.read_text())
    return {node: {name: yaml.safe_load(value) for name, value in UNSET_LINE.findall(body)}
            for node, body in sections}


def typed(values):
    """Return {name: (type name, value)}, so that 10 and 10.0 compare unequal."""
    return {name: (type(value).__name__, value) for name, value in values.items()}


def answer(request, what):
    """
    Return the first response to request() (which sends one and returns its future).

    The request is sent again every RESEND_S: a node can drop a reply while its path back to a
    new client is still being matched (rmw: "failed to send response"), as `ros2 param` users
    retry.
    """
    sent = []

    def answered():
        if not sent or time.monotonic() - sent[-1][0] > RESEND_S:
            sent.append((time.monotonic(), request()))
        return next((future.result() for _, future in sent if future.done()), None)
    return wait_until(answered, START_TIMEOUT_S, 0.05, what)


def running_parameters(peer, proc, node):
    """Return {name: value or None (not set)} of node's own parameters, as it runs."""
    client = AsyncParameterClient(peer.node, node)
    wait_until(client.services_are_ready, START_TIMEOUT_S, 0.1, 'the parameters of ' + node)
    listed = answer(client.list_parameters, 'the parameter list of ' + node)
    # Every rclpy node has ROS's own parameters (use_sim_time, ...): the peer has them too.
    ros_own = set(peer.node.get_parameters_by_prefix(''))
    names = [name for name in listed.result.names if name not in ros_own]
    got = answer(lambda: client.get_parameters(names), 'the parameter values of ' + node).values
    assert len(got) == len(names), '%s answered %d values for %d parameters' % (
        node, len(got), len(names))
    values = {name: parameter_value_to_python(value) for name, value in zip(names, got)}
    if proc.proc.poll() is not None:
        proc.fail('%s exited while its parameters were read' % node)
    return values


def test_the_file_has_a_section_for_every_installed_executable():
    installed = sorted(path.name for path in EXECUTABLES.iterdir())
    assert sorted(file_sections()) == installed
    assert sorted(RUN_HERE) == installed


@pytest.mark.parametrize('node', sorted(RUN_HERE))
def test_the_file_holds_every_declared_parameter_with_its_default(launch, peer, node):
    proc = launch(node, params=RUN_HERE[node])
    declared = running_parameters(peer, proc, node)
    descriptors = describe_parameters(peer, node, list(declared))
    camera = {d.name for d in descriptors
              if d.additional_constraints.startswith('camera control')}
    # rclpy's QoS overrides, one set per topic: the file shows their form in comments.
    own = {name: value for name, value in declared.items()
           if name not in camera and not name.startswith('qos_overrides.')}
    values = dict(file_sections()[node], **RUN_HERE[node])
    examples = unset_examples().get(node, {})
    missing = sorted(set(own) - set(values))
    extra = sorted(set(values) - set(own))
    assert not missing, '%s declares %s, missing in params.yaml: add with the default' % (
        node, missing)
    assert not extra, 'params.yaml has %s, which %s does not declare' % (extra, node)
    assert typed(own) == typed(values), \
        'the defaults of %s (left) differ from params.yaml (right)' % node
    if node == 'usbcam_publisher':
        assert sorted(examples) == sorted(USB_CAM_ALIASES), \
            "params.yaml's control examples are usb_cam's names"
        assert set(examples) <= camera, 'every usb_cam name is a synthetic camera control'
    else:
        assert not examples and not camera


@pytest.mark.parametrize('node', sorted(RUN_HERE))
def test_a_node_runs_with_exactly_the_values_of_its_params_file(launch, peer, node, tmp_path):
    # The installed file with its commented-out examples set, changed only where the node could
    # not run here: those values also differ from the defaults, which shows that the file, not
    # a default, reached the node.
    text = PARAMS_FILE.read_text()
    content = yaml.safe_load(text)
    parameters = content[node]['ros__parameters']
    parameters.update(unset_examples(text).get(node, {}))
    parameters.update(RUN_HERE[node])
    params_file = tmp_path / 'params.yaml'
    params_file.write_text(yaml.safe_dump(content))
    proc = launch(node, extra_args=['--params-file', str(params_file)])
    running = running_parameters(peer, proc, node)
    # A camera's own controls are parameters too: the file's are those it names.
    assert typed({name: running[name] for name in parameters if name in running}) == \
        typed(parameters)
