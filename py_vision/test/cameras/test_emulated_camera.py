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
The emulated UVC camera (emulated_camera.py, uvc_emulator/) seen as a program sees a camera.

Every check runs in a child process started with the camera's environment (LD_PRELOAD takes
effect at process start), with this run's OpenCV (5.0 in the main run, 4.6.0 in the board
run): OpenCV's own V4L2 backend opens and streams the device, and V4L2 ioctls written here
(v4l2_ioctl.py) enumerate it, drive its controls and stream from it. The test process injects
the faults and reads the camera's state back.
"""

import json
import os
import selectors
import subprocess
import sys
import textwrap

from emulated_camera import HERE
import ros_harness
import v4l2_ioctl as v4l2

PRELUDE = """
import errno, json, os, sys, time
import cv2
import numpy as np
import v4l2_ioctl as v4l2
from emulated_camera import expected_yuyv, jpeg_digest
from py_vision.capture.synthetic_picture import read_frame_index

def say(**values):
    print(json.dumps(values), flush=True)

def hear():
    return sys.stdin.readline().strip()

def error_of(call, *args):
    try:
        call(*args)
    except OSError as error:
        return errno.errorcode[error.errno] if error.errno else type(error).__name__
    return None
"""


class Child:
    """A Python process with the cameras' environment, talking JSON lines with the test."""

    def __init__(self, cameras, code):
        env = ros_harness.installed_env()
        for camera in cameras if isinstance(cameras, (list, tuple)) else [cameras]:
            env = camera.env(env)
        env['PYTHONPATH'] = os.pathsep.join([str(HERE), env.get('PYTHONPATH', '')])
        self.proc = subprocess.Popen(
            [sys.executable, '-u', '-c', PRELUDE + textwrap.dedent(code)], env=env,
            stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        self.selector = selectors.DefaultSelector()
        self.selector.register(self.proc.stdout, selectors.EVENT_READ)

    def expect(self, timeout=20.0):
        """Return the child's next JSON message; fail with its stderr if none comes."""
        if self.selector.select(timeout):
            line = self.proc.stdout.readline()
            if line:
                return json.loads(line)
        self.proc.kill()
        raise AssertionError('the child said nothing within %.0f s; its stderr:\n%s'
                             % (timeout, self.proc.stderr.read()[-3000:]))

    def tell(self, text='go'):
        """Send the child a line."""
        self.proc.stdin.write(text + '\n')
        self.proc.stdin.flush()

    def close(self, timeout=20.0):
        """Wait for the child to end; fail with its stderr if it failed."""
        try:
            self.proc.stdin.close()
        except OSError:
            pass
        try:
            status = self.proc.wait(timeout)
        except subprocess.TimeoutExpired:
            self.proc.kill()
            self.proc.wait()
            status = 'killed after %.0f s' % timeout
        err = self.proc.stderr.read()
        self.proc.stdout.close()
        self.proc.stderr.close()
        self.selector.close()
        assert status == 0, 'the child ended with %s:\n%s' % (status, err[-3000:])


def run(cameras, code, timeout=30.0):
    """Run code in a child with the camera (or a list of them); return what it said."""
    child = Child(cameras, code)
    try:
        out, err = child.proc.communicate(timeout=timeout)
    except subprocess.TimeoutExpired:
        child.proc.kill()
        out, err = child.proc.communicate()
        raise AssertionError('the child did not end within %.0f s:\n%s' % (timeout, err[-3000:]))
    finally:
        child.selector.close()
    assert child.proc.returncode == 0, 'the child failed:\n%s' % err[-3000:]
    return [json.loads(line) for line in out.splitlines() if line.startswith('{')]


def test_the_device_paths_look_like_a_plugged_in_camera(emulated_camera):
    camera = emulated_camera()
    [seen] = run(camera, """
        import glob, stat
        st = os.stat('/dev/video40')
        link = os.lstat(%r)
        say(char=stat.S_ISCHR(st.st_mode), major=os.major(st.st_rdev), minor=os.minor(st.st_rdev),
            link=stat.S_ISLNK(link.st_mode), readlink=os.readlink(%r),
            real_id=os.path.realpath(%r), real_path=os.path.realpath(%r),
            exists=os.path.exists(%r), access=os.access('/dev/video40', os.R_OK | os.W_OK),
            other=os.path.exists('/dev/video41'),
            by_id=os.path.basename(%r) in os.listdir('/dev/v4l/by-id'),
            by_path=os.path.basename(%r) in [
                e.name for e in os.scandir('/dev/v4l/by-path') if e.is_symlink()],
            nodes='/dev/video40' in glob.glob('/dev/video*'), dir=os.path.isdir('/dev/v4l'))
    """ % (camera.by_id, camera.by_id, camera.by_id, camera.by_path, camera.by_id, camera.by_id,
           camera.by_path))
    assert seen == {'char': True, 'major': 81, 'minor': 40, 'link': True,
                    'readlink': '../../video40', 'real_id': '/dev/video40',
                    'real_path': '/dev/video40', 'exists': True, 'access': True, 'other': False,
                    'by_id': True, 'by_path': True, 'nodes': True, 'dir': True}
    assert camera.device == '/dev/video40'
    assert camera.by_id.startswith('/dev/v4l/by-id/usb-PyVision_Emu_Webcam_1080p_')


def test_opencv_opens_it_by_path_and_by_index_and_streams_the_frames_it_should(emulated_camera):
    camera = emulated_camera()
    [by_path, by_index] = run(camera, """
        for source in ('/dev/video40', 40):
            cap = cv2.VideoCapture(source, cv2.CAP_V4L2)
            frames = [cap.read()[1] for _ in range(4)]
            indexes = [read_frame_index(f) for f in frames]
            diff = max(int(np.abs(f.astype(int) - cv2.cvtColor(
                expected_yuyv(i, 640, 480), cv2.COLOR_YUV2BGR_YUYV).astype(int)).max())
                for f, i in zip(frames, indexes))
            say(opened=cap.isOpened(), shape=list(frames[0].shape), indexes=indexes, diff=diff,
                fourcc=v4l2.fourcc_text(int(cap.get(cv2.CAP_PROP_FOURCC))),
                fps=cap.get(cv2.CAP_PROP_FPS))
            cap.release()
    """)
    for seen in (by_path, by_index):
        assert seen['opened'] and seen['shape'] == [480, 640, 3]
        assert seen['fourcc'] == 'YUYV' and seen['fps'] == 30
        indexes = seen['indexes']
        assert all(b > a for a, b in zip(indexes, indexes[1:])), indexes
        assert seen['diff'] == 0, 'a frame differs from the picture of its index'
    assert by_index['indexes'][0] > by_path['indexes'][-1], 'the index goes on across opens'
    assert camera.frames_served >= 8


def test_opencv_negotiates_sizes_rates_and_formats_as_with_a_real_camera(emulated_camera):
    camera = emulated_camera()
    modes = run(camera, """
        cap = cv2.VideoCapture('/dev/video40', cv2.CAP_V4L2)
        for code, width, height, fps in [('YUYV', 1300, 730, 30), ('YUYV', 1920, 1080, 30),
                                         ('MJPG', 1920, 1080, 30), ('MJPG', 330, 250, 15),
                                         ('YUYV', 640, 480, 11)]:
            cap.set(cv2.CAP_PROP_FOURCC, cv2.VideoWriter_fourcc(*code))
            cap.set(cv2.CAP_PROP_FRAME_WIDTH, width)
            cap.set(cv2.CAP_PROP_FRAME_HEIGHT, height)
            cap.set(cv2.CAP_PROP_FPS, fps)
            ok, frame = cap.read()
            say(ok=ok, shape=list(frame.shape[:2]), index=read_frame_index(frame),
                fourcc=v4l2.fourcc_text(int(cap.get(cv2.CAP_PROP_FOURCC))),
                fps=cap.get(cv2.CAP_PROP_FPS))
    """, timeout=60)
    got = [(m['fourcc'], m['shape'], m['fps']) for m in modes]
    # The nearest offered size; YUYV's rate limited by the USB 2.0 budget, MJPEG's not; an
    # unoffered rate becomes the nearest offered one.
    assert got == [('YUYV', [720, 1280], 10), ('YUYV', [1080, 1920], 5),
                   ('MJPG', [1080, 1920], 30), ('MJPG', [240, 320], 15), ('YUYV', [480, 640], 10)]
    assert all(m['ok'] and m['index'] is not None for m in modes)


def test_mjpeg_frames_are_real_jpeg_that_differ_frame_to_frame(emulated_camera):
    camera = emulated_camera()
    [seen] = run(camera, """
        cap = cv2.VideoCapture('/dev/video40', cv2.CAP_V4L2)
        cap.set(cv2.CAP_PROP_FOURCC, cv2.VideoWriter_fourcc(*'MJPG'))
        cap.set(cv2.CAP_PROP_CONVERT_RGB, 0)
        raw = [cap.read()[1].tobytes() for _ in range(4)]
        decoded = [cv2.imdecode(np.frombuffer(b, np.uint8), cv2.IMREAD_COLOR) for b in raw]
        indexes = [read_frame_index(d) for d in decoded]
        errors = [float(np.abs(d.astype(float) - cv2.cvtColor(
            expected_yuyv(i, 640, 480), cv2.COLOR_YUV2BGR_YUYV)).mean())
            for d, i in zip(decoded, indexes)]
        say(soi=all(b[:2] == b'\\xff\\xd8' for b in raw),
            eoi=all(b[-2:] == b'\\xff\\xd9' for b in raw), distinct=len(set(raw)),
            indexes=indexes, error=max(errors), shape=list(decoded[0].shape))
    """)
    assert seen['soi'] and seen['eoi'] and seen['distinct'] == 4
    assert seen['shape'] == [480, 640, 3]
    assert all(b > a for a, b in zip(seen['indexes'], seen['indexes'][1:])), seen['indexes']
    assert seen['error'] < 3.0, 'the decoded JPEG is far from the picture of its index'


def test_the_camera_records_the_exact_bytes_of_every_jpeg_it_serves(emulated_camera):
    camera = emulated_camera()
    assert camera.served_jpeg_digest(0) is None and camera.served_jpegs() == []
    [seen] = run(camera, """
        cap = cv2.VideoCapture('/dev/video40', cv2.CAP_V4L2)
        cap.set(cv2.CAP_PROP_FOURCC, cv2.VideoWriter_fourcc(*'MJPG'))
        cap.set(cv2.CAP_PROP_CONVERT_RGB, 0)
        raw = [cap.read()[1].tobytes() for _ in range(6)]
        indexes = [read_frame_index(cv2.imdecode(np.frombuffer(b, np.uint8), cv2.IMREAD_COLOR))
                   for b in raw]
        say(indexes=indexes, digests=[jpeg_digest(b) for b in raw])
        cap.release()
    """)
    # What OpenCV returned with CONVERT_RGB off is, byte for byte, what the camera served as
    # the frame whose index the picture carries.
    assert None not in seen['indexes'], seen
    for index, digest in zip(seen['indexes'], seen['digests']):
        assert camera.served_jpeg_digest(index) == tuple(digest), (index, digest)
    served = camera.served_jpegs()
    assert set(seen['indexes']) <= {jpeg.index for jpeg in served}
    assert not any(jpeg.corrupt for jpeg in served)
    assert len(set(map(tuple, seen['digests']))) == len(seen['digests'])   # all differ


def test_ioctls_enumerate_what_the_data_file_describes(emulated_camera):
    camera = emulated_camera()
    [seen] = run(camera, """
        fd = v4l2.open_device('/dev/video40')
        formats = v4l2.enum_formats(fd)
        modes = {code: {'%dx%d' % s: v4l2.enum_intervals(fd, code, *s)
                        for s in v4l2.enum_sizes(fd, code)} for code, _, _ in formats}
        say(cap=v4l2.querycap(fd), formats=formats, modes=modes, fmt=v4l2.get_format(fd),
            parm=v4l2.get_interval(fd))
    """)
    driver, card, bus, caps, device_caps = seen['cap']
    assert (driver, card, bus) == ('uvcvideo', 'Emu Webcam 1080p', 'usb-0000:00:14.0-2')
    wanted = v4l2.CAP_VIDEO_CAPTURE | v4l2.CAP_STREAMING
    assert device_caps & wanted == wanted and caps & wanted == wanted
    model = camera.model
    assert seen['formats'] == [[f['fourcc'], 1 if f['compressed'] else 0, f['description']]
                               for f in model['formats']]
    for fmt in model['formats']:
        offered = seen['modes'][fmt['fourcc']]
        assert list(offered) == ['%dx%d' % tuple(s) for s in fmt['sizes']]
        for frame in fmt['frames']:
            key = '%dx%d' % (frame['width'], frame['height'])
            assert offered[key] == [[1, r] for r in frame['rates']]
    yuyv = seen['modes']['YUYV']
    # USB 2.0 bandwidth: 24 MB/s of YUYV is VGA at 30, 720p at 10, 1080p at 5 fps.
    assert (yuyv['640x480'][0], yuyv['1280x720'][0], yuyv['1920x1080']) == (
        [1, 30], [1, 10], [[1, 5]])
    assert seen['modes']['MJPG']['1920x1080'][0] == [1, 30]
    assert seen['fmt'] == ['YUYV', 640, 480, 1280, 640 * 480 * 2]
    assert seen['parm'] == [1, 30]


def test_controls_answer_as_uvcvideo_and_persist_across_opens(emulated_camera):
    camera = emulated_camera()
    [seen] = run(camera, """
        fd = v4l2.open_device('/dev/video40')
        ids = {c['name']: c['id'] for c in json.loads(sys.stdin.readline())}
        listed = v4l2.list_controls(fd)
        exposure, auto = ids['exposure_time_absolute'], ids['auto_exposure']
        out = {'listed': listed,
               'menu': [error_of(v4l2.query_menu, fd, auto, i) or v4l2.query_menu(fd, auto, i)
                        for i in range(5)],
               'ext': v4l2.query_ext_control(fd, exposure)}
        out['inactive_set'] = error_of(v4l2.set_control, fd, exposure, 100)
        out['read_only_set'] = error_of(v4l2.set_control, fd, ids['privacy'], 1)
        out['unknown'] = error_of(v4l2.get_control, fd, 0x00980999)
        out['class_get'] = error_of(v4l2.get_control, fd, 0x00980001)
        out['bad_menu'] = error_of(v4l2.set_control, fd, auto, 2)
        out['clamped'] = v4l2.set_control(fd, ids['brightness'], 300)
        out['stepped'] = v4l2.set_control(fd, ids['pan_absolute'], 5000)
        out['both'] = v4l2.set_ext_controls(fd, [(auto, 1), (exposure, 500)])
        out['active'] = v4l2.query_control(fd, exposure)['flags']
        out['manual_set'] = v4l2.set_control(fd, exposure, 400)
        out['ext_get'] = v4l2.get_ext_controls(fd, [exposure, auto])
        os.close(fd)
        say(**out)
    """.replace('sys.stdin.readline()', repr(json.dumps(camera.model['controls']))))
    listed = {c['id']: c for c in seen['listed']}
    # Every control of the data file, with the kernel's name and its range, plus the classes.
    for control in camera.model['controls']:
        got = listed.pop(control['id'])
        assert (got['name'], got['min'], got['max'], got['step'], got['default']) == (
            control['label'], control['min'], control['max'], control['step'],
            control['default'])
        assert got['type'] == {'integer': 1, 'boolean': 2, 'menu': 3}[control['type']]
    assert sorted(c['name'] for c in listed.values()) == ['Camera Controls', 'User Controls']
    assert all(c['type'] == v4l2.CTRL_TYPE_CTRL_CLASS for c in listed.values())
    names = [c['name'] for c in seen['listed']]
    assert names.index('User Controls') < names.index('Brightness') < names.index(
        'Camera Controls') < names.index('Auto Exposure')
    by_label = {c['name']: c for c in seen['listed']}
    # While auto exposure is on (aperture priority) the exposure time is inactive and refused.
    assert by_label['Exposure Time, Absolute']['flags'] & v4l2.CTRL_FLAG_INACTIVE
    assert by_label['White Balance Temperature']['flags'] & v4l2.CTRL_FLAG_INACTIVE
    assert by_label['Privacy']['flags'] & v4l2.CTRL_FLAG_READ_ONLY
    assert seen['menu'] == ['EINVAL', 'Manual Mode', 'EINVAL', 'Aperture Priority Mode',
                            'EINVAL']
    assert seen['ext']['min'] == 3 and seen['ext']['max'] == 2047 and seen['ext']['elems'] == 1
    assert seen['inactive_set'] == 'EACCES'
    assert seen['read_only_set'] == 'EACCES'
    assert seen['unknown'] == 'EINVAL' and seen['bad_menu'] == 'EINVAL'
    assert seen['class_get'] == 'EACCES'
    assert seen['clamped'] == 255, 'clamped to the maximum'
    assert seen['stepped'] == 3600, 'rounded to a step of 3600 from -36000'
    assert seen['both'] == [1, 500], 'manual mode and exposure set in one S_EXT_CTRLS'
    assert not seen['active'] & v4l2.CTRL_FLAG_INACTIVE
    assert seen['manual_set'] == 400 and seen['ext_get'] == [400, 1]
    # The device keeps the values: this process sees them, and so does a new open.
    assert (camera.control('brightness'), camera.control('Exposure Time, Absolute'),
            camera.control(0x009a0901)) == (255, 400, 1)
    [again] = run(camera, """
        fd = v4l2.open_device('/dev/video40')
        say(value=v4l2.get_control(fd, 0x00980900))
    """)
    assert again['value'] == 255


def test_every_control_type_answers_as_the_kernels_controls_framework(emulated_camera):
    camera = emulated_camera('every_control')
    ids = {c['name']: c['id'] for c in camera.model['controls']}
    [seen] = run(camera, """
        fd = v4l2.open_device('/dev/video40')
        ids = %r
        simple = v4l2.list_ext_controls(fd)
        compound = v4l2.list_ext_controls(fd, v4l2.CTRL_FLAG_NEXT_COMPOUND)
        both = v4l2.list_ext_controls(fd, v4l2.CTRL_FLAG_NEXT_CTRL | v4l2.CTRL_FLAG_NEXT_COMPOUND)
        wide, button, bits = ids['integer_64_bits'], ids['button'], ids['bitmask']
        out = {'simple': [c['name'] for c in simple], 'compound': [c['name'] for c in compound],
               'both': {c['name']: c for c in both},
               'old_wide': v4l2.query_control(fd, wide),
               'wide_g_ctrl': error_of(v4l2.get_control, fd, wide),
               'wide_default': v4l2.get_ext_controls(fd, [wide], wide=True),
               'wide_set': v4l2.set_ext_controls(fd, [(wide, -(1 << 62) - 3)], wide=True),
               'wide_get': v4l2.get_ext_controls(fd, [wide], wide=True),
               'int_menu': [error_of(v4l2.query_int_menu, fd, ids['integer_menu'], i) or
                            v4l2.query_int_menu(fd, ids['integer_menu'], i) for i in range(9)],
               'button_get': error_of(v4l2.get_control, fd, button),
               'string_get': error_of(v4l2.get_control, fd, ids['string'])}
        v4l2.set_control(fd, button, 0)
        v4l2.set_ext_controls(fd, [(button, 1)])
        out['bits'] = v4l2.set_control(fd, bits, 0x7fffffff) & 0xffffffff
        os.close(fd)
        say(**out)
    """ % ids)
    # V4L2_CTRL_FLAG_NEXT_CTRL walks the controls with one value; NEXT_COMPOUND the arrays and
    # compound types; both together, everything.
    assert 'U32 1 Element Array' not in seen['simple'] and 'Area' not in seen['simple']
    assert seen['compound'] == ['U32 1 Element Array', 'Area']
    assert set(seen['both']) == set(seen['simple']) | set(seen['compound'])
    both = seen['both']
    assert both['Integer 64 Bits']['type'] == v4l2.CTRL_TYPE_INTEGER64
    wide = both['Integer 64 Bits']
    assert (wide['min'], wide['max']) == (-2 ** 63, 2 ** 63 - 1)
    assert (both['U32 1 Element Array']['dims'], both['U32 1 Element Array']['elems']) == (1, 1)
    assert both['Area']['type'] == v4l2.CTRL_TYPE_AREA
    for name in ('String', 'Area', 'U32 1 Element Array'):
        assert both[name]['flags'] & v4l2.CTRL_FLAG_HAS_PAYLOAD, name
    assert both['Button']['flags'] & v4l2.CTRL_FLAG_WRITE_ONLY
    assert both['Button']['flags'] & v4l2.CTRL_FLAG_EXECUTE_ON_WRITE
    assert both['Gain']['flags'] & v4l2.CTRL_FLAG_INACTIVE   # gain_automatic is on
    # The old VIDIOC_QUERYCTRL has no room for a 64-bit range; G_CTRL no room for the value.
    assert (seen['old_wide']['min'], seen['old_wide']['max']) == (0, 0)
    assert seen['wide_g_ctrl'] == 'EINVAL' and seen['string_get'] == 'EINVAL'
    assert seen['wide_default'] == [0]
    assert seen['wide_set'] == seen['wide_get'] == [-(1 << 62) - 3]
    assert camera.control('integer_64_bits') == -(1 << 62) - 3
    assert seen['int_menu'] == ['EINVAL', 'EINVAL', 2, 3, 5, 8, 13, 21, 42]
    # A button cannot be read; each write presses it, through S_CTRL or S_EXT_CTRLS.
    assert seen['button_get'] == 'EACCES'
    assert camera.control('button') == 2
    # A bitmask keeps the bits of its mask.
    assert seen['bits'] == 0x80402010 & 0x7fffffff
    assert camera.control('bitmask') == 0x80402010 & 0x7fffffff


def test_buffers_carry_monotonic_timestamps_and_sequence_numbers(emulated_camera):
    camera = emulated_camera(model='vga_yuyv', node=41)
    [seen] = run(camera, """
        fd = v4l2.open_device('/dev/video41')
        stream = v4l2.Stream(fd, 'YUYV', 320, 240, interval=(1, 15))
        infos = []
        for _ in range(4):
            info, data = stream.read()
            frame = np.frombuffer(data, np.uint8).reshape(240, 320, 2)
            info['index'] = read_frame_index(frame)
            info['now'] = time.monotonic()
            infos.append(info)
        say(infos=infos, fmt=stream.format)
    """)
    infos = seen['infos']
    assert seen['fmt'] == ['YUYV', 320, 240, 640, 320 * 240 * 2]
    assert all(i['flags'] & v4l2.BUF_FLAG_TIMESTAMP_MONOTONIC for i in infos)
    assert all(i['bytesused'] == 320 * 240 * 2 for i in infos)
    assert all(0 <= i['now'] - i['timestamp'] < 10 for i in infos), 'not CLOCK_MONOTONIC'
    for a, b in zip(infos, infos[1:]):
        assert b['sequence'] > a['sequence'] and b['index'] > a['index']
        # Frames are stamped at their capture time: whole multiples of the 1/15 s interval.
        steps = (b['timestamp'] - a['timestamp']) * 15
        assert abs(steps - round(steps)) < 0.02 and round(steps) >= 1


def test_unplug_fails_reads_at_once_and_replug_moves_the_by_id_link(emulated_camera):
    camera = emulated_camera()
    child = Child(camera, """
        import select
        cap = cv2.VideoCapture(%r, cv2.CAP_V4L2)
        fd = v4l2.open_device('/dev/video40')
        say(opened=cap.isOpened(), read=cap.read()[0])
        hear()
        start = time.monotonic()
        ok = cap.read()[0]
        poller = select.poll()
        poller.register(fd, select.POLLIN)
        say(read=ok, seconds=time.monotonic() - start, ioctl=error_of(v4l2.querycap, fd),
            poll=poller.poll(1000), open=error_of(os.open, '/dev/video40', os.O_RDWR),
            exists=os.path.exists(%r))
        hear()
        cap = cv2.VideoCapture(%r, cv2.CAP_V4L2)
        say(real=os.path.realpath(%r), opened=cap.isOpened(), read=cap.read()[0],
            old=os.path.exists('/dev/video40'), old_fd=error_of(v4l2.querycap, fd))
    """ % ((camera.by_id,) * 4))
    try:
        assert child.expect() == {'opened': True, 'read': True}
        camera.unplug()
        child.tell()
        gone = child.expect()
        assert gone['read'] is False and gone['seconds'] < 5.0, gone
        assert gone['ioctl'] == 'ENODEV' and gone['open'] == 'ENOENT' and not gone['exists']
        assert gone['poll'] and gone['poll'][0][1] & 0x8, 'POLLERR after the unplug'
        camera.replug(node=43)
        assert camera.device == '/dev/video43'
        child.tell()
        back = child.expect()
        assert back == {'real': '/dev/video43', 'opened': True, 'read': True, 'old': False,
                        'old_fd': 'ENODEV'}
    finally:
        child.close()


def test_a_stall_leaves_poll_waiting_without_an_error_until_resume(emulated_camera):
    camera = emulated_camera(model='vga_yuyv')
    child = Child(camera, """
        fd = v4l2.open_device('/dev/video40')
        stream = v4l2.Stream(fd)
        stream.read()
        say(ok=True)
        hear()
        while True:  # drain what was captured before the stall
            try:
                stream.read(timeout=0.2)
            except TimeoutError:
                break
        say(poll=stream.wait(0.5), dq=error_of(stream._buffer, v4l2.VIDIOC_DQBUF))
        hear()
        info, _ = stream.read(timeout=10)
        say(sequence=info['sequence'])
    """)
    try:
        assert child.expect() == {'ok': True}
        camera.stall()
        child.tell()
        assert child.expect() == {'poll': 0, 'dq': 'EAGAIN'}, 'a stall times out, with no error'
        served = camera.frames_served
        camera.resume()
        child.tell()
        assert child.expect()['sequence'] > 0
        assert camera.frames_served > served
    finally:
        child.close()


def test_busy_and_denied_cameras_refuse_as_uvcvideo_does(emulated_camera):
    camera = emulated_camera()
    code = """
        cap = cv2.VideoCapture('/dev/video40', cv2.CAP_V4L2)
        opened = cap.isOpened()
        cap.release()
        fd = error_of(os.open, '/dev/video40', os.O_RDWR) or v4l2.open_device('/dev/video40')
        if isinstance(fd, int):
            say(opencv=opened, open=None, querycap=error_of(v4l2.querycap, fd),
                s_fmt=error_of(v4l2.set_format, fd, 'YUYV', 640, 480))
        else:
            say(opencv=opened, open=fd)
    """
    with camera.busy():
        [busy] = run(camera, code)
    assert busy == {'opencv': False, 'open': None, 'querycap': None, 's_fmt': 'EBUSY'}
    camera.deny()
    [denied] = run(camera, code)
    assert denied == {'opencv': False, 'open': 'EACCES'}
    camera.deny(False)
    [free] = run(camera, code)
    assert free == {'opencv': True, 'open': None, 'querycap': None, 's_fmt': None}


def test_the_corrupt_camera_sends_a_broken_jpeg_every_nth_frame(emulated_camera):
    camera = emulated_camera(model='corrupt_mjpeg')
    every = camera.model['corrupt_jpeg']['every']
    [seen] = run(camera, """
        fd = v4l2.open_device('/dev/video40')
        stream = v4l2.Stream(fd, 'MJPG', 640, 480)
        frames = []
        for _ in range(16):
            info, data = stream.read()
            image = cv2.imdecode(np.frombuffer(data, np.uint8), cv2.IMREAD_COLOR)
            frames.append({'sequence': info['sequence'], 'eoi': data[-2:] == b'\\xff\\xd9',
                           'decoded': image is not None and read_frame_index(image),
                           'digest': jpeg_digest(data)})
        say(frames=frames)
    """)
    # A fresh camera's frame index is its stream's sequence number: every `every`-th is broken
    # (no EOI), the others decode to their index.
    frames = seen['frames']
    for frame in frames:
        broken = frame['sequence'] % every == every - 1
        assert frame['eoi'] != broken, frames
        if not broken:
            assert frame['decoded'] == frame['sequence'], frames
    assert sum(not f['eoi'] for f in frames) >= 2, frames
    # The camera recorded each one, the broken ones marked, with the bytes the reader got.
    served = {jpeg.index: jpeg for jpeg in camera.served_jpegs()}
    for frame in frames:
        jpeg = served[frame['sequence']]
        assert (jpeg.length, jpeg.digest) == tuple(frame['digest']), (jpeg, frame)
        assert jpeg.corrupt == (not frame['eoi']), (jpeg, frame)


def test_controls_change_on_one_thread_while_opencv_reads_on_another(emulated_camera):
    camera = emulated_camera()
    [seen] = run(camera, """
        import threading
        cap = cv2.VideoCapture('/dev/video40', cv2.CAP_V4L2)
        fd = v4l2.open_device('/dev/video40')
        done, values = threading.Event(), []
        def poke():
            i = 0
            while not done.is_set():
                values.append(v4l2.set_control(fd, 0x00980900, i % 256))
                v4l2.get_control(fd, 0x00980900)
                i += 1
        thread = threading.Thread(target=poke)
        thread.start()
        indexes = [read_frame_index(cap.read()[1]) for _ in range(10)]
        done.set()
        thread.join()
        say(indexes=indexes, sets=len(values))
    """)
    assert all(b > a for a, b in zip(seen['indexes'], seen['indexes'][1:]))
    assert seen['sets'] > 10


def test_two_cameras_in_one_process_and_a_format_the_camera_lacks(emulated_camera):
    webcam = emulated_camera()
    # Two raw VGA streams at 30 fps do not fit one USB 2.0 bus (test_usb_bus): the second
    # camera is on another host controller.
    vga = emulated_camera(model='vga_yuyv', node=41, usb_controller='0000:00:1d.0')
    [seen] = run([webcam, vga], """
        caps = [cv2.VideoCapture(n, cv2.CAP_V4L2) for n in (40, 41)]
        vga = caps[1]
        vga.set(cv2.CAP_PROP_FOURCC, cv2.VideoWriter_fourcc(*'MJPG'))
        vga.set(cv2.CAP_PROP_FRAME_WIDTH, 1920)
        vga.set(cv2.CAP_PROP_FRAME_HEIGHT, 1080)
        frames = [cap.read()[1] for cap in caps]
        cards = [v4l2.querycap(v4l2.open_device(p))[1] for p in ('/dev/video40', '/dev/video41')]
        say(shapes=[list(f.shape) for f in frames], cards=cards,
            fourcc=v4l2.fourcc_text(int(vga.get(cv2.CAP_PROP_FOURCC))),
            indexes=[read_frame_index(f) for f in frames])
    """)
    assert seen['cards'] == ['Emu Webcam 1080p', 'Emu VGA Camera']
    # The VGA camera has no MJPEG and nothing above 640x480: it stays YUYV at its largest size.
    assert seen['shapes'] == [[480, 640, 3], [480, 640, 3]] and seen['fourcc'] == 'YUYV'
    assert None not in seen['indexes']


def test_controls_change_the_picture_live_and_the_defaults_restore_it(emulated_camera):
    camera = emulated_camera()
    [seen] = run(camera, """
        cap = cv2.VideoCapture('/dev/video40', cv2.CAP_V4L2)
        fd = v4l2.open_device('/dev/video40')

        def settled():  # the buffers already filled hold the old picture
            return [cap.read()[1] for _ in range(6)][-1]

        def colour(image):  # how far from grey the picture is
            return float(image.astype(float).std(axis=2).mean())

        out = {'start': float(settled().mean())}
        v4l2.set_control(fd, 0x00980900, 255)           # brightness up
        out['bright'] = float(settled().mean())
        v4l2.set_control(fd, 0x00980900, 128)
        v4l2.set_ext_controls(fd, [(0x009a0901, 1), (0x009a0902, 125)])  # half the exposure
        out['dark'] = float(settled().mean())
        v4l2.set_control(fd, 0x009a0901, 3)             # auto again: exposure ignored
        frame = settled()
        index = read_frame_index(frame)
        out['back'] = int(np.abs(frame.astype(int) - cv2.cvtColor(
            expected_yuyv(index, 640, 480), cv2.COLOR_YUV2BGR_YUYV).astype(int)).max())
        cap.set(cv2.CAP_PROP_FOURCC, cv2.VideoWriter_fourcc(*'MJPG'))
        out['colour'] = colour(settled())
        v4l2.set_control(fd, 0x00980902, 0)             # saturation 0: grey
        grey = settled()
        out['grey'], out['grey_index'] = colour(grey), read_frame_index(grey)
        say(**out)
    """)
    assert seen['bright'] > seen['start'] + 20 and seen['dark'] < seen['start'] - 20, seen
    assert seen['back'] == 0, 'controls back at their defaults give the picture again'
    assert seen['grey'] < seen['colour'] / 5 and seen['grey_index'] is not None, seen


def test_fork_and_exec_leave_the_parent_streaming(emulated_camera):
    camera = emulated_camera(model='vga_yuyv')
    [seen] = run(camera, """
        cap = cv2.VideoCapture('/dev/video40', cv2.CAP_V4L2)
        fd = v4l2.open_device('/dev/video40')
        before = read_frame_index(cap.read()[1])
        pid = os.fork()
        if pid == 0:  # the child closes its copies (explicitly, and by exiting)
            os.close(fd)
            os._exit(0)
        _, status = os.waitpid(pid, 0)
        import subprocess
        subprocess.run([sys.executable, '-c', 'pass'], check=True)  # fork and exec
        after = [read_frame_index(cap.read()[1]) for _ in range(3)]
        say(status=status, before=before, after=after, caps=v4l2.querycap(fd)[0])
    """)
    assert seen['status'] == 0 and seen['caps'] == 'uvcvideo'
    assert None not in seen['after'] and seen['after'][0] > seen['before']


def test_two_test_runs_building_the_library_at_once_both_get_it(tmp_path):
    build = ('import emulated_camera, ctypes; path = emulated_camera.build_library(); '
             'ctypes.CDLL(str(path)); print(path)')
    env = dict(os.environ, PY_VISION_UVC_CACHE=str(tmp_path),
               PYTHONPATH=os.pathsep.join([str(HERE), os.environ.get('PYTHONPATH', '')]))
    builds = [subprocess.Popen([sys.executable, '-c', build], env=env, stdout=subprocess.PIPE,
                               stderr=subprocess.PIPE, text=True) for _ in range(2)]
    results = [b.communicate(timeout=120) for b in builds]
    assert [b.returncode for b in builds] == [0, 0], [err for _, err in results]
    paths = {out.strip() for out, _ in results}
    assert len(paths) == 1, paths
    assert [p.name for p in tmp_path.iterdir()] == [os.path.basename(paths.pop())]
