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
Emulated UVC cameras for the tests: a device path that answers the V4L2 API as uvcvideo does.

`EmulatedCamera` describes one camera (a data file in uvc_emulator/cameras/) to the C library
uvc_emulator/uvc_emulator.c, which a process loads with LD_PRELOAD (`env()` gives the
variables): in that process /dev/videoN, /dev/v4l/by-id/... and /dev/v4l/by-path/... are the
camera, for OpenCV's V4L2 backend and for any ioctl. The camera's state lives in a small file
in its directory, shared by every process using it and by this object, which changes it to
inject faults (unplug, replug under another node, stall, permission denied) and reads it back
(control values, frames served). `busy()` streams from it in another process.

Frames are the synthetic camera's picture (py_vision.capture.synthetic_picture) without the
moving box and digits: its background for the size, and the 4 x 11 frame-index code that
`read_frame_index` decodes, drawn by the library for each frame's index. Each MJPEG frame a
DQBUF hands out is recorded (index, length, CRC-32) in a ring next to the state, so a test can
check that bytes it received are exactly the JPEG the camera served (`served_jpeg_digest`,
`jpeg_digest`). How it works and the data-file format: docs/emulated_cameras.md.
"""

import contextlib
from dataclasses import dataclass
import hashlib
import mmap
import os
from pathlib import Path
import shutil
import struct
import subprocess
import sys
import tempfile
import zlib

import cv2
import numpy as np

HERE = Path(__file__).resolve().parent
SOURCE = HERE / 'uvc_emulator' / 'uvc_emulator.c'
CAMERAS = HERE / 'uvc_emulator' / 'cameras'
CLIPS = HERE / 'uvc_emulator' / 'clips'
CFLAGS = ['-O2', '-shared', '-fPIC', '-Wall']
LIBS = ['-lpthread', '-ldl', '-lm']
ENV_CAMERAS = 'PY_VISION_UVC_CAMERAS'
JPEG_QUALITY = 80

# The shared state file (struct shared_state in uvc_emulator.c).
_MAGIC = 0x45435655
_STATE_SIZE = 4096
# The USB bus the cameras of one state directory share (struct bus_state in uvc_emulator.c):
# a lock word, then 16 slots of (camera key, owner, bytes per microframe).
_BUS_FILE, _BUS_SLOT = 'usb_bus', struct.Struct('=QQII')
_BUS_SLOTS_AT, _BUS_SLOTS = 8, 16
# A UVC endpoint's alternate settings (bytes per 125 us microframe: 1 to 3 x 1024 at most) and
# what a camera asks for a compressed stream, unless its data file says otherwise.
_USB_ALTS = (128, 256, 512, 1024, 2048, 3072)
_USB_COMPRESSED_PAYLOAD = 1024
_OFF_NODE, _OFF_PLUGGED, _OFF_GENERATION, _OFF_STALLED, _OFF_DENIED = 4, 8, 12, 16, 20
_OFF_OWNER, _OFF_FORMAT, _OFF_FRAME, _OFF_INTERVAL = 24, 32, 36, 40
_OFF_SENSOR, _OFF_SERVED, _OFF_VALUES, _OFF_RENDER_NS, _OFF_WIDE = 48, 56, 64, 320, 328
_MAX_CONTROLS = 48
# The served ring (struct served_record in uvc_emulator.c): tag (index + 1), length, flags,
# CRC-32, reserved; frame `index` at slot index % _SERVED_SLOTS.
_SERVED = struct.Struct('<QIIII')
_SERVED_SLOTS = 4096
_SERVED_CORRUPT = 1
# Control types (enum v4l2_ctrl_type: camera_model.CONTROL_TYPES) and the size of one element.
_TYPES = {'integer': 1, 'boolean': 2, 'menu': 3, 'button': 4, 'integer64': 5, 'string': 7,
          'bitmask': 8, 'integer_menu': 9, 'u8': 0x100, 'u16': 0x101, 'u32': 0x102,
          'area': 0x106}
_ELEM_SIZES = {'integer64': 8, 'u8': 1, 'u16': 2, 'area': 8}
_FLAG_READ_ONLY = 0x4
_FAULTS = ('stalled', 'denied')
# no_userptr's values, as the data file gives them (uvc_emulator.c: 1 REQBUFS refuses, 2 QBUF).
_NO_USERPTR = {None: 0, False: 0, True: 1, 'reqbufs': 1, 'qbuf': 2}


def jpeg_digest(data):
    """Return (length, CRC-32) of a JPEG's bytes, as the camera records what it served."""
    return len(data), zlib.crc32(data) & 0xFFFFFFFF


