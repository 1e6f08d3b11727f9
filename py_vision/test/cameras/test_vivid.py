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
usbcam_publisher on the Linux kernel's own virtual video driver, vivid, in a QEMU VM.

Real kernel V4L2 semantics, where the emulated cameras give uvcvideo's as emulated: vivid's
formats, sizes and controls listed; its YUYV test pattern published with the right colours;
controls given on the command line reaching the device, and vivid's controls as parameters
with its ranges and menus; its injected faults (a fatal streaming error, a buffer flagged as
an error, a failing STREAMON) survived; a managed node deactivated, keeping the device, and
activated. Each test sends a function to the VM
(`vivid.run`, docs/vivid.md), which runs the installed nodes there on vivid's device and
returns what they did; the assertions are made here.
"""

import errno
import os
import re

from lifecycle_client import CameraStatus, Lifecycle
from lifecycle_msgs.msg import Transition
from listing_text import control_line, formats
import numpy as np
from param_client import describe_parameters, get_parameters, list_parameters, set_parameter
from py_vision.control_names import param_name
import pytest
from rcl_interfaces.msg import ParameterType
from ros_harness import wait_until
from sensor_msgs.msg import Image
import v4l2_ioctl

NODE = 'usbcam_publisher'
CTRL_READ_ONLY = v4l2_ioctl.CTRL_FLAG_READ_ONLY
INTEGER, BOOLEAN, MENU, BUTTON, INTEGER64, BITMASK, INTEGER_MENU = (
    v4l2_ioctl.CTRL_TYPE_INTEGER, v4l2_ioctl.CTRL_TYPE_BOOLEAN, v4l2_ioctl.CTRL_TYPE_MENU,
    v4l2_ioctl.CTRL_TYPE_BUTTON, v4l2_ioctl.CTRL_TYPE_INTEGER64, v4l2_ioctl.CTRL_TYPE_BITMASK,
    v4l2_ioctl.CTRL_TYPE_INTEGER_MENU)
# The control types one number sets, and the parameter type each becomes (a button: true
# presses it).
PARAMETER_TYPES = {INTEGER: ParameterType.PARAMETER_INTEGER,
                   BOOLEAN: ParameterType.PARAMETER_BOOL,
                   MENU: ParameterType.PARAMETER_INTEGER,
                   BUTTON: ParameterType.PARAMETER_BOOL,
                   INTEGER64: ParameterType.PARAMETER_INTEGER,
                   BITMASK: ParameterType.PARAMETER_INTEGER,
                   INTEGER_MENU: ParameterType.PARAMETER_INTEGER}
# How --list-formats names each type, and the parameters' ranges (the rest have none).
LISTED_AS = {INTEGER: 'int', BOOLEAN: 'bool', MENU: 'menu', BUTTON: 'button',
             INTEGER64: 'int64', BITMASK: 'bitmask', INTEGER_MENU: 'integer menu'}
RANGED = (INTEGER, INTEGER64, MENU, INTEGER_MENU)
# vivid's test_pattern menu entry "100% Colorbar": white, yellow, cyan, green, magenta, red,
# blue and black bars (BGR), left to right, each an eighth of the width; osd_text_mode 2
# ("None") leaves the text off the picture.
COLOUR_BARS = {'test_pattern': 1, 'osd_text_mode': 2}
BARS_BGR = [(255, 255, 255), (0, 255, 255), (255, 255, 0), (0, 255, 0), (255, 0, 255),
            (0, 0, 255), (255, 0, 0), (0, 0, 0)]
# A limited-range 4:2:2 picture converted back to 8-bit BGR: a few levels of rounding.
COLOUR_TOLERANCE = 8
# Small frames at vivid's webcam rate: the VM's CPU is emulated.
STREAM = {'image_width': 320, 'image_height': 180, 'framerate': 15.0}


def image_of(msg):
    return np.frombuffer(msg.data, np.uint8).reshape(msg.height, msg.width, -1)


def bar_colours(image):
    """Return each eighth's median colour, over the rows around the middle."""
    height, width = image.shape[:2]
    rows = image[height * 3 // 8:height * 5 // 8]
    return [tuple(int(c) for c in np.median(
        rows[:, width * i // 8 + width // 32:width * (i + 1) // 8 - width // 32].reshape(-1, 3),
        axis=0)) for i in range(8)]


# The functions below run in the VM (vivid.run): vm is vivid_agent.Vm.

def listing(vm):
    node = vm.launch(NODE, params={'video_device': vm.device}, extra_args=['--list-formats'])
    return {'status': node.wait_exit(60), 'output': node.output(), 'formats': vm.formats(),
            'controls': vm.controls()}


def stream(vm, params, count=3, names=()):
    """Start the publisher on the device with params; the last frames, and controls' values."""
    frames = vm.peer.collect(Image, 'usb_camera/image')
    node = vm.launch(NODE, params=dict(STREAM, video_device=vm.device, **params))
    wait_until(lambda: len(frames) >= count, 120, what='%d frames' % count)
    return {'frames': [(msg.encoding, image_of(msg)) for msg in frames[-count:]],
            'values': {name: vm.control(name) for name in names}, 'output': node.output()}


def parameters(vm):
    """Return the publisher's descriptors of the controls one number sets, and the controls."""
    controls = [c for c in vm.controls() if c['type'] in PARAMETER_TYPES]
    node = vm.launch(NODE, params=dict(STREAM, video_device=vm.device))
    node.wait_for_output('opened', 120)
    names = [param_name(c['name']) for c in controls]
    described = describe_parameters(vm.peer, NODE, names)
    return {'controls': controls, 'descriptors': [
        (d.name, d.type, d.read_only, d.description,
         [(r.from_value, r.to_value, r.step) for r in d.integer_range]) for d in described]}


# The tests.

def test_list_formats_shows_every_format_size_rate_and_control_vivid_offers(vivid):
    got = vivid.run(listing)
    out = got['output']
    assert got['status'] == 0, out
    printed = {description: (fourcc, sizes) for fourcc, description, sizes in formats(out)}
    assert len(got['formats']) > 50  # vivid offers dozens of raw formats
    for code, description, sizes in got['formats']:
        assert description in printed, 'format %r (%s) not listed:\n%s' % (
            code, description, out)
        fourcc, listed = printed[description]
        if code.isascii():  # a big-endian variant's mark (bit 31) is not ASCII
            assert fourcc == code.strip(), description
        assert {size: sorted(rates) for size, rates in listed.items()} == \
            {size: sorted(rates) for size, rates in sizes.items()}, description
    assert len(printed) == len(got['formats'])
    for control in got['controls']:
        if control['type'] == v4l2_ioctl.CTRL_TYPE_CTRL_CLASS:
            continue
        line = control_line(out, param_name(control['name']))
        assert line is not None, 'control %s not listed:\n%s' % (control['name'], out)
        if control['type'] not in PARAMETER_TYPES:  # a string
            assert line.endswith('not a parameter'), line
            continue
        assert '(0x%08x): %s' % (control['id'], LISTED_AS[control['type']]) in line, line
        if control['type'] in (INTEGER, INTEGER64):
            assert '%d..%d' % (control['min'], control['max']) in line, line
        for index, name in control.get('menu', {}).items():
            assert '%d=%s' % (index, name) in line, line
        assert ('read-only' in line) == bool(control['flags'] & CTRL_READ_ONLY), line


def test_yuyv_colour_bars_arrive_with_their_colours(vivid):
    got = vivid.run(stream, params=dict(COLOUR_BARS, pixel_format='yuyv'))
    assert 'YUYV' in got['output']
    for encoding, image in got['frames']:
        assert encoding == 'bgr8' and image.shape == (180, 320, 3)
        for bar, (found, expected) in enumerate(zip(bar_colours(image), BARS_BGR)):
            assert max(abs(a - b) for a, b in zip(found, expected)) <= COLOUR_TOLERANCE, (
                'bar %d is %s, not %s' % (bar, found, expected))


def stream_as(vm, pixel_format, outputs):
    """Stream the colour bars in a pixel format as each output; what each published."""
    from py_vision.cv_bridge import CvBridge
    bridge, got = CvBridge(), {}
    for output in outputs:
        frames = vm.peer.collect(Image, 'usb_camera/image')
        status = CameraStatus(vm.peer)
        node = vm.launch(NODE, params=dict(STREAM, **COLOUR_BARS, video_device=vm.device,
                                           pixel_format=pixel_format, output_encoding=output))
        wait_until(lambda: len(frames) >= 3, 120, what='3 frames')
        wait_until(lambda: status.latest()[1].get('io method'), 60,
                   what='a report saying how frames reach the node')
        got[output + ' io method'] = status.latest()[1]['io method']
        node.end(timeout=60)   # Ctrl-C, the VM's CPU being slow: the device free again
        got[output] = [(msg.encoding, msg.step, len(msg.data),
                        bridge.imgmsg_to_cv2(msg, 'bgr8')) for msg in list(frames)[-2:]]
        got[output + ' log'] = node.output()
    return got


# Each raw format the issue names: the encoding native publishes, its bytes per pixel.
RAW = {'GREY': ('mono8', 1), 'RGB3': ('rgb8', 3), 'YUYV': ('yuv422_yuy2', 2),
       'UYVY': ('yuv422', 2), 'NV12': ('bgr8', 3)}   # sensor_msgs has no NV12: converted


@pytest.mark.parametrize('fourcc', list(RAW))
def test_every_raw_format_streams_right_as_native_and_as_bgr8(vivid, fourcc):
    got = vivid.run(stream_as, pixel_format=fourcc, outputs=['native', 'bgr8'])
    native, bytes_per_pixel = RAW[fourcc]
    for output, encoding in (('native', native), ('bgr8', 'bgr8')):
        log = got[output + ' log']
        assert 'opened %s: 320x180 %s at' % ('/dev/video0', fourcc) in log, log
        # The kernel's vb2 takes user memory: native frames the camera wrote into the
        # messages themselves; converted ones (NV12, bgr8) come from the driver's buffers.
        assert got[output + ' io method'] == (
            'userptr' if output == 'native' and native != 'bgr8' else 'mmap'), \
            (output, got[output + ' io method'])
        for published, step, size, image in got[output]:
            assert published == encoding, (output, published)
            if output == 'native':   # the camera's bytes, in its own layout
                assert (step, size) == (320 * bytes_per_pixel, 320 * 180 * bytes_per_pixel)
            found = bar_colours(image)
            if fourcc == 'GREY':
                # Grey bars: the colour bars' luma, white to black, each darker than the last.
                levels = [colour[0] for colour in found]
                assert all(colour == (level,) * 3 for colour, level in zip(found, levels))
                assert levels[0] > 200 and levels[-1] < 40, levels
                assert all(a > b + 8 for a, b in zip(levels, levels[1:])), levels
                continue
            for bar, (colour, expected) in enumerate(zip(found, BARS_BGR)):
                assert max(abs(a - b) for a, b in zip(colour, expected)) <= \
                    COLOUR_TOLERANCE, '%s as %s: bar %d is %s, not %s' % (
                        fourcc, output, bar, colour, expected)


# Values other than each control's default, of every type one number sets (but a button).
GIVEN = {'brightness': 200, 'contrast': 90, 'hue': -20, 'horizontal_flip': True,
         'gain_automatic': False, 'gain': 77, 'menu': 4, 'integer_32_bits': -123456,
         'integer_64_bits': 2**40 + 3, 'integer_menu': 4, 'bitmask': 0x00400010}


def test_controls_given_on_the_command_line_reach_the_device(vivid):
    got = vivid.run(stream, params=GIVEN, count=1, names=list(GIVEN))
    assert got['values'] == {name: int(value) for name, value in GIVEN.items()}, got['output']


def test_vivids_controls_are_parameters_with_its_ranges_and_menus(vivid):
    got = vivid.run(parameters)
    assert len(got['controls']) > 30
    for control, (name, kind, read_only, description, ranges) in zip(
            got['controls'], got['descriptors']):
        assert name == param_name(control['name'])
        assert kind == PARAMETER_TYPES[control['type']], name
        assert read_only == bool(control['flags'] & CTRL_READ_ONLY), name
        assert description.startswith(control['name']), (name, description)
        if control['type'] in RANGED:
            assert ranges == [(control['min'], control['max'], control['step'])], name
        elif control['type'] in (BOOLEAN, BUTTON):
            assert not ranges, name
        for index, entry in control.get('menu', {}).items():
            assert '%d=%s' % (index, entry) in description, (name, description)


# Faults, in the VM: each pressed on the running node, which must get over it.

def recovering(vm, node, frames, fault, sign):
    """Inject fault; wait for the node to log sign once more, then for frames to flow again."""
    start = len(node.output())
    seen = node.output().count(sign)
    before = len(frames)
    fault()
    try:
        wait_until(lambda: node.output().count(sign) > seen or node.proc.poll() is not None,
                   120, what='%r once more in the log' % sign)
    except AssertionError as error:
        node.fail(str(error))
    after = len(frames)
    wait_until(lambda: len(frames) >= after + 5, 120, what='frames after %s' % sign)
    return {'log': node.output()[start:], 'frames_before': before,
            'frames_after': len(frames) - after, 'running': node.proc.poll() is None}


def injected_faults(vm):
    frames = vm.peer.collect(Image, 'usb_camera/image')
    node = vm.launch(NODE, params=dict(STREAM, video_device=vm.device))
    wait_until(lambda: len(frames) >= 5, 120, what='5 frames')
    return {
        'flagged': recovering(vm, node, frames,
                              lambda: vm.set_control('inject_v4l2_buf_flag_error'),
                              'flagged as an error'),
        'fatal': recovering(vm, node, frames,
                            lambda: vm.set_control('inject_fatal_streaming_error'),
                            'is back after'),
        'streamon': recovering(vm, node, frames, lambda: (
            vm.set_control('inject_vidioc_streamon_error'),
            vm.set_control('inject_fatal_streaming_error')), 'is back after'),
        'output': node.output()}


def unplugged(vm):
    """Stream with a control given, unbind the driver, bind it again; what the node did."""
    frames = vm.peer.collect(Image, 'usb_camera/image')
    node = vm.launch(NODE, params=dict(STREAM, video_device=vm.device, brightness=200))
    wait_until(lambda: len(frames) >= 5, 120, what='5 frames')
    vm.unplug()
    node.wait_for_output('lost %s' % vm.device, 120)
    gone = not os.path.exists(vm.device)
    # Released means no handle and no mapping left: the kernel frees the device's number
    # only then, and gives it to the device when it comes back.
    try:
        wait_until(lambda: not vm.held_by(node.proc.pid), 30, what='the device released')
        held = []
    except AssertionError:
        held = vm.held_by(node.proc.pid)
    got = {'gone': gone, 'held': held}
    if held:
        vm.plug()
        got.update(device=vm.device, output=node.output())
        return got
    # Plugged back inside recovering(), which counts the node's 'is back after' lines first.
    got.update(recovering(vm, node, frames, vm.plug, 'is back after'))   # back at its defaults
    got.update(device=vm.device, brightness=vm.control('brightness'), output=node.output())
    return got


def deactivated(vm):
    """Activate, deactivate, activate a managed node: its frames, and who has the device."""
    frames = vm.peer.collect(Image, 'usb_camera/image')
    node = vm.launch(NODE, params=dict(STREAM, video_device=vm.device, managed=True))
    lifecycle = Lifecycle(vm.peer)
    got = {'configured': lifecycle.set(Transition.TRANSITION_CONFIGURE),
           'activated': lifecycle.set(Transition.TRANSITION_ACTIVATE)}
    wait_until(lambda: len(frames) >= 5, 120, what='frames while active')
    got['deactivated'] = lifecycle.set(Transition.TRANSITION_DEACTIVATE)
    node.wait_for_output('deactivated: streaming stopped after', 60)
    count = len(frames)
    # Another program asking for a format while the node keeps the device: the kernel says.
    fd = v4l2_ioctl.open_device(vm.device)
    try:
        v4l2_ioctl.set_format(fd, 'YUYV', 320, 180)
        got['other_program'] = 'granted'
    except OSError as error:
        got['other_program'] = errno.errorcode[error.errno]
    finally:
        os.close(fd)
    got['kept'] = vm.open_by(node.proc.pid)
    got['reactivated'] = lifecycle.set(Transition.TRANSITION_ACTIVATE)
    wait_until(lambda: len(frames) >= count + 5, 120, what='frames after activating again')
    got['output'] = node.output()
    return got


# Parameter changes on vivid, in the VM: the refusal of a control auto gain holds, a 64-bit
# value, a button pressed, and every control of the device with what it is.
WIDE = -(2 ** 50) - 7


def change_controls(vm):
    node = vm.launch(NODE, params=dict(STREAM, video_device=vm.device))
    node.wait_for_output('opened', 120)
    wait_until(lambda: 'button' in list_parameters(vm.peer, NODE), 120,
               what='the controls declared')
    got = {'gain_refused': set_parameter(vm.peer, NODE, 'gain', 50).reason,
           'gain_constraints': describe_parameters(
               vm.peer, NODE, ['gain'])[0].additional_constraints,
           'wide': set_parameter(vm.peer, NODE, 'integer_64_bits', WIDE).successful,
           'wide_value': vm.control('integer_64_bits'),
           'pressed': set_parameter(vm.peer, NODE, 'button', True).reason or 'pressed'}
    wait_until(lambda: get_parameters(vm.peer, NODE, ['button'])[0].bool_value is False, 60,
               what='the button to read back false')
    got['gain_freed'] = [set_parameter(vm.peer, NODE, name, value).reason for name, value in
                         (('gain_automatic', False), ('gain', 50))]
    got['gain_value'] = vm.control('gain')
    fd = os.open(vm.device, os.O_RDWR | os.O_NONBLOCK)
    try:
        got['controls'] = v4l2_ioctl.list_ext_controls(
            fd, v4l2_ioctl.CTRL_FLAG_NEXT_CTRL | v4l2_ioctl.CTRL_FLAG_NEXT_COMPOUND)
    finally:
        os.close(fd)
    got['parameters'] = list_parameters(vm.peer, NODE)
    got['output'] = node.output()
    return got


@pytest.fixture(scope='module')
def faults(vivid_session):
    """Inject the faults once, on one node, for the tests that read what it did."""
    return vivid_session.vm_or_skip().run(injected_faults)


def test_a_buffer_flagged_as_an_error_is_dropped_and_said(faults):
    got = faults['flagged']
    assert 'delivered a frame flagged as an error (1 so far); dropped, never published' in \
        got['log'], faults['output']
    assert 'lost' not in got['log'], faults['output']   # one bad buffer is no reason to reopen
    assert got['running'] and got['frames_after'] >= 5


def test_a_fatal_streaming_error_is_survived(faults):
    got = faults['fatal']
    assert re.search(r'lost /dev/video\d+ after \d+ failed reads; releasing it and reopening'
                     r'.*is back after 1 attempt', got['log'], re.S), faults['output']
    assert got['running'] and got['frames_after'] >= 5


def test_a_streamon_that_fails_is_tried_again(faults):
    got = faults['streamon']
    assert re.search(r'reopen attempt 1 failed: .*VIDIOC_STREAMON: Invalid argument.*'
                     r'is back after 2 attempt', got['log'], re.S), faults['output']
    assert got['running'] and got['frames_after'] >= 5


def test_an_unplug_is_survived_and_the_controls_set_again(vivid):
    got = vivid.run(unplugged)
    assert got['gone'], 'the device node stayed after the driver was unbound'
    assert not got['held'], 'the node said it released %s but still holds it:\n%s\n%s' % (
        got['device'], '\n'.join(got['held']), got['output'])
    assert got['device'] == '/dev/video0', got   # its number, free again, given back to it
    assert got['running'] and got['frames_after'] >= 5, got['output']
    assert got['brightness'] == 200, got['output']  # the device came back at its default, 128


def test_deactivate_stops_streaming_and_keeps_the_device(vivid):
    got = vivid.run(deactivated)
    assert got['configured'] and got['activated'] and got['deactivated'], got['output']
    assert got['kept'] and got['other_program'] == 'EBUSY', got
    assert got['reactivated'], got['output']
    assert got['output'].count('opened /dev/video') == 1, got['output']  # never reopened


def kind_of(control):
    """Return what a control that is not a parameter is, as the publisher says it."""
    if control['dims'] or control['type'] in (0x100, 0x101, 0x102) or (
            control['flags'] & v4l2_ioctl.CTRL_FLAG_DYNAMIC_ARRAY):
        return 'array'
    return 'string' if control['type'] == v4l2_ioctl.CTRL_TYPE_STRING else 'compound'


def test_a_refused_gain_names_auto_gain_and_every_control_type_is_handled(vivid):
    got = vivid.run(change_controls)
    out = got['output']
    # vivid's auto gain holds the gain (v4l2_ctrl_auto_cluster): the refusal names it.
    assert got['gain_refused'] == 'gain is inactive while gain_automatic is 1', out
    assert got['gain_constraints'].endswith('; inactive while gain_automatic is 1')
    assert got['gain_freed'] == ['', ''] and got['gain_value'] == 50, out
    # A 64-bit value beyond 32 bits reaches the device (VIDIOC_S_EXT_CTRLS).
    assert got['wide'] and got['wide_value'] == WIDE, out
    # The button is pressed (the driver took it) and reads back false.
    assert got['pressed'] == 'pressed', out
    # Every control: a parameter when one number sets it, else named once in the log.
    others = []
    for control in got['controls']:
        if control['type'] == v4l2_ioctl.CTRL_TYPE_CTRL_CLASS:
            continue
        name = param_name(control['name'])
        if control['type'] in PARAMETER_TYPES and not control['dims'] and not (
                control['flags'] & v4l2_ioctl.CTRL_FLAG_DYNAMIC_ARRAY):
            assert name in got['parameters'], name
        else:
            assert name not in got['parameters'], name
            others.append('%s (%s)' % (name, kind_of(control)))
    assert {'string (string)', 'area (compound)', 'u32_1_element_array (array)'} <= set(others)
    said = re.findall(r'not parameters \(no single value to set\): (.*)', out)
    assert len(said) == 1 and said[0].split(', ') == others, out
