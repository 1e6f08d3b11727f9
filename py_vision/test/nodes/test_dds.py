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

"""The packaged Fast DDS profile: used by default, never over a user's choice, fit to the node."""

import os
from pathlib import Path
import socket
import xml.etree.ElementTree as ET

from py_vision import dds
import pytest
import ros_harness

NS = '{http://www.eprosima.com/XMLSchemas/fastRTPS_Profiles}'
VGA_BYTES = 640 * 480 * 3
LIMITS = {'sendBufferSize': '/proc/sys/net/core/wmem_max',
          'receiveBufferSize': '/proc/sys/net/core/rmem_max'}


@pytest.fixture(autouse=True)
def own_choices(monkeypatch):
    """Keep what each test makes dds choose (dds._chosen) from the tests that follow."""
    monkeypatch.setattr(dds, '_chosen', dict(dds._chosen))


def udp(path):
    root = ET.parse(path).getroot()
    for descriptor in root.iter(NS + 'transport_descriptor'):
        if descriptor.find(NS + 'type').text == 'UDPv4':
            return descriptor


def buffer_sizes(path):
    return {tag: int(udp(path).find(NS + tag).text) for tag in LIMITS}


def segment(path):
    return int(ET.parse(path).getroot().find('.//%ssegment_size' % NS).text)


def allowed_interfaces(path):
    return [a.text for a in udp(path).iter(NS + 'address')]


def test_installed_profile_has_shared_memory_and_udp():
    path = dds.packaged_profile()
    assert path is not None and 'install' in path
    root = ET.parse(path).getroot()
    transports = [t.text for t in root.iter(NS + 'transport_id')]
    assert 'py_vision_shm' in transports and 'py_vision_udp' in transports
    assert allowed_interfaces(path) == [], 'the packaged profile reaches other hosts'