@dataclass(frozen=True)
class ServedJpeg:
    """One JPEG the camera handed to a DQBUF: its frame index, length, CRC-32, brokenness."""

    index: int
    length: int
    digest: int
    corrupt: bool


class CompilerMissing(RuntimeError):
    """No C compiler: the emulated cameras cannot be built."""


def cache_dir():
    """Return the directory (outside git) where the library and pictures are kept."""
    root = os.environ.get('PY_VISION_UVC_CACHE') or os.path.join(
        tempfile.gettempdir(), 'py_vision-uvc-emulator-%d' % os.getuid())
    os.makedirs(root, exist_ok=True)
    return Path(root)


def _atomic_write(path, data):
    """Write a file under a temporary name and rename it: concurrent writers are safe."""
    fd, tmp = tempfile.mkstemp(dir=str(path.parent), prefix='.' + path.name + '.')
    try:
        with os.fdopen(fd, 'wb') as out:
            out.write(data)
        os.replace(tmp, path)
    except BaseException:
        with contextlib.suppress(OSError):
            os.unlink(tmp)
        raise


def compiler():
    """Return the system C compiler's command, or None."""
    for name in (os.environ.get('CC'), 'cc', 'gcc', 'clang'):
        if name and shutil.which(name):
            return name
    return None


def build_library():
    """
    Compile uvc_emulator.c once per source change and return the shared library's path.

    The library is named by a hash of the source and the flags, compiled under a temporary
    name and renamed, so two test runs building at once both end with a complete file.
    """
    source = SOURCE.read_bytes()
    digest = hashlib.sha256(source + ' '.join(CFLAGS + LIBS).encode()).hexdigest()[:16]
    library = cache_dir() / ('uvc_emulator-%s.so' % digest)
    if library.exists():
        return library
    cc = compiler()
    if cc is None:
        raise CompilerMissing(
            'no C compiler (cc) to build the emulated UVC camera: install one (Debian: '
            'apt-get install gcc; scripts/test.sh does this as root)')
    tmp = library.with_name('.%s.%d.so' % (library.stem, os.getpid()))
    result = subprocess.run([cc, *CFLAGS, '-o', str(tmp), str(SOURCE), *LIBS],
                            capture_output=True, text=True)
    if result.returncode != 0:
        with contextlib.suppress(OSError):
            tmp.unlink()
        raise RuntimeError('compiling %s failed:\n%s' % (SOURCE, result.stderr))
    os.replace(tmp, library)
    return library


def _synthetic():
    from py_vision.capture import synthetic_picture
    return synthetic_picture


def _picture_key():
    module = _synthetic()
    return hashlib.sha256(Path(module.__file__).read_bytes()).hexdigest()[:12]


def background(width, height):
    """Return the YUYV picture of this size every frame starts from ((h, w, 2) uint8)."""
    sc = _synthetic()
    path = cache_dir() / ('background-%dx%d-%s.yuyv' % (width, height, _picture_key()))
    if path.exists() and path.stat().st_size == width * height * 2:
        return np.fromfile(str(path), np.uint8).reshape(height, width, 2)
    picture = sc.frame_layout(width, height).background.copy()
    _atomic_write(path, picture.tobytes())
    return picture


def code_geometry(width, height):
    """Return (x, y, cell) of the frame-index code at this size, or (0, 0, 0) if none."""
    code = _synthetic()._geometry(width, height).code
    return code if code is not None else (0, 0, 0)


def _with_cells(width, height, bits):
    """Return the YUYV picture of this size with the code's cells white where bits say 1."""
    sc = _synthetic()
    frame = background(width, height).copy()
    x, y, cell = code_geometry(width, height)
    if cell:
        for (row, col), bit in bits.items():
            frame[y + row * cell:y + (row + 1) * cell, x + col * cell:x + (col + 1) * cell,
                  0] = sc._WHITE if bit else sc._BLACK
    return frame


def expected_yuyv(index, width, height):
    """Return the YUYV frame an emulated camera sends as frame `index` at this size."""
    sc = _synthetic()
    bits = dict(sc._SYNC)
    bits.update(zip(sc._DATA_CELLS, sc._code_bits(index)))
    return _with_cells(width, height, bits)


