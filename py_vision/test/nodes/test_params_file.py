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

from param_client import describe_parameters, get_parameters, list_parameters
from py_vision import dds
from py_vision.control_names import USB_CAM_ALIASES
import pytest
from rclpy.parameter import parameter_value_to_python
from ros_harness import EXECUTABLES, SHARE
import yaml

PARAMS_FILE = SHARE / 'config' / 'params.yaml'
# What a node needs to run on a test machine: no camera, and ports other tests may hold.
RUN_HERE = {
    'usbcam_publisher': {'video_device': 'synthetic'},
    'usbcam_subscriber': {'display': 'none', 'web_port': 0},
    'cv_bridge_test': {'web_port': 0},
    'vision_step': {'web_port': 0},
}
# A camera control example: `    # name: example value` in its node's section.
UNSET_LINE = re.compile(r'^    # ([a-z_]+): (\S.*)$', re.MULTILINE)
SECTION = re.compile(r'^([a-z_]+):\n(.*?)(?=^\S|\Z)', re.MULTILINE | re.DOTALL)


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


def running_parameters(peer, proc, node):
    """Return {name: value or None (not set)} of node's own parameters, as it runs."""
    # Every rclpy node has ROS's own parameters (use_sim_time, ...): the peer has them too.
    ros_own = set(peer.node.get_parameters_by_prefix(''))
    names = [name for name in list_parameters(peer, node) if name not in ros_own]
    values = {name: parameter_value_to_python(value)
              for name, value in zip(names, get_parameters(peer, node, names))}
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


def shared_memory_segment(proc):
    """Return the size of the largest Fast DDS shared-memory segment the node has mapped."""
    sizes = [0]
    for line in open('/proc/%d/maps' % proc.proc.pid):
        fields = line.split()
        if len(fields) == 6 and fields[5].startswith('/dev/shm/fastrtps_') and \
                not fields[5].startswith('/dev/shm/fastrtps_port'):
            start, end = (int(address, 16) for address in fields[0].split('-'))
            sizes.append(end - start)
    return max(sizes)


def room_for(width, height):
    return dds.SEGMENT_FRAMES * width * height * dds.BYTES_PER_PIXEL


def test_a_parameter_given_after_the_file_wins_and_sizes_the_shared_memory(launch, peer):
    # The README's form: the shipped file, then -p. Humble's rclpy 3.3.2 lets the file's
    # section beat any -p; node_main gives rclpy the command line's order on every
    # distribution, and dds sizes the shared memory from the same reading.
    proc = launch('usbcam_publisher', extra_args=[
        '--params-file', str(PARAMS_FILE), '-p', 'video_device:=synthetic',
        '-p', 'image_width:=1280', '-p', 'image_height:=720', '-p', 'framerate:=15.0'])
    proc.wait_for_output(r'opened synthetic: 1280x720 .* at 15 fps')
    names = ['video_device', 'image_width', 'image_height', 'framerate']
    got = [parameter_value_to_python(value)
           for value in get_parameters(peer, 'usbcam_publisher', names)]
    assert got == ['synthetic', 1280, 720, 15.0]
    assert shared_memory_segment(proc) >= room_for(1280, 720)


def test_a_parameter_file_after_a_parameter_wins(launch, tmp_path):
    small = tmp_path / 'small.yaml'
    small.write_text('usbcam_publisher:\n  ros__parameters:\n    video_device: synthetic\n'
                     '    image_width: 320\n    image_height: 240\n')
    proc = launch('usbcam_publisher', extra_args=[
        '-p', 'image_width:=1280', '-p', 'image_height:=720', '--params-file', str(small)])
    proc.wait_for_output(r'opened synthetic: 320x240 ')
    segment = shared_memory_segment(proc)
    assert room_for(320, 240) <= segment < room_for(1280, 720)


BASE_FILE = SHARE / 'config' / 'hand_signs_base.yaml'


def test_the_real_base_file_runs_hand_signs_with_exactly_its_values(launch, peer):
    # config/hand_signs_base.yaml, as docs/processing.md tells a user with a real base to start:
    # every name in it is a parameter of hand_signs (or the node's), every value accepted.
    parameters = yaml.safe_load(BASE_FILE.read_text())['vision_step']['ros__parameters']
    proc = launch('vision_step', params={'web_port': 0},
                  extra_args=['--params-file', str(BASE_FILE)])
    proc.wait_for_output('moving only while /hand_signs/enable says true', timeout=90.0)
    assert 'Twist on /hand_signs/cmd_vel' in proc.output()
    running = running_parameters(peer, proc, 'vision_step')
    assert sorted(set(parameters) - set(running)) == []
    assert typed({name: running[name] for name in parameters}) == typed(parameters)
