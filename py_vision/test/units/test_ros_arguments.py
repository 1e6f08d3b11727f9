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
py_vision.ros_arguments against rclpy's own reading of the same command line.

rcl is the oracle for what it decides alone (how a value is typed, what a remapping rule
names): an rclpy node of this run's rclpy (Humble's 3.3.2 or Jazzy's) is built with the
arguments and asked. Which value wins when a parameter is given twice is py_vision's order
(ros_arguments's docstring), checked case by case; and what node_main gives rclpy instead of
the parameter arguments (one file, parameters_file()) gets the node exactly those values.
"""

import array
import math
import os
import tempfile

from hypothesis import assume, given, HealthCheck, settings, strategies as st
from py_vision import node_main, ros_arguments
from py_vision.ros_arguments import (
    given_parameters, node_name, parameters_file, scalar, topic_name, UnreadableArguments,
    without_parameters)
import pytest
from rcl_interfaces.msg import ParameterDescriptor
import rclpy
from rclpy.context import Context
import ros_harness

SETTINGS = settings(max_examples=150, deadline=None,
                    suppress_health_check=[HealthCheck.function_scoped_fixture])
NODE = 'usbcam_publisher'


@pytest.fixture(scope='module')
def context():
    """
    Give the tests an rclpy context of their own (its nodes only parse arguments).

    On a ROS domain of its own, with a node kept for the module's time: rmw_fastrtps makes the
    context's DDS participant with its first node and destroys it with its last, and a
    participant destroyed while another process' participants come and go could hang for good
    in Fast DDS 2.14 (DomainParticipant::set_listener waiting on a listener in use; seen once,
    with tests in two processes). The kept node keeps one participant for every example.
    """
    domain = ros_harness.DomainId()
    ctx = Context()
    rclpy.init(args=[], context=ctx, domain_id=domain.value)
    keeper = rclpy.create_node('argument_tests_participant', context=ctx, enable_rosout=False,
                               start_parameter_services=False)
    yield ctx
    keeper.destroy_node()
    rclpy.shutdown(context=ctx)
    domain.release()


def rclpy_reads(context, args, names, name=NODE):
    """Return (fully qualified name, {name: value}) an rclpy node gets from args."""
    node = rclpy.create_node(name, context=context, cli_args=list(args),
                             use_global_arguments=False, enable_rosout=False,
                             start_parameter_services=False)
    try:
        values = {}
        for parameter in names:
            value = node.declare_parameter(
                parameter, None, ParameterDescriptor(dynamic_typing=True)).value
            if value is not None:
                values[parameter] = value
        return node.get_fully_qualified_name(), values
    finally:
        node.destroy_node()


def same(a, b):
    """Compare values with their types, NaN equal to NaN."""
    if isinstance(a, (list, array.array)) and isinstance(b, (list, array.array)):
        return len(a) == len(b) and all(same(x, y) for x, y in zip(a, b))
    if isinstance(a, float) and isinstance(b, float) and math.isnan(a) and math.isnan(b):
        return True
    return type(a) is type(b) and a == b and (
        not isinstance(a, float) or math.copysign(1, a) == math.copysign(1, b))


def argv(*args):
    return ['usbcam_publisher', '--ros-args'] + list(args)


def params_file(tmp, sections, name='params.yaml'):
    path = os.path.join(tmp, name)
    with open(path, 'w') as stream:
        stream.write(sections)
    return path


# --- values are typed as rcl types them -----------------------------------------------------

WORDS = ['y', 'Y', 'n', 'N', 'yes', 'No', 'ON', 'off', 'True', 'FALSE', 'tRue', 'null', '~',
         '.inf', '-.Inf', '+.INF', '.nan', '.NaN', 'inf', '-Infinity', 'nan', 'NAN', 'synthetic',
         '/dev/video0', '0x1f', '0X1F', '017', '08', '-0', '+5', '0.5', '.5', '5.', '1e5',
         '1E-3', '1e999', '1e-400', '4.9e-324', '2.2250738585072014e-308', '0x1p3', '0x.8p1',
         '9223372036854775807', '9223372036854775808', '-9223372036854775809', '1_000', '']
TEXT = st.one_of(
    st.sampled_from(WORDS),
    st.text(st.sampled_from('0123456789xXeEpP+-.aAfFiInN'), min_size=1, max_size=8),
    st.integers(-2 ** 70, 2 ** 70).map(str),
    st.floats().map(repr))


@SETTINGS
@given(text=TEXT, quote=st.sampled_from(['', "'", '"']))
def test_a_value_is_typed_as_rcl_types_it(context, text, quote):
    rule = 'x:=%s%s%s' % (quote, text, quote)
    try:
        _, got = rclpy_reads(context, ['--ros-args', '-p', rule], ['x'])
    except Exception:  # noqa: B902 - rcl refuses the rule (the node says so, one line)
        assume(False)
    assume('x' in got)
    expected = given_parameters(argv('-p', rule), '/' + NODE)['x']
    assert same(expected, got['x']), (rule, expected, got['x'])


def test_a_scalar_is_typed_as_rcl_does():
    assert scalar('0') == 0 and scalar('017') == 15 and scalar('0x1f') == 31
    assert scalar('0', quoted=True) == '0'
    assert scalar('yes') is True and scalar('Off') is False
    assert scalar('1e5') == 100000.0 and isinstance(scalar('1e5'), float)
    assert scalar('1e999') == '1e999'  # strtod's ERANGE: a string
    assert scalar('synthetic') == 'synthetic'


# --- which value wins ---------------------------------------------------------------------

def test_a_parameter_rule_after_a_params_file_wins(tmp_path):
    path = params_file(tmp_path, 'usbcam_publisher:\n  ros__parameters:\n'
                                 '    video_device: /dev/video0\n    framerate: 10.0\n')
    given = given_parameters(argv('--params-file', path, '-p', 'video_device:=synthetic'),
                             '/usbcam_publisher')
    assert given == {'video_device': 'synthetic', 'framerate': 10.0}
    given = given_parameters(argv('-p', 'video_device:=synthetic', '--params-file', path),
                             '/usbcam_publisher')
    assert given['video_device'] == '/dev/video0'


def test_launch_arguments_after_the_parameter_file_win(tmp_path):
    # What launch_ros 0.19.2 passes for parameters=[params_file, {...}] of a Node it does not
    # name: the launch arguments in a file of their own, under /**.
    shipped = params_file(tmp_path, 'usbcam_publisher:\n  ros__parameters:\n'
                                    '    video_device: /dev/video0\n    image_width: 640\n')
    launch = params_file(tmp_path, '/**:\n  ros__parameters:\n    video_device: synthetic\n',
                         'launch_params_x')
    given = given_parameters(argv('--params-file', shipped, '--params-file', launch),
                             '/usbcam_publisher')
    assert given == {'video_device': 'synthetic', 'image_width': 640}


def test_sections_count_in_the_files_order_for_their_nodes_only(tmp_path):
    path = params_file(tmp_path, '/**:\n  ros__parameters:\n    a: 1\n    b: 1\n'
                                 'usbcam_publisher:\n  ros__parameters:\n    b: 2\n    c: 2\n'
                                 'other:\n  ros__parameters:\n    c: 3\n'
                                 '/*:\n  ros__parameters:\n    c: 4\n'
                                 'ns:\n  usbcam_publisher:\n    ros__parameters:\n      d: 5\n')
    assert given_parameters(argv('--params-file', path), '/usbcam_publisher') == {
        'a': 1, 'b': 2, 'c': 4}
    assert given_parameters(argv('--params-file', path), '/ns/usbcam_publisher') == {
        'a': 1, 'b': 1, 'd': 5}


def test_nested_parameter_names_and_lists(tmp_path):
    path = params_file(tmp_path, 'usbcam_publisher:\n  ros__parameters:\n'
                                 '    qos_overrides:\n      /usb_camera/image:\n'
                                 '        publisher:\n          depth: 3\n'
                                 "    sizes: [1, 2]\n    names: ['a', b]\n")
    assert given_parameters(argv('--params-file', path), '/usbcam_publisher') == {
        'qos_overrides./usb_camera/image.publisher.depth': 3, 'sizes': [1, 2],
        'names': ['a', 'b']}


def test_only_the_ros_arguments_count():
    args = ['usbcam_publisher', '-p', 'a:=1', '--ros-args', '-p', 'b:=2', '--', '-p', 'c:=3',
            '--ros-args', '-p', 'usbcam_publisher:d:=4', '-p', 'other:e:=5']
    assert given_parameters(args, '/usbcam_publisher') == {'b': 2, 'd': 4}


def test_an_unreadable_file_or_rule_is_one_line(tmp_path):
    with pytest.raises(UnreadableArguments, match='nowhere.yaml') as raised:
        given_parameters(argv('--params-file', str(tmp_path / 'nowhere.yaml')), '/x')
    assert '\n' not in str(raised.value)
    bad = params_file(tmp_path, 'usbcam_publisher: [1, 2\n')
    with pytest.raises(UnreadableArguments, match='params.yaml'):
        given_parameters(argv('--params-file', bad), '/x')
    with pytest.raises(UnreadableArguments, match='no :='):
        given_parameters(argv('-p', 'framerate'), '/x')


@pytest.mark.parametrize('remaps', [
    [], ['-r', '__node:=camera'], ['-r', '__ns:=/left'], ['-r', '__ns:=/left', '-r', '__node:=a'],
    ['-r', 'usbcam_publisher:__node:=b'], ['-r', 'other:__node:=c'],
    ['-r', '__node:=first', '-r', '__node:=second'], ['-r', '__name:=d'],
])
def test_the_node_name_is_rcls(context, remaps):
    fqn, _ = rclpy_reads(context, ['--ros-args'] + remaps, [])
    assert node_name(argv(*remaps), NODE) == fqn


# The remappings a user or a launch file gives a viewer, as rcl reads them (first rule wins).
TOPIC_REMAPS = [
    [], ['-r', '__ns:=/left'], ['-r', 'usb_camera/image:=/left/image'],
    ['-r', '/usb_camera/image:=cam/image'], ['-r', '__ns:=/left', '-r', 'usb_camera/image:=raw'],
    ['-r', 'usbcam_publisher:usb_camera/image:=mine'], ['-r', 'other:usb_camera/image:=theirs'],
    ['-r', '__node:=viewer', '-r', 'viewer:usb_camera/image:=renamed'],
    ['-r', 'usb_camera/image:=first', '-r', 'usb_camera/image:=second'],
    ['-r', 'usb_camera/other:=x', '-r', '__ns:=/a/b'], ['-r', 'usb_camera/image:=~/own'],
    ['-r', 'rostopic://usb_camera/image:=/t'], ['-r', 'rosservice://usb_camera/image:=/s'],
    ['-r', 'usbcam_publisher:rostopic://usb_camera/image:=/u'],
    ['-r', '/usb_camera/image/compressed:=/cam/jpeg'],
    ['-r', 'usb_camera/image:=/left/image', '-r', '/left/image/compressed:=/left/jpeg'],
]


@pytest.mark.parametrize('remaps', TOPIC_REMAPS)
def test_a_topic_resolves_as_rcl_resolves_it(context, remaps):
    # What dds gives shared memory on Fast DDS 2.6 (node_main), before there is a node.
    node = rclpy.create_node(NODE, context=context, cli_args=['--ros-args'] + remaps,
                             use_global_arguments=False, enable_rosout=False,
                             start_parameter_services=False)
    try:
        expected = node.resolve_topic_name('usb_camera/image')
        # A transport's topic is subscribed to by its full name, which rcl resolves again.
        compressed = node.resolve_topic_name(expected + '/compressed')
        fqn = node.get_fully_qualified_name()
    finally:
        node.destroy_node()
    assert node_name(argv(*remaps), NODE) == fqn
    assert topic_name(argv(*remaps), 'usb_camera/image', fqn) == expected
    # What node_main gives dds: the raw topic first, then the others (transport.image_topics).
    reader = type('Reader', (), {'NODE_NAME': NODE, 'IMAGE_INPUT': 'usb_camera/image'})
    raw, given_compressed, *video = node_main._image_topics(reader, argv(*remaps))
    assert (raw, given_compressed) == (expected, compressed)


# --- what node_main gives rclpy: the node gets exactly what ros_arguments read ---------------

NAMES = ['video_device', 'framerate', 'image_width', 'managed']
# Humble's rclpy cannot hold an infinite parameter (its message refuses one).
VALUES = st.one_of(st.booleans(), st.integers(-2 ** 63, 2 ** 63 - 1),
                   st.floats(allow_nan=False, allow_infinity=False, allow_subnormal=False),
                   st.text(
                       st.characters(blacklist_categories=('Cs', 'Cc', 'Cn')), max_size=12),
                   st.lists(st.integers(-100, 100), min_size=1, max_size=3))
PATTERNS = ['/**', 'usbcam_publisher', '/usbcam_publisher', 'other', '/*', '/left/*']
SOURCES = st.lists(st.one_of(
    st.tuples(st.just('-p'), st.sampled_from(['', 'usbcam_publisher:', 'other:']),
              st.sampled_from(NAMES), st.integers(-5, 5)),
    st.tuples(st.just('file'), st.lists(st.tuples(
        st.sampled_from(PATTERNS), st.dictionaries(st.sampled_from(NAMES), VALUES,
                                                   min_size=1)), min_size=1, max_size=3))),
    min_size=1, max_size=5)


@SETTINGS
@given(sources=SOURCES, namespace=st.sampled_from([[], ['-r', '__ns:=/left']]))
def test_rclpy_gives_the_node_what_was_read(context, sources, namespace):
    with tempfile.TemporaryDirectory() as tmp:
        args = list(namespace)
        for index, source in enumerate(sources):
            if source[0] == '-p':
                _, prefix, name, value = source
                args += ['-p', '%s%s:=%d' % (prefix, name, value)]
            else:
                text = ''.join('%s:\n  ros__parameters:\n%s' % (pattern, ''.join(
                    '    %s: %s\n' % (name, ros_arguments.yaml_text(value))
                    for name, value in values.items())) for pattern, values in source[1])
                args += ['--params-file', params_file(tmp, text, 'f%d.yaml' % index)]
        fqn = node_name(argv(*args), NODE)
        given = given_parameters(argv(*args), fqn)
        # What node_main gives rclpy (rcl refuses a section without parameters).
        given_file = ['--ros-args', '--params-file', params_file(
            tmp, parameters_file(given, fqn), 'given.yaml')] if given else []
        got_fqn, got = rclpy_reads(
            context, without_parameters(['--ros-args'] + args) + given_file, NAMES)
    assert got_fqn == fqn
    assert set(got) == set(given)
    for name, value in given.items():
        assert same(value, got[name]), (name, value, got[name])


def test_without_parameters_keeps_everything_else():
    args = ['x', '-p', 'keep', '--ros-args', '-p', 'a:=1', '-r', '-p:=q', '--params-file', 'f',
            '--log-level', 'debug', '--param', 'b:=2', '--', '-p', 'c:=3', '--ros-args', '-e',
            '/e']
    assert without_parameters(args) == ['x', '-p', 'keep', '--ros-args', '-r', '-p:=q',
                                        '--log-level', 'debug', '--', '-p', 'c:=3',
                                        '--ros-args', '-e', '/e']
