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
Use the Fast DDS profile shipped with py_vision unless the user chose their own.

The packaged profile (config/fastdds_image_profile.xml) lists a shared-memory transport for
this host and a UDPv4 transport for other hosts. Each node gets a copy of it, written to the
temporary directory and named after its content, tailored to the node:

- Shared memory sized to what the node itself publishes. Every participant maps its whole
  segment at start-up (real RAM on Fast DDS 2.6 and 2.14), and a subscriber's segment only
  ever carries small messages: the frames it receives are read from the publisher's segment.
  So a node that publishes no images keeps Fast DDS' default size, and one that does gets
  room for a few of its frames in flight, not one fixed size for every node.
- Localhost only when the user asked for it (ROS_LOCALHOST_ONLY=1 on Humble,
  ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST or OFF from Iron on): the UDP transport is then
  restricted to 127.0.0.1. Humble's rmw_fastrtps only adds a localhost transport beside the
  profile's own, so without this the profile's UDP would stay open to the network.
- Socket buffers no larger than the kernel allows (net.core.wmem_max / rmem_max): Fast DDS
  drops its whole UDP transport, silently, when a buffer above the limit is requested, and
  with it every peer on another host.
- On Fast DDS 2.6 (Humble, the boards), a node receives through shared memory its images
  alone: discovery and every other reader and writer (services, parameter events, the graph)
  listen on UDP, the readers of its image topics on the participant's shared-memory port
  (reader profiles named after those topics, which rmw_fastrtps looks up). It still sends
  through shared memory. Fast DDS 2.6.0 to 2.6.5 can stop reading a shared-memory port for
  good, and a node that listened there for everything would go unheard (docs/boards.md, "A
  node nobody hears"). PY_VISION_SHM_RECEIVE=1 turns this off.
"""

import atexit
import os
import socket
import sys
import xml.etree.ElementTree as ET
import zlib

from ament_index_python.packages import get_package_share_directory, PackageNotFoundError
from py_vision import ros_arguments

PROFILE_NAME = 'fastdds_image_profile.xml'
NS = 'http://www.eprosima.com/XMLSchemas/fastRTPS_Profiles'
# The variable Fast DDS 2.x (2.6 on Humble, 2.14 on Jazzy) reads. FASTDDS_DEFAULT_PROFILES_FILE
# is Fast DDS 3's (Kilted on): set alone, 2.x ignores it, and stepping aside for it would
# leave the nodes on the 0.5 MB shared-memory default; 3.x in turn ignores our variable.
USER_SETTING = 'FASTRTPS_DEFAULT_PROFILES_FILE'
_FAST_DDS_RMWS = ('', 'rmw_fastrtps_cpp', 'rmw_fastrtps_dynamic_cpp')
_KERNEL_LIMITS = {
    'sendBufferSize': '/proc/sys/net/core/wmem_max',
    'receiveBufferSize': '/proc/sys/net/core/rmem_max',
}

# What a node publishes, stated by its class (PUBLISHES) and read before rclpy.init(), when
# the segment has to be sized and parameters do not exist yet.
NO_IMAGES = 'no images'
OWN_SIZE = 'images of its image_width x image_height parameters'
INPUT_SIZE = 'images as large as those it receives (the camera node size, if known)'

# Fast DDS' own default segment: enough for everything but images.
SMALL_SEGMENT = 512 * 1024
# Frames in flight a publisher's segment holds (bench/bench_pipeline.py measured it; see
# docs/dds.md), and the size assumed when the node's frame size cannot be read.
SEGMENT_FRAMES = 3
DEFAULT_SIZE = (640, 480)  # usbcam_publisher's image_width, image_height defaults
# The camera node, whose entry in a shared parameter file tells the others the frame size.
CAMERA_NODE = 'usbcam_publisher'
SAFE_SIZE = (1920, 1080)
BYTES_PER_PIXEL = 3

# Fast DDS 2.6.0 to 2.6.5 stop reading a shared-memory port for good when the message at its
# head came from a process that has since removed its segment (fixed in 2.6.6). Humble's
# rmw_fastrtps (6) runs on 2.6: there a node listens on UDP, but for its images.
SHM_RECEIVE_SETTING = 'PY_VISION_SHM_RECEIVE'
# Fast DDS' discovery multicast group (its ports are Fast DDS' own: 0 means computed).
DISCOVERY_MULTICAST = '239.255.0.1'
_RMW_PACKAGE = 'rmw_fastrtps_shared_cpp'


def packaged_profile():
    """Return the installed profile's path, or None when the package is not installed."""
    try:
        share = get_package_share_directory('py_vision')
    except (PackageNotFoundError, OSError):
        # Not found through AMENT_PREFIX_PATH (install/setup.bash not sourced): look where
        # colcon installs it relative to this module, <prefix>/lib/pythonX.Y/site-packages.
        share = os.path.join(os.path.dirname(os.path.abspath(__file__)),
                             '..', '..', '..', '..', 'share', 'py_vision')
    path = os.path.normpath(os.path.join(share, 'config', PROFILE_NAME))
    return path if os.path.isfile(path) else None


def localhost_only(environ=os.environ):
    """Return True when the user asked for ROS traffic on this host only (either variable)."""
    # On Jazzy ROS_LOCALHOST_ONLY=1 overrides the discovery range too; OFF is stricter still.
    return (environ.get('ROS_LOCALHOST_ONLY') == '1'
            or environ.get('ROS_AUTOMATIC_DISCOVERY_RANGE') in ('LOCALHOST', 'OFF'))


def requested_size(args, fully_qualified_name, default=DEFAULT_SIZE):
    """
    Return the (width, height) a node's command line gives the node of that name.

    image_width and image_height as ros_arguments reads them (node_main gives rclpy the same
    values); default where nothing says; SAFE_SIZE when a value or a file cannot be read, so a
    misread never makes the segment too small.
    """
    try:
        values = ros_arguments.given_parameters(args, fully_qualified_name)
        size = (int(values.get('image_width', default[0])),
                int(values.get('image_height', default[1])))
    except (ros_arguments.UnreadableArguments, TypeError, ValueError):
        return SAFE_SIZE
    return size if min(size) > 0 else SAFE_SIZE


def segment_size(publishes, args=(), node_name=''):
    """Return the shared-memory segment, in bytes, for a node that publishes `publishes`."""
    if publishes == NO_IMAGES:
        return SMALL_SEGMENT
    if publishes == OWN_SIZE:
        width, height = requested_size(args, ros_arguments.node_name(args, node_name))
    elif publishes == INPUT_SIZE:
        # It cannot know what it will receive unless told: by what its own command line gives
        # the camera node (image_width, image_height for every node, or the camera's section
        # of the parameter file they share, as pipeline.launch.py gives them). Told nothing,
        # it assumes the camera node's default size, as the camera node itself does: room for
        # 1920x1080 would cost every plain `ros2 run` 15 MiB of RAM. A node that then receives
        # larger frames says so (frame_fits).
        width, height = requested_size(args, '/' + CAMERA_NODE)
    else:
        width, height = SAFE_SIZE
    return max(SMALL_SEGMENT, SEGMENT_FRAMES * width * height * BYTES_PER_PIXEL)


def _kernel_limit(path):
    try:
        with open(path) as limit:
            return int(limit.read())
    except (OSError, ValueError):
        return None


def tailor(profile, segment=None, localhost=False, limits=None, udp_receive=False,
           shm_topics=(), endpoint_port=None):
    """
    Return the path of a copy of profile tailored to one node, or profile itself if unchanged.

    segment: the shared-memory segment size in bytes (None: as in profile); localhost: restrict
    UDP to 127.0.0.1; limits: the kernel's socket buffer limits by element name (by default
    read from /proc/sys/net/core), to which the buffer sizes are capped; udp_receive: the
    participant listens on UDP locators only (discovery and data), none of shared memory, which
    it still sends through; shm_topics: with udp_receive, the topics (resolved names) whose
    readers still listen on shared memory (and UDP), alone on the participant's shared-memory
    port, every other endpoint on UDP endpoint_port (None: one free_udp_port() picks).
    """
    if limits is None:
        limits = {tag: _kernel_limit(path) for tag, path in _KERNEL_LIMITS.items()}
    ET.register_namespace('', NS)
    tree = ET.parse(profile)
    q = '{%s}%%s' % NS
    changed = False
    for descriptor in tree.getroot().iter(q % 'transport_descriptor'):
        kind = descriptor.find(q % 'type').text.strip()
        if kind == 'SHM' and segment is not None:
            element = descriptor.find(q % 'segment_size')
            if int(element.text) != segment:
                element.text = str(segment)
                changed = True
        if kind != 'UDPv4':
            continue
        for tag, limit in limits.items():
            element = descriptor.find(q % tag)
            if element is not None and limit is not None and int(element.text) > limit:
                element.text = str(limit)
                changed = True
        if localhost:
            allowed = ET.Element(q % 'interfaceWhiteList')
            ET.SubElement(allowed, q % 'address').text = '127.0.0.1'
            # Fast DDS' schema wants it right after <type>.
            descriptor.insert(list(descriptor).index(descriptor.find(q % 'type')) + 1, allowed)
            changed = True
    if udp_receive:
        if shm_topics and endpoint_port is None:
            endpoint_port = free_udp_port()
        _receive_over_udp(tree.getroot(), q, shm_topics, endpoint_port)
        changed = True
    if not changed:
        return profile
    fitted = '<?xml version="1.0" encoding="UTF-8"?>\n%s\n' % ET.tostring(
        tree.getroot(), encoding='unicode')
    if udp_receive and shm_topics:
        return _own_copy(fitted)
    # Named after its content, so an upgraded profile rarely meets a stale copy, and checked
    # anyway; a file of another user's is never trusted. (zlib, not hashlib: OpenSSL would add
    # 4 MB to every node.)
    path = os.path.join(os.environ.get('TMPDIR') or '/tmp', 'py_vision_fastdds_%d_%08x.xml' % (
        os.getuid(), zlib.crc32(fitted.encode())))
    if not _holds(path, fitted):
        partial = '%s.%d' % (path, os.getpid())
        _write_new(partial, fitted)
        os.replace(partial, path)
    return path


def _write_new(path, text):
    """Write text to path, a file created here: never an existing file or link there."""
    _remove(path)  # left by a killed process that had this pid
    with os.fdopen(os.open(path, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o644), 'w') as out:
        out.write(text)


_OWN_COPY = 'py_vision_fastdds_%d_pid%d.xml'


def _own_copy(fitted):
    """
    Write a copy that holds a port of this process' own; return its path.

    Named after the process and removed when it ends (Fast DDS reads it once, as the first
    node starts); those of processes that ended without removing theirs (killed) go too.
    """
    directory = os.environ.get('TMPDIR') or '/tmp'
    prefix = 'py_vision_fastdds_%d_pid' % os.getuid()
    for name in os.listdir(directory):
        pid = name[len(prefix):-len('.xml')]
        if name.startswith(prefix) and name.endswith('.xml') and pid.isdigit():
            if not os.path.exists('/proc/%s' % pid):
                _remove(os.path.join(directory, name))
    path = os.path.join(directory, _OWN_COPY % (os.getuid(), os.getpid()))
    _write_new(path, fitted)
    atexit.register(_remove, path)
    return path


def _remove(path):
    try:
        os.unlink(path)
    except OSError:
        pass


def _receive_over_udp(root, q, shm_topics=(), endpoint_port=None):
    """
    Give the profile UDPv4 locators to listen on, and so none of shared memory.

    Without shm_topics, the participant's (discovery and every endpoint). With them, discovery
    and the default reader and writer profiles get UDP locators, and each topic in shm_topics
    a reader profile of its own name (rmw_fastrtps looks one up by the topic's resolved name)
    that lists none: its reader takes the participant's defaults, shared memory first.
    """
    rtps = root.find('%s/%s' % (q % 'participant', q % 'rtps'))

    def udp_list(parent, name, address=None, port=None):
        locator = ET.SubElement(ET.SubElement(parent, q % name), q % 'locator')
        udp = ET.SubElement(locator, q % 'udpv4')
        if port is not None:
            ET.SubElement(udp, q % 'port').text = str(port)
        if address is not None:
            ET.SubElement(udp, q % 'address').text = address
    # No address, no port: every allowed interface, the participant's well-known ports.
    if not shm_topics:
        udp_list(rtps, 'defaultUnicastLocatorList')
    builtin = ET.SubElement(rtps, q % 'builtin')
    udp_list(builtin, 'metatrafficUnicastLocatorList')
    udp_list(builtin, 'metatrafficMulticastLocatorList', DISCOVERY_MULTICAST)
    if not shm_topics:
        return
    # A port of its own: with port 0, Fast DDS 2.6.0 computes one from a participant id not yet
    # given at that point, and the endpoints hear nothing.
    for kind in ('data_writer', 'data_reader'):
        endpoint = ET.SubElement(root, q % kind, {
            'profile_name': 'py_vision_udp_%s' % kind.split('_')[1],
            'is_default_profile': 'true'})
        udp_list(endpoint, 'unicastLocatorList', port=endpoint_port)
    for topic in shm_topics:
        reader = ET.SubElement(root, q % 'data_reader', {'profile_name': topic})
        # As rmw_fastrtps sets it; an element, since an empty profile is not one to Fast DDS.
        ET.SubElement(reader, q % 'historyMemoryPolicy').text = 'PREALLOCATED_WITH_REALLOC'


def free_udp_port():
    """Return a UDP port free on every interface, as the kernel picks one."""
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as probe:
        probe.bind(('', 0))
        return probe.getsockname()[1]


def shm_receive_breaks(environ=os.environ):
    """
    Return True where Fast DDS is 2.6 (rmw_fastrtps 6, Humble) and the user did not opt out.

    Which 2.6 patch release runs cannot be told before it is loaded: every 2.6 counts (2.6.0,
    the boards', to 2.6.5 have the defect).
    """
    return environ.get(SHM_RECEIVE_SETTING) != '1' and fast_dds_2_6()


def fast_dds_2_6():
    """Return True where rmw_fastrtps is 6 (Humble's), which runs on Fast DDS 2.6."""
    try:
        with open(os.path.join(get_package_share_directory(_RMW_PACKAGE), 'package.xml')) as xml:
            version = ET.parse(xml).getroot().findtext('version', '')
    except (PackageNotFoundError, OSError, ET.ParseError):
        return False
    return version.split('.')[0] == '6'


def _holds(path, text):
    """Return True if path is this user's file and holds text."""
    try:
        if os.stat(path).st_uid != os.getuid():
            return False
        with open(path) as existing:
            return existing.read() == text
    except OSError:
        return False


def use_packaged_profile(publishes=None, args=None, node_name='', environ=os.environ,
                         image_topics=None):
    """
    Point Fast DDS at the packaged profile tailored to a node; return its path, or None.

    publishes: NO_IMAGES, OWN_SIZE or INPUT_SIZE (None: large images, SAFE_SIZE); args: the
    node's command line (default sys.argv), where OWN_SIZE and INPUT_SIZE read the frame size;
    image_topics: the resolved topics whose images the node reads. On Fast DDS 2.6
    (shm_receive_breaks) the node then receives through shared memory on these topics alone,
    everything else (discovery, services, other topics) through UDP (none: the node reads no
    images); None: not told, it receives through shared memory as Fast DDS would.
    Left alone (None): another RMW is selected, the user set a profile file, or Fast DDS would
    load DEFAULT_FASTRTPS_PROFILES.xml from the working directory.
    """
    if environ.get('RMW_IMPLEMENTATION', '') not in _FAST_DDS_RMWS:
        return None
    if environ.get(USER_SETTING):
        return None
    if os.path.exists('DEFAULT_FASTRTPS_PROFILES.xml'):
        return None
    path = packaged_profile()
    if path is not None:
        segment = segment_size(publishes, sys.argv if args is None else args, node_name)
        udp = image_topics is not None and shm_receive_breaks(environ)
        shm_topics = tuple(image_topics or ()) if udp else ()
        try:
            port = free_udp_port() if shm_topics else None
            path = tailor(path, segment, localhost_only(environ), udp_receive=udp,
                          shm_topics=shm_topics, endpoint_port=port)
        except OSError as error:  # no room or no right in the temporary directory
            sys.stderr.write('py_vision: Fast DDS keeps its own settings: cannot write the '
                             "node's profile copy (%s)\n" % error)
            return None
        environ[USER_SETTING] = path
        _chosen.update(segment=segment, shm_topics=shm_topics, port=port,
                       linger=fast_dds_2_6() and publishes != NO_IMAGES)
    return path


# What use_packaged_profile() gave this process.
_chosen = {'segment': None, 'shm_topics': (), 'linger': False, 'port': None}
# How long a node that published images through shared memory on Fast DDS 2.6 keeps its
# participant after its last frame: a reader that got its first frame from it just before
# reads it while the segment it is in still exists (else that reader's port is dead for good).
LINGER_S = 0.25


def linger_s():
    """Return the seconds to wait between a node's last frame and its participant's end."""
    return LINGER_S if _chosen['linger'] else 0.0


def lost_port():
    """
    Return the UDP port this process' endpoints were given if no socket of it holds it, or None.

    Asked once the first node exists: another process that bound the port between its choice
    and Fast DDS' own bind leaves every endpoint but the image readers unheard.
    """
    port = _chosen['port']
    held = udp_ports()
    if port is None or held is None or port in held:  # None: cannot tell
        return None
    return port


def udp_ports(pid='self'):
    """Return the local UDP (IPv4) ports a process has sockets on, or None if unreadable."""
    inodes = set()
    try:
        for fd in os.listdir('/proc/%s/fd' % pid):
            try:
                target = os.readlink('/proc/%s/fd/%s' % (pid, fd))
            except OSError:
                continue
            if target.startswith('socket:['):
                inodes.add(target[8:-1])
        with open('/proc/%s/net/udp' % pid) as table:
            rows = [line.split() for line in table.readlines()[1:]]
    except OSError:
        return None
    return {int(row[1].rsplit(':', 1)[1], 16) for row in rows if row[9] in inodes}


def shm_topics():
    """Return the topics whose readers alone receive through shared memory (empty: all do)."""
    return _chosen['shm_topics']


def frame_fits(frame_bytes, segment=None):
    """
    Return True if frames of frame_bytes fit the shared-memory segment this process was given.

    segment: in bytes (default: the one use_packaged_profile() chose; None when the node runs
    on another profile, which is then the user's to size). A segment holds SEGMENT_FRAMES
    frames; larger frames reach same-host subscribers late or not at all.
    """
    segment = _chosen['segment'] if segment is None else segment
    return segment is None or frame_bytes * SEGMENT_FRAMES <= segment