def _pixel_format(fourcc):
    from py_vision.capture.pixel_formats import find
    return find(fourcc)


def _as_sent(pixel_format, yuyv):
    return np.ascontiguousarray(pixel_format.from_yuyv(yuyv)).reshape(-1).view(np.uint8)


def expected_frame(fourcc, index, width, height):
    """Return the bytes an emulated camera sends as frame `index` in a raw format (1-D)."""
    return _as_sent(_pixel_format(fourcc), expected_yuyv(index, width, height))


def raw_pictures(fourcc, width, height):
    """
    Return the paths of a raw format's two pictures of this size: every code cell black, white.

    Made from the YUYV picture the way the pixel format table says (`from_yuyv`); the library
    copies each cell's bytes from one or the other, plane by plane.
    """
    from py_vision.capture import pixel_formats
    key = hashlib.sha256(Path(pixel_formats.__file__).read_bytes()).hexdigest()[:12]
    paths = []
    sc = _synthetic()
    cells = [(row, col) for row in range(sc._CODE_ROWS) for col in range(sc._CODE_COLS)]
    for level in (0, 1):
        path = cache_dir() / ('%s-%dx%d-%d-%s-%s.raw' % (
            fourcc.strip(), width, height, level, _picture_key(), key))
        if not path.exists():
            yuyv = _with_cells(width, height, dict.fromkeys(cells, level))
            _atomic_write(path, _as_sent(_pixel_format(fourcc), yuyv).tobytes())
        paths.append(path)
    return paths


def jpeg_tables():
    """Return the path of the DQT and DHT segments (libjpeg's, through OpenCV) JPEGs use."""
    path = cache_dir() / ('jpeg-tables-q%d.bin' % JPEG_QUALITY)
    if path.exists():
        return path
    ok, data = cv2.imencode('.jpg', np.zeros((16, 16, 3), np.uint8),
                            [cv2.IMWRITE_JPEG_QUALITY, JPEG_QUALITY])
    data = data.tobytes()
    segments, pos = b'', 2
    while pos + 4 <= len(data) and data[pos] == 0xFF and data[pos + 1] != 0xDA:
        length = struct.unpack_from('>H', data, pos + 2)[0]
        if data[pos + 1] in (0xDB, 0xC4):
            segments += data[pos:pos + 2 + length]
        pos += 2 + length
    _atomic_write(path, segments)
    return path


def model_path(model):
    """Return the data file a model names: a path, the synthetic camera's, or one in CAMERAS."""
    if str(model).endswith('.yaml'):
        return Path(model)
    if model == 'synthetic':
        from py_vision.capture import camera_model
        return camera_model.SYNTHETIC
    return CAMERAS / ('%s.yaml' % model)


def load_model(model):
    """
    Return a camera's data file as a dict, with what it implies worked out.

    The file is read as the synthetic camera reads its own (py_vision.capture.camera_model).
    Each format gets its `description` (the pixel format table's unless the file gives one),
    `compressed` and `frames`: [{'width', 'height', 'rates', 'intervals'}], the rates offered
    at that size (camera_model.bus_rates: raw formats those whose frames fit in
    `usb_bandwidth`), as V4L2 intervals (1, rate); each control gets its `index` in the shared
    state and the defaults of what the file leaves out.
    """
    from py_vision.capture import camera_model
    path = model_path(model)
    described = camera_model.load(path)
    data = described.data
    data['model'] = described.name
    data['default_size'] = list(described.default_size)
    for fmt, offered in zip(data['formats'], described.formats):
        fmt['description'] = offered.description
        fmt['compressed'] = offered.pixel_format.compressed
        if offered.pixel_format.video:
            if 'clip' not in fmt:
                raise ValueError('%s: %s needs a clip (a file in %s)' % (path, fmt['fourcc'],
                                                                         CLIPS))
            fmt['clip'] = str(CLIPS / fmt['clip'])
        fmt['frames'] = [{'width': size.width, 'height': size.height, 'rates': list(size.rates),
                          'intervals': [(1, rate) for rate in size.rates]}
                         for size in described.frame_sizes(offered)]
    data['controls'] = data.get('controls') or []
    if len(data['controls']) > _MAX_CONTROLS:
        raise ValueError('%s: at most %d controls' % (path, _MAX_CONTROLS))
    for index, control in enumerate(data['controls']):
        control['index'] = index
        for key in ('min', 'max', 'step', 'default'):
            control.setdefault(key, 0)   # a button, an area: no range
    return data