def test_used_by_default_and_capped_to_the_kernel_limits(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    env = {}
    used = dds.use_packaged_profile(dds.OWN_SIZE, [], 'usbcam_publisher', env)
    assert env['FASTRTPS_DEFAULT_PROFILES_FILE'] == used
    for tag, size in buffer_sizes(used).items():
        assert size <= int(Path(LIMITS[tag]).read_text())


def test_buffers_above_the_limit_are_capped_in_a_copy():
    packaged = dds.packaged_profile()
    small = {'sendBufferSize': 212992, 'receiveBufferSize': 212992}
    fitted = dds.tailor(packaged, limits=small)
    assert fitted != packaged
    assert buffer_sizes(fitted) == small
    assert segment(fitted) == segment(packaged)
    assert dds.tailor(packaged, limits={'sendBufferSize': 1 << 30,
                                        'receiveBufferSize': 1 << 30}) == packaged


def test_segment_holds_the_frames_a_node_publishes_and_no_more():
    assert dds.segment_size(dds.NO_IMAGES) == dds.SMALL_SEGMENT
    vga = dds.segment_size(dds.OWN_SIZE, [], 'usbcam_publisher')
    assert 2 * VGA_BYTES <= vga <= 4 * VGA_BYTES
    full_hd = dds.segment_size(dds.OWN_SIZE, [
        'usbcam_publisher', '--ros-args', '-p', 'image_width:=1920',
        '--param', 'image_height:=1080'], 'usbcam_publisher')
    assert full_hd == vga * (1920 * 1080) // (640 * 480)
    # What it publishes unknown: as large as 1920x1080.
    assert dds.segment_size(None) == full_hd
    # Told nothing, a node that republishes what it receives assumes the camera's default
    # size, as the camera does (a plain `ros2 run` does not pay 15 MiB for 1080p room) ...
    assert dds.segment_size(dds.INPUT_SIZE, [], 'cv_bridge_test') == vga
    # ... and can tell when the frames it gets are larger than that.
    assert dds.frame_fits(VGA_BYTES, vga) and not dds.frame_fits(4 * VGA_BYTES, vga)
    assert dds.frame_fits(4 * VGA_BYTES, full_hd)
    assert dds.segment_size(dds.INPUT_SIZE, [
        '--ros-args', '-p', 'image_width:=640', '-p', 'image_height:=480'],
        'cv_bridge_test') == vga
    # Arguments after a closing -- are not ROS arguments.
    assert dds.segment_size(dds.OWN_SIZE, [
        '--ros-args', '--', '-p', 'image_width:=1920'], 'usbcam_publisher') == vga


def test_frame_size_from_a_parameter_file(tmp_path):
    params = tmp_path / 'params.yaml'
    params.write_text('/**:\n  ros__parameters:\n    image_height: 960\n'
                      'usbcam_publisher:\n  ros__parameters:\n    image_width: 1280\n'
                      '    image_height: 720\n'
                      'other_node:\n  ros__parameters:\n    image_width: 4000\n')
    args = ['--ros-args', '--params-file', str(params)]
    assert dds.requested_size(args, '/usbcam_publisher') == (1280, 720)
    assert dds.requested_size(args, '/cv_bridge_test') == (640, 960)
    # A node that republishes the camera's frames reads what its command line gives the
    # camera, as pipeline.launch.py gives params.yaml to every node.
    assert dds.segment_size(dds.INPUT_SIZE, args, 'cv_bridge_test') == \
        dds.segment_size(dds.OWN_SIZE, args, 'usbcam_publisher')
    # The command line's order (ros_arguments): a -p after the file wins ...
    assert dds.requested_size(args + ['-p', 'image_width:=320'], '/usbcam_publisher') == (
        320, 720)
    # ... and a /** section after the node's.
    reordered = tmp_path / 'reordered.yaml'
    reordered.write_text('usbcam_publisher:\n  ros__parameters:\n    image_width: 1280\n'
                         '    image_height: 720\n'
                         '/**:\n  ros__parameters:\n    image_height: 960\n')
    assert dds.requested_size(['--ros-args', '--params-file', str(reordered)],
                              '/usbcam_publisher') == (1280, 960)
    # A renamed node reads its new name's section.
    assert dds.segment_size(dds.OWN_SIZE, args + ['-r', '__node:=other_node'],
                            'usbcam_publisher') == dds.segment_size(
        dds.OWN_SIZE, ['--ros-args', '-p', 'image_width:=4000', '-p', 'image_height:=960'],
        'usbcam_publisher')


def test_unreadable_sizes_assume_large_frames(tmp_path):
    broken = tmp_path / 'broken.yaml'
    broken.write_text('usbcam_publisher: [unclosed\n')
    for args in (['--ros-args', '--params-file', str(broken)],
                 ['--ros-args', '--params-file', str(tmp_path / 'missing.yaml')],
                 ['--ros-args', '-p', 'image_width:=wide'],
                 ['--ros-args', '-p', 'image_width:=0']):
        assert dds.requested_size(args, '/usbcam_publisher') == dds.SAFE_SIZE, args


def test_localhost_settings_restrict_udp_to_loopback(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    for env, local in (({}, False), ({'ROS_LOCALHOST_ONLY': '0'}, False),
                       ({'ROS_AUTOMATIC_DISCOVERY_RANGE': 'SUBNET'}, False),
                       ({'ROS_LOCALHOST_ONLY': '1'}, True),
                       ({'ROS_AUTOMATIC_DISCOVERY_RANGE': 'LOCALHOST'}, True),
                       ({'ROS_AUTOMATIC_DISCOVERY_RANGE': 'OFF'}, True),
                       # Jazzy: ROS_LOCALHOST_ONLY=1 overrides the range.
                       ({'ROS_LOCALHOST_ONLY': '1',
                         'ROS_AUTOMATIC_DISCOVERY_RANGE': 'SUBNET'}, True)):
        path = dds.use_packaged_profile(dds.NO_IMAGES, [], 'usbcam_subscriber', dict(env))
        assert allowed_interfaces(path) == (['127.0.0.1'] if local else []), env
        assert segment(path) == dds.SMALL_SEGMENT


def test_user_settings_and_other_rmws_are_left_alone(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    for env in ({'FASTRTPS_DEFAULT_PROFILES_FILE': '/etc/mine.xml'},
                {'RMW_IMPLEMENTATION': 'rmw_cyclonedds_cpp'}):
        before = dict(env)
        assert dds.use_packaged_profile(dds.OWN_SIZE, [], 'usbcam_publisher', env) is None
        assert env == before
    env = {'RMW_IMPLEMENTATION': 'rmw_fastrtps_cpp'}
    assert dds.use_packaged_profile(dds.OWN_SIZE, [], 'usbcam_publisher', env) is not None
    # Fast DDS reads DEFAULT_FASTRTPS_PROFILES.xml from the working directory by itself.
    (tmp_path / 'DEFAULT_FASTRTPS_PROFILES.xml').write_text('<profiles/>')
    env = {}
    assert dds.use_packaged_profile(dds.OWN_SIZE, [], 'usbcam_publisher', env) is None
    assert env == {}


def test_fast_dds_3s_variable_alone_does_not_leave_nodes_on_the_small_default(
        tmp_path, monkeypatch):
    # Fast DDS 2.6 (Humble, the boards) and 2.14 (Jazzy) read FASTRTPS_DEFAULT_PROFILES_FILE
    # only: a FASTDDS_DEFAULT_PROFILES_FILE alone configures nothing there.
    monkeypatch.chdir(tmp_path)
    env = {'FASTDDS_DEFAULT_PROFILES_FILE': '/etc/mine.xml'}
    path = dds.use_packaged_profile(dds.OWN_SIZE, [], 'usbcam_publisher', env)
    assert path is not None and env['FASTRTPS_DEFAULT_PROFILES_FILE'] == path
    assert segment(path) > dds.SMALL_SEGMENT
    assert env['FASTDDS_DEFAULT_PROFILES_FILE'] == '/etc/mine.xml'


def listening(path):
    """Return the participant's own locator lists: {list name: [(kind, address), ...]}."""
    rtps = ET.parse(path).getroot().find('.//%sparticipant/%srtps' % (NS, NS))
    found = {}
    for name in ('defaultUnicastLocatorList', 'builtin/%smetatrafficUnicastLocatorList' % NS,
                 'builtin/%smetatrafficMulticastLocatorList' % NS):
        locators = rtps.findall('%s/%slocator' % (NS + name, NS))
        found[name.rsplit('}', 1)[-1]] = [(kind.tag[len(NS):], kind.findtext(NS + 'address'))
                                          for locator in locators for kind in locator]
    return found


# Fast DDS' own choice of locators, shared memory included (nothing listed) ...
SHM_AND_UDP = {'defaultUnicastLocatorList': [], 'metatrafficUnicastLocatorList': [],
               'metatrafficMulticastLocatorList': []}
# ... and UDP alone: every allowed interface, the discovery multicast group.
UDP_ONLY = {'defaultUnicastLocatorList': [('udpv4', None)],
            'metatrafficUnicastLocatorList': [('udpv4', None)],
            'metatrafficMulticastLocatorList': [('udpv4', dds.DISCOVERY_MULTICAST)]}


def test_udp_receive_keeps_the_shared_memory_to_send_through():
    # Fast DDS 2.6.0 to 2.6.5 can stop reading a shared-memory port for good (docs/boards.md,
    # "A node nobody hears"): a node that receives no images then listens on UDP alone.
    packaged = dds.packaged_profile()
    assert listening(packaged) == SHM_AND_UDP
    vga = dds.segment_size(dds.OWN_SIZE, [], 'usbcam_publisher')
    fitted = dds.tailor(packaged, vga, localhost=True, udp_receive=True)
    assert listening(fitted) == UDP_ONLY
    # Its frames still leave through its own shared memory, sized for them; UDP on loopback.
    root = ET.parse(fitted).getroot()
    assert [t.text for t in root.iter(NS + 'transport_id')].count('py_vision_shm') == 2
    assert segment(fitted) == vga and allowed_interfaces(fitted) == ['127.0.0.1']


# A node that receives images, on Fast DDS 2.6: discovery on UDP; its endpoints take the
# participant's defaults (shared memory first) only where a reader profile of their topic's
# name lists none.
DISCOVERY_ON_UDP = dict(UDP_ONLY, defaultUnicastLocatorList=[])


def endpoints(path):
    """Return the endpoint profiles: {(kind, name): (default?, [(kind, address, port)])}."""
    found = {}
    for kind in ('data_writer', 'data_reader'):
        for profile in ET.parse(path).getroot().findall(NS + kind):
            listed = profile.iterfind('%sunicastLocatorList/%slocator/*' % (NS, NS))
            locators = [(loc.tag[len(NS):], loc.findtext(NS + 'address'),
                         loc.findtext(NS + 'port')) for loc in listed]
            found[kind, profile.get('profile_name')] = (
                profile.get('is_default_profile') == 'true', locators)
    return found


def test_image_readers_alone_keep_the_shared_memory():
    packaged = dds.packaged_profile()
    topics = ('/usb_camera/image', '/usb_camera/image/compressed')
    fitted = dds.tailor(packaged, dds.SMALL_SEGMENT, localhost=True, udp_receive=True,
                        shm_topics=topics)
    assert listening(fitted) == DISCOVERY_ON_UDP
    found = endpoints(fitted)
    # Every other reader and writer (services, parameter events, the graph) listens on one UDP
    # port of its own, not 0 (with 0 Fast DDS 2.6.0 computes a port nobody listens on).
    (writer_default, writer), = [v for (kind, _), v in found.items() if kind == 'data_writer']
    defaults = [v for (kind, name), v in found.items()
                if kind == 'data_reader' and name not in topics]
    assert writer_default and defaults == [(True, writer)]
    (udp_kind, address, port), = writer
    assert udp_kind == 'udpv4' and address is None and 0 < int(port) < 65536
    # The image topics' readers list no locators: the participant's, shared memory first.
    assert [found['data_reader', topic] for topic in topics] == [(False, []), (False, [])]
    # Two nodes never share that port.
    other = dds.tailor(packaged, dds.SMALL_SEGMENT, localhost=True, udp_receive=True,
                       shm_topics=topics)
    assert endpoints(other)['data_writer', 'py_vision_udp_writer'] != (True, writer)


def test_on_fast_dds_2_6_nodes_receive_over_udp_but_images_unless_turned_off(
        tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    on_2_6 = ros_harness.ON_HUMBLE  # Humble's rmw_fastrtps 6 runs Fast DDS 2.6 (the boards)
    assert dds.shm_receive_breaks({}) == on_2_6
    camera = dds.use_packaged_profile(dds.OWN_SIZE, [], 'usbcam_publisher',
                                      {'ROS_LOCALHOST_ONLY': '1'}, image_topics=())
    assert listening(camera) == (UDP_ONLY if on_2_6 else SHM_AND_UDP)
    assert endpoints(camera) == {}
    # A node that receives images keeps receiving them through shared memory, and nothing else.
    viewer = dds.use_packaged_profile(dds.NO_IMAGES, [], 'usbcam_subscriber',
                                      {'ROS_LOCALHOST_ONLY': '1'}, image_topics=('/image',))
    assert listening(viewer) == (DISCOVERY_ON_UDP if on_2_6 else SHM_AND_UDP)
    assert (('data_reader', '/image') in endpoints(viewer)) == on_2_6
    assert dds.shm_topics() == (('/image',) if on_2_6 else ())
    # Topics that could not be told: as Fast DDS would.
    unknown = dds.use_packaged_profile(dds.NO_IMAGES, [], 'usbcam_subscriber',
                                       {'ROS_LOCALHOST_ONLY': '1'}, image_topics=None)
    assert listening(unknown) == SHM_AND_UDP and endpoints(unknown) == {}
    env = {dds.SHM_RECEIVE_SETTING: '1', 'ROS_LOCALHOST_ONLY': '1'}
    assert not dds.shm_receive_breaks(env)
    assert listening(dds.use_packaged_profile(
        dds.OWN_SIZE, [], 'usbcam_publisher', env, image_topics=())) == SHM_AND_UDP


def test_a_copy_with_a_port_is_the_process_own(tmp_path, monkeypatch):
    monkeypatch.setenv('TMPDIR', str(tmp_path))
    # One left by a killed process (no such pid) goes; a running process' stays.
    dead = tmp_path / ('py_vision_fastdds_%d_pid%d.xml' % (os.getuid(), 2 ** 22 + 1))
    alive = tmp_path / ('py_vision_fastdds_%d_pid%d.xml' % (os.getuid(), os.getppid()))
    dead.write_text('<profiles/>')
    alive.write_text('<profiles/>')
    path = dds.tailor(dds.packaged_profile(), dds.SMALL_SEGMENT, udp_receive=True,
                      shm_topics=('/image',))
    assert Path(path).name == 'py_vision_fastdds_%d_pid%d.xml' % (os.getuid(), os.getpid())
    assert not dead.exists() and alive.exists()
    assert ('data_reader', '/image') in endpoints(path)


def test_a_port_taken_before_fast_dds_bound_it_is_told(monkeypatch):
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as held:
        held.bind(('', 0))
        port = held.getsockname()[1]
        monkeypatch.setitem(dds._chosen, 'port', port)
        assert dds.lost_port() is None  # this process holds it
    # Nobody holds it now (or another process would): the endpoints hear nothing.
    assert dds.lost_port() == port
    monkeypatch.setitem(dds._chosen, 'port', None)
    assert dds.lost_port() is None  # no port given (Jazzy, or a node reading no images)


def test_a_copy_that_cannot_be_written_leaves_fast_dds_alone(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    monkeypatch.setenv('TMPDIR', str(tmp_path / 'missing'))
    env = {}
    assert dds.use_packaged_profile(dds.OWN_SIZE, [], 'usbcam_publisher', env) is None
    assert env == {}
    said = capsys.readouterr().err
    assert said.count('\n') == 1 and "cannot write the node's profile copy" in said