class EmulatedCamera:
    """
    One emulated UVC camera: its device paths, its data file, its faults and its state.

    `state_dir` holds its directory (a test's temporary directory); `model` names a data file
    in uvc_emulator/cameras (or is a path to one); `node` is the N of /dev/videoN. Options:
    `serial` and `usb_port` (the by-id and by-path names; the data file's by default),
    `stalled` and `denied` (start with that fault), `corrupt_every` (overrides the data
    file's broken-JPEG period; 0: never), `drop_every` (every N-th frame lost on the way: the
    buffers' sequence skips it), `error_every` (every N-th buffer comes back flagged
    V4L2_BUF_FLAG_ERROR, empty), `streamon_errno` (VIDIOC_STREAMON fails with that errno),
    `no_userptr` (True or 'reqbufs': VIDIOC_REQBUFS refuses V4L2_MEMORY_USERPTR, as a driver
    without it does; 'qbuf': VIDIOC_QBUF refuses the memory, EFAULT) and
    `usb_controller` (the PCI address of its USB host controller, 0000:00:14.0 by default:
    the cameras of one state directory on one controller share its bus's bandwidth).
    `close()` unplugs it and removes its directory (the
    `emulated_camera` fixture does this after the test).
    """

    def __init__(self, state_dir, model='webcam_1080p', node=40, **faults):
        unknown = set(faults) - set(_FAULTS) - {'serial', 'corrupt_every', 'usb_port',
                                                'drop_every', 'error_every', 'streamon_errno',
                                                'usb_controller', 'no_userptr'}
        if unknown:
            raise TypeError('unknown option(s) %s' % ', '.join(sorted(unknown)))
        if faults.get('no_userptr') not in _NO_USERPTR:
            raise TypeError("no_userptr is True, 'reqbufs' or 'qbuf', not %r"
                            % (faults['no_userptr'],))
        self.model = load_model(model)
        self.library = build_library()
        self.dir = Path(tempfile.mkdtemp(prefix='%s-' % self.model['model'], dir=str(state_dir)))
        m = self.model
        serial = faults.get('serial', m.get('serial', 'EMU0000'))
        port = faults.get('usb_port', m.get('usb_port', '1'))
        controller = faults.get('usb_controller', '0000:00:14.0')
        product = m['product']
        self.driver = m.get('driver', 'uvcvideo')
        self.bus_info = m.get('bus_info', 'usb-%s-%s' % (controller, port))
        # A device on no USB bus (a board's capture pipeline) gets no by-id link from udev.
        self.by_id = None if 'bus_info' in m else \
            '/dev/v4l/by-id/usb-%s_%s_%s-video-index0' % (
                m['vendor'].replace(' ', '_'), product.replace(' ', '_'), serial)
        self.by_path = m.get('by_path', '/dev/v4l/by-path/pci-%s-usb-0:%s:1.0-video-index0' % (
            controller, port))
        self.card = product
        corrupt = dict(m.get('corrupt_jpeg') or {})
        if 'corrupt_every' in faults:
            corrupt['every'] = faults['corrupt_every']
        # The cameras of one state directory on one controller share its USB bus (a device
        # on none takes no bandwidth).
        self.bus = Path(state_dir) / ('%s-%s' % (_BUS_FILE, controller)) \
            if self.bus_info.startswith('usb-') else None
        self.bus_key = int.from_bytes(os.urandom(8), 'little') | 1
        if self.bus is not None and not self.bus.exists():
            self.bus.write_bytes(bytes(_STATE_SIZE))
        self._write_config(serial, port, corrupt, faults)
        self._init_state(node, faults)

    # -- set-up

    def _write_config(self, serial, port, corrupt, faults):
        m = self.model
        lines = ['card %s' % self.card, 'driver %s' % self.driver,
                 'bus_info %s' % self.bus_info, 'by_id %s' % (self.by_id or ''),
                 'by_path %s' % self.by_path,
                 'jpeg_tables %s' % jpeg_tables(),
                 'corrupt_every %d' % int(corrupt.get('every', 0)),
                 'corrupt_mode %s' % corrupt.get('mode', 'truncate'),
                 'drop_every %d' % int(faults.get('drop_every', 0)),
                 'error_every %d' % int(faults.get('error_every', 0)),
                 'streamon_errno %d' % int(faults.get('streamon_errno', 0)),
                 'no_userptr %d' % _NO_USERPTR[faults.get('no_userptr')]]
        if self.bus is not None:
            lines += ['bus %d %d %s' % (self.bus_key, m.get('usb_compressed_payload',
                                                            _USB_COMPRESSED_PAYLOAD), self.bus),
                      'alts %s' % ' '.join(map(str, m.get('usb_alts', _USB_ALTS)))]
        for fmt in m['formats']:
            pixel_format = _pixel_format(fmt['fourcc'])
            flags = 1 if fmt['compressed'] else 0
            lines.append('format %s %d %s' % (pixel_format.fourcc, flags, fmt['description']))
            if pixel_format.video:
                # Its frames are the clip's access units (the buffers hold the largest).
                clip = Path(fmt['clip'])
                lines.append('clip %d %s' % (clip.stat().st_size, clip))
            # YUYV and JPEG are made from the YUYV picture with the controls' effects; any
            # other raw format from its two pictures, plane by plane.
            generic = not pixel_format.compressed and pixel_format.fourcc != 'YUYV'
            if generic:
                lines.append('planes %s' % ' '.join('%d %d %d' % (
                    plane.across, plane.per, plane.down) for plane in pixel_format.planes))
            for frame in fmt['frames']:
                width, height = frame['width'], frame['height']
                background(width, height)
                x, y, cell = code_geometry(width, height)
                picture = cache_dir() / ('background-%dx%d-%s.yuyv' % (
                    width, height, _picture_key()))
                size, stride = width * height * 2, pixel_format.bytesperline(width)
                if pixel_format.video:
                    size = Path(fmt['clip']).stat().st_size
                if generic:
                    size = pixel_format.frame_bytes(width, height)
                    picture, white = raw_pictures(pixel_format.fourcc, width, height)
                lines.append('frame %d %d %d %d %d %d %d %s' % (
                    width, height, size, stride, x, y, cell, picture))
                if generic:
                    lines.append('white %s' % white)
                lines += ['interval %d %d' % iv for iv in frame['intervals']]
        by_name = {c['name']: c for c in m['controls']}
        for c in m['controls']:
            master_id, manual = 0, 0
            for master, value in c.get('inactive_unless', {}).items():
                master_id, manual = by_name[master]['id'], value
            flags = _FLAG_READ_ONLY if c.get('read_only') else 0
            size = c['max'] + 1 if c['type'] == 'string' else _ELEM_SIZES.get(c['type'], 4)
            lines.append('control %#x %d %d %d %d %d %d %#x %d %d %s' % (
                c['id'], _TYPES[c['type']], c['min'], c['max'], c['step'], c['default'],
                flags, master_id, manual, size, c['label']))
            for index, name in sorted((c.get('menu') or {}).items()):
                lines.append('menu %#x %d %s' % (c['id'], index, name))
            if c.get('dims'):
                lines.append('dims %#x %s' % (c['id'], ' '.join(map(str, c['dims']))))
            if c.get('effect'):
                lines.append('effect %#x %s' % (c['id'], c['effect']))
        (self.dir / 'camera.conf').write_text('\n'.join(lines) + '\n')
        (self.dir / 'empty').mkdir()  # listed in place of /dev/v4l/by-id where udev made none

    def _init_state(self, node, faults):
        path = self.dir / 'state'
        path.write_bytes(bytes(_STATE_SIZE))
        self._file = open(path, 'r+b')
        self._state = mmap.mmap(self._file.fileno(), _STATE_SIZE)
        self._put('I', _OFF_STALLED, 1 if faults.get('stalled') else 0)
        self._put('I', _OFF_DENIED, 1 if faults.get('denied') else 0)
        self._reset(node)
        self._put('I', 0, _MAGIC)
        path = self.dir / 'served'
        path.write_bytes(bytes(_SERVED.size * _SERVED_SLOTS))
        self._served_file = open(path, 'rb')
        self._served = mmap.mmap(self._served_file.fileno(), 0, access=mmap.ACCESS_READ)

    def _put(self, kind, offset, value):
        struct.pack_into(kind, self._state, offset, value)

    def _get(self, kind, offset):
        return struct.unpack_from(kind, self._state, offset)[0]

    def _reset(self, node):
        """As a camera powering up: default format and size, default control values."""
        first = self.model['formats'][0]
        default = tuple(self.model.get('default_size') or first['sizes'][0])
        sizes = [tuple(s) for s in first['sizes']]
        self._put('i', _OFF_NODE, int(node))
        self._put('Q', _OFF_OWNER, 0)
        self._put('I', _OFF_FORMAT, 0)
        self._put('I', _OFF_FRAME, sizes.index(default) if default in sizes else 0)
        self._put('I', _OFF_INTERVAL, 0)
        for control in self.model['controls']:
            if control['type'] == 'integer64':
                self._put('q', _OFF_WIDE + 8 * control['index'], control['default'])
            elif control['type'] == 'button':
                self._put('i', _OFF_VALUES + 4 * control['index'], 0)   # presses
            else:
                # Held as the kernel's s32 (a bitmask's top bit makes it negative there).
                self._put('I', _OFF_VALUES + 4 * control['index'],
                          control['default'] & 0xFFFFFFFF)
        self._put('I', _OFF_PLUGGED, 1)

    # -- what a test uses

    @property
    def node(self):
        """Return the N of /dev/videoN the camera answers at."""
        return self._get('i', _OFF_NODE)

    @property
    def device(self):
        """Return the device path, e.g. /dev/video40."""
        return '/dev/video%d' % self.node

    @property
    def plugged(self):
        """Return whether the camera is plugged in."""
        return self._get('I', _OFF_PLUGGED) == 1

    @property
    def frames_served(self):
        """Return how many frames went into streaming buffers so far (all processes)."""
        return self._get('Q', _OFF_SERVED)

    @property
    def render_seconds(self):
        """Return the CPU time the library spent making frames so far (all processes)."""
        return self._get('Q', _OFF_RENDER_NS) / 1e9

    @property
    def next_index(self):
        """Return the frame index the sensor gives next (frames without a buffer are lost)."""
        return self._get('Q', _OFF_SENSOR)

    def _served_record(self, slot):
        """Return a whole record of the served ring (tag read before and after), or None."""
        offset = _SERVED.size * slot
        for _ in range(100):   # a torn read: the library was writing this very slot
            record = _SERVED.unpack_from(self._served, offset)
            if record[0] == struct.unpack_from('<Q', self._served, offset)[0]:
                return record if record[0] else None
        return None

    def served_jpeg_digest(self, index):
        """
        Return (length, CRC-32) of the JPEG the camera served as frame `index`, or None.

        None: no such frame went out of a DQBUF (lost, YUYV, not yet), or it is more than
        4096 frames old. Compare with `jpeg_digest(data)` of bytes a program got.
        """
        record = self._served_record(index % _SERVED_SLOTS)
        if record is None or record[0] != index + 1:
            return None
        return record[1], record[3]

    def served_jpegs(self):
        """
        Return the JPEGs served (the last 4096 at most) as `ServedJpeg`s, oldest first.

        A video format's frames (its clip's access units) are recorded the same way.
        """
        records = (self._served_record(slot) for slot in range(_SERVED_SLOTS))
        return sorted((ServedJpeg(tag - 1, length, crc, bool(flags & _SERVED_CORRUPT))
                       for tag, length, flags, crc, _ in filter(None, records)),
                      key=lambda jpeg: jpeg.index)

    def env(self, base_env=None):
        """Return a copy of base_env, os.environ by default, with LD_PRELOAD and this camera."""
        env = dict(os.environ if base_env is None else base_env)
        preload = [p for p in env.get('LD_PRELOAD', '').split(':') if p]
        if str(self.library) not in preload:
            preload.insert(0, str(self.library))
        env['LD_PRELOAD'] = ':'.join(preload)
        cameras = [p for p in env.get(ENV_CAMERAS, '').split(':') if p]
        if str(self.dir) not in cameras:
            cameras.append(str(self.dir))
        env[ENV_CAMERAS] = ':'.join(cameras)
        return env

    def unplug(self):
        """
        Unplug: open descriptors get ENODEV and POLLERR, the paths vanish (ENOENT).

        Its bandwidth on the USB bus is free again, as the host controller frees it.
        """
        self._put('I', _OFF_PLUGGED, 0)
        self._put('I', _OFF_GENERATION, self._get('I', _OFF_GENERATION) + 1)
        self._put('Q', _OFF_OWNER, 0)
        for slot in self.bus_reservations(own=True):
            with open(self.bus, 'r+b') as bus, mmap.mmap(bus.fileno(), _STATE_SIZE) as mapped:
                mapped[slot:slot + _BUS_SLOT.size] = bytes(_BUS_SLOT.size)

    def bus_reservations(self, own=False):
        """
        Return where the streams on this camera's bus hold bandwidth (offsets in its file).

        own: only this camera's. Reservations of processes that ended are left in the file
        (the library takes them as free); a camera on no USB bus has none.
        """
        if self.bus is None:
            return []
        data = self.bus.read_bytes()
        found = []
        for slot in range(_BUS_SLOTS):
            at = _BUS_SLOTS_AT + slot * _BUS_SLOT.size
            key = _BUS_SLOT.unpack_from(data, at)[0]
            if key and (key == self.bus_key or not own):
                found.append(at)
        return found

    def replug(self, node=None):
        """Plug in again, at /dev/video`node` if given; by-id and by-path follow."""
        if self.plugged:
            self.unplug()
        self._reset(self.node if node is None else node)

    def stall(self):
        """Stall: the camera goes on streaming but sends nothing, no buffer becomes ready."""
        self._put('I', _OFF_STALLED, 1)

    def resume(self):
        """End a stall: frames flow again."""
        self._put('I', _OFF_STALLED, 0)

    def deny(self, denied=True):
        """Make opening the device fail with EACCES (emulated: for any user, root too)."""
        self._put('I', _OFF_DENIED, 1 if denied else 0)

    @contextlib.contextmanager
    def busy(self, timeout=20.0):
        """Stream from the camera in another process meanwhile (others get EBUSY)."""
        holder = subprocess.Popen(
            [sys.executable, str(Path(__file__).resolve()), 'hold', self.device],
            env=self.env(), stdin=subprocess.PIPE, stdout=subprocess.PIPE,
            stderr=subprocess.PIPE, text=True)
        try:
            line = _read_line(holder.stdout, timeout)
            if line.strip() != 'streaming':
                holder.kill()
                raise RuntimeError('the process holding %s did not stream: %s %s' % (
                    self.device, line, holder.stderr.read()))
            yield holder
        finally:
            with contextlib.suppress(OSError):
                holder.stdin.close()
            try:
                holder.wait(timeout)
            except subprocess.TimeoutExpired:
                holder.kill()
                holder.wait()
            holder.stdout.close()
            holder.stderr.close()

    def control_info(self, name_or_id):
        """Return a control's entry of the data file, by name, label or V4L2 id."""
        for control in self.model['controls']:
            if name_or_id in (control['name'], control['label'], control['id']):
                return control
        raise KeyError('%s has no control %r' % (self.model['model'], name_or_id))

    def control(self, name_or_id):
        """
        Return the device's current value of this control, as every process sees it.

        A button's value is how often it was pressed since the camera was plugged in; a
        bitmask's is unsigned.
        """
        info = self.control_info(name_or_id)
        if info['type'] == 'integer64':
            return self._get('q', _OFF_WIDE + 8 * info['index'])
        value = self._get('i', _OFF_VALUES + 4 * info['index'])
        return value & 0xFFFFFFFF if info['type'] == 'bitmask' else value

    def close(self):
        """Unplug the camera and remove its directory."""
        if self._state is not None:
            self.unplug()
            self._state.close()
            self._file.close()
            self._served.close()
            self._served_file.close()
            self._state = None
        shutil.rmtree(self.dir, ignore_errors=True)


def _read_line(stream, timeout):
    import selectors
    selector = selectors.DefaultSelector()
    selector.register(stream, selectors.EVENT_READ)
    ready = selector.select(timeout)
    selector.close()
    return stream.readline() if ready else ''


def _hold(device):
    """Stream from a device until stdin closes (the `busy` fault's other process)."""
    import v4l2_ioctl
    fd = v4l2_ioctl.open_device(device)
    stream = v4l2_ioctl.Stream(fd)
    print('streaming', flush=True)
    sys.stdin.read()
    stream.close()
    os.close(fd)


if __name__ == '__main__':
    if len(sys.argv) == 3 and sys.argv[1] == 'hold':
        _hold(sys.argv[2])
    else:
        sys.exit('usage: emulated_camera.py hold DEVICE')
