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
The synthetic V4L2 source: a camera with OpenCV's VideoCapture interface and no hardware.

`SyntheticCamera` behaves like a V4L2 camera seen through OpenCV: it honours the requested size
and frame rate (an odd width is rounded down to even, as YUYV needs), builds every frame as a
packed YUYV 4:2:2 buffer and converts it with ``cv2.COLOR_YUV2BGR_YUYV`` as OpenCV's V4L2 backend
does, and paces frames in real time with a single buffer: a caller that falls behind gets the
newest frame and the frames in between are lost (their indices are skipped).

Every frame shows 75% colour bars with a moving box, a grey ramp and, in a dark strip at the
bottom, the frame index as digits and as a 4 x 11 grid of black/white blocks that
`read_frame_index` decodes (32 bits of index, an 8-bit CRC and four corner sync blocks). The
blocks are pure luma over neutral chroma, so they stay grey through YUYV, JPEG and the bridge.
A block is 1/40 of the width or 1/30 of the height, whichever is smaller, kept within 4..32
pixels; frames smaller than 64 x 48 (`MIN_CODE_SIZE`) carry the bars and the box only. Each
frame is built from a YUYV background precomputed once per size, and read() returns a new array
every time (the caller may keep it while the next frame is built).

Like a USB 2.0 UVC camera it offers two pixel formats. YUYV is limited by the bus to 24 MB/s:
the highest of 30, 25, 20, 15, 10 and 5 fps whose ``width * height * 2`` bytes fit (640x480 at
30, 1280x720 at 10, 1920x1080 at 5 fps). MJPEG runs at the requested rate at any size. The
FOURCC is chosen with ``set(CAP_PROP_FOURCC)`` and, as in OpenCV's V4L2 backend, YUYV is the
format a camera opens with; with ``CAP_PROP_CONVERT_RGB`` off in MJPEG mode, read() returns the
camera's JPEG bytes as a 1-D uint8 array, otherwise a BGR image. A real camera encodes JPEG in
hardware, so the synthetic one does not pay for a whole encode per frame: the scene above the
frame code repeats every 64 frames and is encoded once per cycle position, and only the MCU
rows of the code strip are encoded per frame and spliced in (restart markers at every MCU row
make the two encodings' rows interchangeable: the result is the same bytes as a full encode).

Camera controls (`CONTROLS`: brightness, contrast, saturation, sharpness, gain, white balance
and its auto switch, exposure and auto exposure, focus and autofocus) are set and read through
set() and get() with V4L2-like ranges (`control_range()`), and change the image visibly and
deterministically: brightness offsets it, contrast scales it around mid-grey, saturation scales
its colour, sharpness sharpens or softens it, gain and (manual) exposure brighten it, a manual
white balance tints it (lower temperatures bluer), a manual focus away from 0 blurs it.

Faults for tests, as constructor options or in a ``video_device`` string (`open_synthetic`):
``fail_open`` (never opens), ``stop_after`` (unplugged after N frames), ``unplugged_for``
(reopening works again that many seconds after the unplug) and ``fail_every`` (every K-th read
fails while the device stays open); ``formats`` restricts what the camera offers
(``synthetic?formats=yuyv``, ``mjpeg`` or ``yuyv,mjpeg``). Devices with the same name and
options share one state, kept in this module: the frame index and an unplug carry over to the
next camera opened with them.
"""

from dataclasses import dataclass
import functools
import math
import re
import threading
import time
from urllib.parse import parse_qsl

import cv2
import numpy as np

MAX_SIZE = 8192
MIN_CODE_SIZE = (64, 48)
MAX_FPS = 1000.0
FOURCC_YUYV = float(cv2.VideoWriter_fourcc(*'YUYV'))
FOURCC_MJPG = float(cv2.VideoWriter_fourcc(*'MJPG'))
FORMATS = {'yuyv': FOURCC_YUYV, 'mjpeg': FOURCC_MJPG}
# USB 2.0 high speed carries about 24 MB/s of isochronous video; UVC cameras offer these rates.
BUS_BYTES_PER_S = 24e6
UVC_RATES = (30.0, 25.0, 20.0, 15.0, 10.0, 5.0)
JPEG_QUALITY = 90

# Patched by the tests to run the pacing on a fake clock.
_now = time.monotonic
_sleep = time.sleep

_BLACK = 16
# The digits 0-9, seven rows of five pixels each.
_FONT_5X7 = (
    '01110 10001 10011 10101 11001 10001 01110',
    '00100 01100 00100 00100 00100 00100 01110',
    '01110 10001 00001 00010 00100 01000 11111',
    '11110 00001 00001 01110 00001 00001 11110',
    '00010 00110 01010 10010 11111 00010 00010',
    '11111 10000 11110 00001 00001 10001 01110',
    '00110 01000 10000 11110 10001 10001 01110',
    '11111 00001 00010 00100 01000 01000 01000',
    '01110 10001 10001 01110 10001 10001 01110',
    '01110 10001 10001 01111 00001 00010 01100',
)
_WHITE = 235
_STRIP = 40
_CODE_ROWS, _CODE_COLS = 4, 11
# Corner blocks with fixed values let the decoder measure black and white in the image itself.
_SYNC = {(0, 0): 1, (0, _CODE_COLS - 1): 0, (_CODE_ROWS - 1, 0): 0,
         (_CODE_ROWS - 1, _CODE_COLS - 1): 1}
_DATA_CELLS = [(r, c) for r in range(_CODE_ROWS) for c in range(_CODE_COLS)
               if (r, c) not in _SYNC]
# 75% colour bars, BGR: white, yellow, cyan, green, magenta, red, blue.
_BARS = [(191, 191, 191), (0, 191, 191), (191, 191, 0), (0, 191, 0), (191, 0, 191),
         (0, 0, 191), (191, 0, 0)]
_BOX_PERIOD = 64
_OPTIONS = 'fail_open, stop_after, unplugged_for, fail_every, formats'


def _crc8(data):
    crc = 0
    for byte in data:
        crc ^= byte
        for _ in range(8):
            crc = ((crc << 1) ^ 0x07) & 0xFF if crc & 0x80 else (crc << 1) & 0xFF
    return crc


def _code_bits(index):
    """Return the 40 data-cell bits for an index: 32 bits of index then the CRC-8, MSB first."""
    value = index & 0xFFFFFFFF
    payload = value.to_bytes(4, 'big')
    word = (value << 8) | _crc8(payload)
    return [(word >> (39 - i)) & 1 for i in range(40)]


class _Geometry:
    """Where everything goes in a frame of one size (cheap: the decoder uses it too)."""

    def __init__(self, width, height):
        self.width, self.height = width, height
        self.code = None
        self.strip_y = height
        if width >= MIN_CODE_SIZE[0] and height >= MIN_CODE_SIZE[1]:
            cell = max(4, min(32, min(width // 40, height // 30) & ~1))
            margin = cell // 2
            self.strip_y = height - (_CODE_ROWS * cell + 2 * margin)
            self.code = (width - margin - _CODE_COLS * cell, self.strip_y + margin, cell)
            self.digits_area = (margin, self.strip_y + margin,
                                self.code[0] - 2 * margin, _CODE_ROWS * cell)
        scene = self.strip_y
        self.bars_h = max(1, (scene * 2) // 3)
        self.box_h = max(1, self.bars_h // 4)
        self.box_y = (self.bars_h - self.box_h) // 2
        self.box_w = min(width, max(2, (width // 16) & ~1))


@functools.lru_cache(maxsize=32)
def _geometry(width, height):
    return _Geometry(width, height)


def bgr_to_yuyv(bgr):
    """
    Convert a BGR uint8 image of even width to packed YUYV (BT.601, video range).

    This is the inverse of ``cv2.COLOR_YUV2BGR_YUYV``, done in numpy because older OpenCV 4.x
    has no BGR to YUYV conversion. Chroma is the average of each horizontal pixel pair.
    """
    height, width = bgr.shape[:2]
    if width % 2:
        raise ValueError('YUYV needs an even width, got %d' % width)
    b, g, r = (bgr[:, :, i].astype(np.float32) for i in range(3))
    y = 16.0 + 0.2568 * r + 0.5041 * g + 0.0979 * b
    u = 128.0 - 0.1482 * r - 0.2910 * g + 0.4392 * b
    v = 128.0 + 0.4392 * r - 0.3678 * g - 0.0714 * b
    out = np.empty((height, width, 2), np.uint8)
    out[:, :, 0] = np.clip(np.rint(y), 0, 255)
    out[:, 0::2, 1] = np.clip(np.rint((u[:, 0::2] + u[:, 1::2]) / 2), 0, 255)
    out[:, 1::2, 1] = np.clip(np.rint((v[:, 0::2] + v[:, 1::2]) / 2), 0, 255)
    return out


def yuyv_to_bgr(yuyv):
    """Convert packed YUYV to BGR exactly as OpenCV's V4L2 backend does."""
    return cv2.cvtColor(yuyv, cv2.COLOR_YUV2BGR_YUYV)


class _Layout:
    """The precomputed YUYV background and digit glyphs for one frame size."""

    def __init__(self, width, height):
        geo = self.geo = _geometry(width, height)
        bgr = np.empty((height, width, 3), np.uint8)
        bar_edges = [(width * i // len(_BARS)) & ~1 for i in range(len(_BARS))] + [width]
        for i, colour in enumerate(_BARS):
            bgr[:geo.bars_h, bar_edges[i]:bar_edges[i + 1]] = colour
        ramp = np.linspace(0, 255, width).astype(np.uint8)
        bgr[geo.bars_h:] = ramp[None, :, None]
        self.background = bgr_to_yuyv(bgr)
        # The strip and the ramp are grey: neutral chroma, so YUYV keeps them exactly grey.
        self.background[geo.bars_h:, :, 1] = 128
        self.background[geo.strip_y:, :, 0] = _STRIP
        self.glyphs = None
        if geo.code is not None:
            self._make_glyphs()

    def _make_glyphs(self):
        x0, y0, area_w, area_h = self.geo.digits_area
        # A built-in 5x7 font, not cv2.putText, so that a frame is the same bytes whatever
        # OpenCV draws it (4.x and 5.x render Hershey text differently).
        scale = int(0.7 * area_h) // 7
        if scale < 1:
            return
        cell_w = 6 * scale
        count = min(10, area_w // cell_w)
        top = (area_h - 7 * scale) // 2
        glyphs = np.full((10, area_h, cell_w), _STRIP, np.uint8)
        for digit, rows in enumerate(_FONT_5X7):
            bits = np.array([[ch == '1' for ch in row] for row in rows.split()], bool)
            pixels = np.kron(bits, np.ones((scale, scale), bool))
            glyphs[digit, top:top + 7 * scale, scale // 2:scale // 2 + 5 * scale][pixels] = _WHITE
        self.glyphs = glyphs
        self.blank = np.full_like(glyphs[0], _STRIP)
        self.digit_count = count
        self.digits_origin = (x0, y0)

    def render(self, index, buf, fresh):
        """Draw frame `index` into `buf` (YUYV, a copy of the background if `fresh`)."""
        geo = self.geo
        y0, y1 = geo.box_y, geo.box_y + geo.box_h
        if not fresh:
            buf[y0:y1] = self.background[y0:y1]
        travel = geo.width - geo.box_w
        x = ((index % _BOX_PERIOD) * travel // (_BOX_PERIOD - 1)) & ~1 if travel > 0 else 0
        box = buf[y0:y1, x:x + geo.box_w]
        box[:, :, 1] = 128
        box[:, :, 0] = _BLACK
        edge = max(1, geo.box_w // 8)
        if geo.box_h > 2 * edge:
            box[edge:-edge, edge:-edge, 0] = _WHITE
        if geo.code is None:
            return
        if self.glyphs is not None:
            text = str(index)[-self.digit_count:].ljust(self.digit_count)
            digits = [self.glyphs[int(ch)] if ch != ' ' else self.blank for ch in text]
            dx, dy = self.digits_origin
            row = np.concatenate(digits, axis=1)
            buf[dy:dy + row.shape[0], dx:dx + row.shape[1], 0] = row
        cx, cy, cell = geo.code
        cells = np.empty((_CODE_ROWS, _CODE_COLS), np.uint8)
        for (r, c), bit in _SYNC.items():
            cells[r, c] = _WHITE if bit else _BLACK
        for (r, c), bit in zip(_DATA_CELLS, _code_bits(index)):
            cells[r, c] = _WHITE if bit else _BLACK
        blocks = np.repeat(np.repeat(cells, cell, axis=0), cell, axis=1)
        buf[cy:cy + blocks.shape[0], cx:cx + blocks.shape[1], 0] = blocks


@functools.lru_cache(maxsize=8)
def _layout(width, height):
    return _Layout(width, height)


def synthetic_yuyv(index, width, height):
    """Return the YUYV buffer of frame `index` at this size (a new array)."""
    layout = _layout(width, height)
    buf = layout.background.copy()
    layout.render(index, buf, fresh=True)
    return buf


def synthetic_frame(index, width, height):
    """Return exactly the BGR image a SyntheticCamera of this size gives for frame `index`."""
    return yuyv_to_bgr(synthetic_yuyv(index, width, height))


def yuyv_max_fps(width, height):
    """Return the highest UVC rate at which YUYV frames of this size fit the USB 2.0 bus."""
    for rate in UVC_RATES:
        if width * height * 2 * rate <= BUS_BYTES_PER_S:
            return rate
    return UVC_RATES[-1]


@dataclass(frozen=True)
class Control:
    """A camera control: its OpenCV property, V4L2-like range and the camera's default."""

    prop: int
    minimum: int
    maximum: int
    default: int


# V4L2 exposes auto exposure as a menu (1 manual, 3 aperture priority, i.e. automatic) and the
# automatic switches as 0/1, which is what OpenCV's V4L2 backend passes through.
CONTROLS = {
    'brightness': Control(cv2.CAP_PROP_BRIGHTNESS, -64, 64, 0),
    'contrast': Control(cv2.CAP_PROP_CONTRAST, 0, 64, 32),
    'saturation': Control(cv2.CAP_PROP_SATURATION, 0, 128, 64),
    'sharpness': Control(cv2.CAP_PROP_SHARPNESS, 0, 6, 3),
    'gain': Control(cv2.CAP_PROP_GAIN, 0, 100, 0),
    'auto_white_balance': Control(cv2.CAP_PROP_AUTO_WB, 0, 1, 1),
    'white_balance': Control(cv2.CAP_PROP_WB_TEMPERATURE, 2800, 6500, 4600),
    'auto_exposure': Control(cv2.CAP_PROP_AUTO_EXPOSURE, 1, 3, 3),
    'exposure': Control(cv2.CAP_PROP_EXPOSURE, 3, 2047, 166),
    'autofocus': Control(cv2.CAP_PROP_AUTOFOCUS, 0, 1, 1),
    'focus': Control(cv2.CAP_PROP_FOCUS, 0, 250, 0),
}
_CONTROL_BY_PROP = {control.prop: name for name, control in CONTROLS.items()}
_DEFAULT_CONTROLS = {name: control.default for name, control in CONTROLS.items()}


def apply_controls(yuyv, values):
    """
    Return the YUYV buffer as the camera's controls make it look (the same array at defaults).

    Luma is offset by brightness, scaled around mid-grey by contrast and brightened by gain
    and, with auto exposure off, by exposure; chroma is scaled by saturation and, with auto
    white balance off, shifted by the white balance (lower temperatures bluer); sharpness away
    from 3 sharpens or softens and, with autofocus off, a focus away from 0 blurs.
    """
    if values == _DEFAULT_CONTROLS:
        return yuyv
    v = values
    luma = yuyv[:, :, 0].astype(np.float32)
    chroma = yuyv[:, :, 1].astype(np.float32)
    gain = 1.0 + v['gain'] / 100.0
    if v['auto_exposure'] == 1:
        gain *= v['exposure'] / float(CONTROLS['exposure'].default)
    luma = (luma - 128.0) * (v['contrast'] / 32.0) + 128.0 + v['brightness']
    luma = (luma - 16.0) * gain + 16.0
    blur = v['focus'] / 25.0 if v['autofocus'] == 0 else 0.0
    if blur > 0:
        luma = cv2.GaussianBlur(luma, (0, 0), blur)
    if v['sharpness'] != 3:
        soft = cv2.GaussianBlur(luma, (0, 0), 1.5)
        luma = luma + (luma - soft) * ((v['sharpness'] - 3) / 3.0)
    chroma = (chroma - 128.0) * (v['saturation'] / 64.0) + 128.0
    if v['auto_white_balance'] == 0:
        shift = (CONTROLS['white_balance'].default - v['white_balance']) / 50.0
        chroma[:, 0::2] += shift   # U: bluer below the default temperature
        chroma[:, 1::2] -= shift   # V: less red
    out = np.empty_like(yuyv)
    out[:, :, 0] = np.clip(np.rint(luma), 0, 255)
    out[:, :, 1] = np.clip(np.rint(chroma), 0, 255)
    return out


_RESTART = re.compile(rb'\xff[\xd0-\xd7]')


def _jpeg_rows(jpeg):
    """Split a JPEG with a restart marker after every MCU row into (header, rows)."""
    sos = jpeg.index(b'\xff\xda')
    header_end = sos + 2 + int.from_bytes(jpeg[sos + 2:sos + 4], 'big')
    return jpeg[:header_end], _RESTART.split(jpeg[header_end:-2])


class _MjpegEncoder:
    """
    JPEG frames of one size as a camera's hardware encoder gives them, at little CPU cost.

    The rows above the code strip repeat every _BOX_PERIOD frames: they are encoded once per
    position in that cycle; only the MCU rows from the strip down are encoded per frame.
    """

    MCU = 16  # 4:2:0 sampling, libjpeg's default for colour images

    def __init__(self, width, height):
        geo = _geometry(width, height)
        self.split = (geo.strip_y // self.MCU) * self.MCU
        self.params = [cv2.IMWRITE_JPEG_QUALITY, JPEG_QUALITY,
                       cv2.IMWRITE_JPEG_RST_INTERVAL, (width + self.MCU - 1) // self.MCU]
        self.scenes = {}

    def encode(self, index, yuyv):
        """Return the JPEG bytes of frame `index` whose YUYV buffer is `yuyv`."""
        key = index % _BOX_PERIOD
        if key not in self.scenes:
            full = self._encode(yuyv_to_bgr(yuyv))
            header, rows = _jpeg_rows(full)
            self.scenes[key] = (header, rows[:self.split // self.MCU])
            return full
        header, top = self.scenes[key]
        rows = top + _jpeg_rows(self._encode(yuyv_to_bgr(yuyv[self.split:])))[1]
        out = bytearray(header)
        for number, row in enumerate(rows):
            out += row
            out += b'\xff%c' % (0xD0 + number % 8) if number < len(rows) - 1 else b'\xff\xd9'
        return bytes(out)

    def _encode(self, bgr):
        ok, buffer = cv2.imencode('.jpg', bgr, self.params)
        if not ok:
            raise ValueError('JPEG encoding failed for a %s frame' % (bgr.shape,))
        return buffer.tobytes()


@functools.lru_cache(maxsize=4)
def _mjpeg_encoder(width, height):
    return _MjpegEncoder(width, height)


def synthetic_jpeg(index, width, height):
    """Return exactly the JPEG bytes a SyntheticCamera of this size gives in MJPEG mode."""
    return _mjpeg_encoder(width, height).encode(index, synthetic_yuyv(index, width, height))


def _luma(image):
    """Return the image as float32 luma on a 0..255 scale, or None if it is not an image."""
    image = np.asarray(image)
    if image.ndim == 3:
        channels = image.shape[2]
        if channels >= 3:
            # Summing channel planes is many times faster than mean(axis=2).
            luma = image[:, :, 0].astype(np.float32)
            luma += image[:, :, 1]
            luma += image[:, :, 2]
            luma /= 3.0
        elif channels == 2:
            luma = image[:, :, 0].astype(np.float32)  # raw YUYV: luma first
        elif channels == 1:
            luma = image[:, :, 0].astype(np.float32)
        else:
            return None
    elif image.ndim == 2:
        luma = image.astype(np.float32)
    else:
        return None
    if image.dtype == np.uint16 and luma.size and luma.max() > 255:
        luma /= 257.0
    elif image.dtype.kind == 'f' and luma.size and luma.max() <= 1.0:
        luma *= 255.0
    return luma


def read_frame_index(image):
    """
    Decode the frame index a synthetic frame carries, or None if the image has no code.

    Works on the camera's BGR frames and on what the bridge or JPEG (quality 50 or better)
    makes of them: RGB, BGRA, mono8/mono16, float images, as long as the size is unchanged.
    """
    if image is None:
        return None
    shape = np.shape(image)
    if len(shape) < 2:
        return None
    geo = _geometry(int(shape[1]), int(shape[0]))
    if geo.code is None:
        return None
    cx, cy, cell = geo.code
    # Only the code's pixels are converted: decoding costs the same at any frame size.
    grid = _luma(np.asarray(image)[cy:cy + _CODE_ROWS * cell, cx:cx + _CODE_COLS * cell])
    if grid is None:
        return None
    grid = grid.reshape(_CODE_ROWS, cell, _CODE_COLS, cell)
    inset = cell // 4
    inner = grid[:, inset:cell - inset, :, inset:cell - inset]
    count = float(inner.shape[1] * inner.shape[3])
    means = inner.sum(axis=3).sum(axis=1) / count
    squares = (inner * inner).sum(axis=3).sum(axis=1) / count
    spread = np.sqrt(np.maximum(squares - means * means, 0.0))
    white = np.mean([means[rc] for rc, bit in _SYNC.items() if bit])
    black = np.mean([means[rc] for rc, bit in _SYNC.items() if not bit])
    contrast = white - black
    if contrast < 100:
        return None
    threshold = (white + black) / 2
    if np.any(np.abs(means - threshold) < 0.3 * contrast) or np.any(spread > 0.2 * contrast):
        return None
    bits = [int(means[rc] > threshold) for rc in _DATA_CELLS]
    word = 0
    for bit in bits:
        word = (word << 1) | bit
    value, crc = word >> 8, word & 0xFF
    if _crc8(value.to_bytes(4, 'big')) != crc:
        return None
    return value


class FramePacer:
    """
    Real-time frame schedule: frame n is due at t0 + n / fps, t0 being the first wait().

    With ``drop=True`` (a camera with a single buffer) a late caller gets the newest due frame
    and the frames in between are skipped. With ``drop=False`` (a file played in real time) a
    late caller gets the next frame at once and the schedule restarts from there.
    """

    def __init__(self, fps, drop=True):
        self.fps = fps
        self.drop = drop
        self.t0 = None
        self.next = 0
        self.cancelled = threading.Event()

    def cancel(self):
        """End a wait() in progress (in another thread) and every later one at once."""
        self.cancelled.set()

    def restart(self):
        """Start a new schedule at the next wait() (after a size or rate change)."""
        self.t0 = None
        self.next = 0

    @property
    def running(self):
        return self.t0 is not None

    def wait(self):
        """Block until the next frame is due; return its number in this schedule and due time."""
        now = _now()
        if self.t0 is None:
            self.t0 = now
            self.next = 1
            return 0, now
        number = self.next
        due = self.t0 + number / self.fps
        if now >= due + 1.0 / self.fps:
            if self.drop:
                number = max(number, int(math.floor((now - self.t0) * self.fps)))
                due = self.t0 + number / self.fps
            else:
                self.t0 = now - number / self.fps
                due = now
        else:
            _sleep_until(due, self.cancelled)
        self.next = number + 1
        return number, due


def _sleep_until(deadline, cancelled):
    # Sleep most of the wait, then short sleeps: never more than ~0.1 ms late, no busy spin.
    # Long waits (low frame rates) are cut into 50 ms steps so that cancel() is seen quickly.
    while not cancelled.is_set():
        remaining = deadline - _now()
        if remaining <= 0:
            return
        _sleep(min(0.05, remaining - 0.001 if remaining > 0.002 else remaining))


class _DeviceState:
    """What outlives one SyntheticCamera object: the frame sequence and an unplug."""

    def __init__(self):
        self.last_index = None
        self.last_time = None
        self.unplugged_at = None
        self.recovered = False


_devices = {}
_devices_lock = threading.Lock()


def reset_synthetic_devices():
    """Forget every device's state (frame sequence, unplugs): for tests."""
    with _devices_lock:
        _devices.clear()


def _device_state(key):
    with _devices_lock:
        return _devices.setdefault(key, _DeviceState())


def _check_size(value):
    if not isinstance(value, (int, float, np.integer, np.floating)) or isinstance(value, bool):
        return None
    if not math.isfinite(value) or value <= 0 or value > MAX_SIZE:
        return None
    return int(value)


def _check_fps(value):
    if not isinstance(value, (int, float, np.integer, np.floating)) or isinstance(value, bool):
        return None
    if not math.isfinite(value) or value <= 0 or value > MAX_FPS:
        return None
    return float(value)


class SyntheticCamera:
    """
    A V4L2 camera without hardware, with OpenCV's VideoCapture interface.

    `last_index` is the frame index of the image the last successful read() returned and
    `last_capture_time` the time.monotonic() at which it was captured (its due time; earlier
    than the read's return when the caller was late). `error` says why the device is not
    open, or why its reads fail, or is None. `formats` names the pixel formats it offers
    (keys of FORMATS); it opens in YUYV where it offers it, as OpenCV's V4L2 backend does.
    """

    def __init__(self, width=640, height=480, fps=10.0, *, fail_open=False, stop_after=None,
                 unplugged_for=None, fail_every=None, formats=('yuyv', 'mjpeg'),
                 name='synthetic'):
        w, h, rate = _check_size(width), _check_size(height), _check_fps(fps)
        if w is None or h is None:
            raise ValueError('image size must be 1..%d pixels each way, got %r x %r'
                             % (MAX_SIZE, width, height))
        if rate is None:
            raise ValueError('framerate must be > 0 and <= %g, got %r' % (MAX_FPS, fps))
        if stop_after is not None and (int(stop_after) != stop_after or stop_after < 0):
            raise ValueError('stop_after must be an integer >= 0, got %r' % (stop_after,))
        if unplugged_for is not None and not (0 <= unplugged_for < math.inf):
            raise ValueError('unplugged_for must be a number of seconds >= 0, got %r'
                             % (unplugged_for,))
        if fail_every is not None and (int(fail_every) != fail_every or fail_every < 1):
            raise ValueError('fail_every must be an integer >= 1, got %r' % (fail_every,))
        unknown = [f for f in formats if f not in FORMATS]
        if unknown or not formats:
            raise ValueError('formats must be one or more of %s, got %s'
                             % (', '.join(FORMATS), ','.join(formats) or 'none'))
        self.name = name
        self.last_index = None
        self.last_capture_time = None
        self.error = None
        self._width, self._height = max(2, w & ~1), h
        self._offered = [FORMATS[f] for f in FORMATS if f in formats]
        self._fourcc = self._offered[0]
        self._convert_rgb = True
        self._controls = dict(_DEFAULT_CONTROLS)
        self._requested_fps = rate
        self._pacer = FramePacer(self._rate())
        self._stop_after = stop_after
        self._fail_every = fail_every
        self._frames = 0
        self._reads = 0
        self._base = 0
        self._grabbed = None
        self._buf = None
        self._rendered = None
        self._state = _device_state((name, stop_after, unplugged_for, fail_every, formats))
        self._opened = not fail_open
        if fail_open:
            self.error = 'the device does not open (fail_open)'
        elif self._state.unplugged_at is not None and not self._state.recovered:
            away = _now() - self._state.unplugged_at
            if unplugged_for is None or away < unplugged_for:
                self._opened = False
                self.error = 'the device is unplugged (stop_after=%d)' % stop_after
                if unplugged_for is not None:
                    self.error += ' and back in %.1f s' % (unplugged_for - away)
            else:
                self._state.recovered = True

    def isOpened(self):  # noqa: N802 (OpenCV's name)
        """Return True while the device is open (also after an unplug, as V4L2 does)."""
        return self._opened

    def release(self):
        """Close the device; reads fail afterwards."""
        self._opened = False
        self._buf = None
        self._rendered = None
        self._grabbed = None

    def interrupt(self):
        """Make a read() waiting for its frame in another thread fail at once, and later ones."""
        self._pacer.cancel()

    def _unplugged(self):
        if (self._stop_after is None or self._state.recovered
                or self._frames < self._stop_after):
            return False
        if self._state.unplugged_at is None:
            self._state.unplugged_at = _now()
        self.error = 'the device was unplugged after %d frames (stop_after)' % self._stop_after
        return True

    def grab(self):
        """Wait for the next frame and capture it; False on a failed read."""
        self._grabbed = None
        if not self._opened or self._unplugged():
            return False
        starting = not self._pacer.running
        if not starting:
            # A sensor's frame exists at its capture time: build the YUYV buffer of the frame
            # expected next before waiting for it, so only the BGR conversion follows the stamp.
            self._render(self._base + self._pacer.next)
        number, due = self._pacer.wait()
        if self._pacer.cancelled.is_set():
            return False
        if starting:
            self._base = self._next_index(due)
        index = self._base + number
        self._state.last_index, self._state.last_time = index, due
        self._reads += 1
        if self._fail_every and self._reads % self._fail_every == 0:
            return False
        self._frames += 1
        self._grabbed = index
        self.last_index, self.last_capture_time = index, due
        return True

    def _next_index(self, start):
        """Index of the first frame of a new schedule: the sequence goes on, gaps included."""
        state = self._state
        if state.last_index is None:
            return 0
        missed = int(round((start - state.last_time) * self._pacer.fps))
        return state.last_index + max(1, missed)

    def retrieve(self, image=None, flag=0):
        """
        Return the grabbed frame (a new array each call).

        A BGR image, or with CAP_PROP_CONVERT_RGB off the buffer as the camera sent it, as a
        1-D uint8 array: the JPEG bytes in MJPEG mode, the packed YUYV bytes in YUYV mode.
        """
        if self._grabbed is None or not self._opened:
            return False, None
        if self._rendered != self._grabbed:
            self._render(self._grabbed)
        yuyv = apply_controls(self._buf, self._controls)
        if self._fourcc == FOURCC_YUYV:
            if self._convert_rgb:
                return True, yuyv_to_bgr(yuyv)
            return True, yuyv.reshape(-1).copy()
        encoder = _mjpeg_encoder(self._width, self._height)
        if yuyv is self._buf:
            jpeg = encoder.encode(self._grabbed, yuyv)
        else:  # controls changed the whole picture: no cached rows apply
            jpeg = encoder._encode(yuyv_to_bgr(yuyv))
        data = np.frombuffer(jpeg, np.uint8)
        if self._convert_rgb:
            return True, cv2.imdecode(data, cv2.IMREAD_COLOR)
        return True, data.copy()

    def _render(self, index):
        layout = _layout(self._width, self._height)
        fresh = self._buf is None or self._buf.shape != layout.background.shape
        if fresh:
            self._buf = layout.background.copy()
        layout.render(index, self._buf, fresh)
        self._rendered = index

    def read(self, image=None):
        """Grab and retrieve: (True, BGR image) or (False, None)."""
        if not self.grab():
            return False, None
        return self.retrieve()

    def _rate(self):
        """Return the frame rate the camera gives: YUYV is limited by the bus, MJPEG is not."""
        if self._fourcc == FOURCC_YUYV:
            return min(self._requested_fps, yuyv_max_fps(self._width, self._height))
        return self._requested_fps

    def controls(self):
        """Return the camera's controls: name -> Control (OpenCV property, range, default)."""
        return dict(CONTROLS)

    def set(self, prop_id, value):  # noqa: A003 (OpenCV's name)
        """
        Set a property like a V4L2 driver; False for what the camera refuses.

        Width and height (an odd width is rounded down), fps (YUYV is capped by the bus),
        FOURCC (YUYV or MJPG where offered), CONVERT_RGB and the controls within their range.
        """
        if not self._opened:
            return False
        prop_id = int(prop_id)
        if prop_id in _CONTROL_BY_PROP:
            control = CONTROLS[_CONTROL_BY_PROP[prop_id]]
            if not isinstance(value, (int, float, np.integer, np.floating)) or not (
                    math.isfinite(value) and control.minimum <= value <= control.maximum):
                return False
            self._controls[_CONTROL_BY_PROP[prop_id]] = int(round(value))
            return True
        if prop_id == cv2.CAP_PROP_CONVERT_RGB:
            self._convert_rgb = bool(value)
            return True
        if prop_id == cv2.CAP_PROP_FOURCC:
            if value not in self._offered:
                return False
            changed, self._fourcc = value != self._fourcc, float(value)
        elif prop_id in (cv2.CAP_PROP_FRAME_WIDTH, cv2.CAP_PROP_FRAME_HEIGHT):
            size = _check_size(value)
            if size is None:
                return False
            if prop_id == cv2.CAP_PROP_FRAME_WIDTH:
                size = max(2, size & ~1)
                changed, self._width = size != self._width, size
            else:
                changed, self._height = size != self._height, size
        elif prop_id == cv2.CAP_PROP_FPS:
            rate = _check_fps(value)
            if rate is None:
                return False
            changed, self._requested_fps = rate != self._requested_fps, rate
        else:
            return False
        rate = self._rate()
        if changed or rate != self._pacer.fps:
            self._pacer.fps = rate
            self._pacer.restart()
            self._rendered = None
        return True

    def get(self, prop_id):
        """Return the real width, height, fps, next frame index, FOURCC or last capture time."""
        if not self._opened:
            return 0.0
        prop_id = int(prop_id)
        if prop_id == cv2.CAP_PROP_FRAME_WIDTH:
            return float(self._width)
        if prop_id == cv2.CAP_PROP_FRAME_HEIGHT:
            return float(self._height)
        if prop_id == cv2.CAP_PROP_FPS:
            return float(self._pacer.fps)
        if prop_id == cv2.CAP_PROP_FOURCC:
            return self._fourcc
        if prop_id == cv2.CAP_PROP_CONVERT_RGB:
            return 1.0 if self._convert_rgb else 0.0
        if prop_id in _CONTROL_BY_PROP:
            return float(self._controls[_CONTROL_BY_PROP[prop_id]])
        if prop_id == cv2.CAP_PROP_POS_FRAMES:
            if self._pacer.running:
                return float(self._base + self._pacer.next)
            last = self._state.last_index
            return 0.0 if last is None else float(last + 1)
        if prop_id == cv2.CAP_PROP_POS_MSEC:
            return 0.0 if self.last_capture_time is None else self.last_capture_time * 1000.0
        return 0.0


def _parse_bool(key, text):
    lowered = text.lower()
    if lowered in ('1', 'true'):
        return True
    if lowered in ('0', 'false'):
        return False
    raise ValueError('%s must be 0, 1, true or false, got "%s"' % (key, text))


def _parse_number(key, text, kind, minimum):
    try:
        value = kind(text)
    except ValueError:
        value = None
    if value is None or not math.isfinite(value) or value < minimum:
        raise ValueError('%s must be %s >= %s, got "%s"'
                         % (key, 'an integer' if kind is int else 'a number', minimum, text))
    return value


def parse_synthetic_spec(spec):
    """Return the SyntheticCamera fault options a ``synthetic?key=value&...`` string asks for."""
    base, _, query = spec.partition('?')
    if base != 'synthetic':
        raise ValueError('"%s" is not a synthetic device (synthetic or synthetic?key=value)'
                         % spec)
    options = {}
    for key, value in parse_qsl(query, keep_blank_values=True):
        if key in options:
            raise ValueError('option %s is given twice' % key)
        if key == 'fail_open':
            options[key] = _parse_bool(key, value)
        elif key in ('stop_after', 'fail_every'):
            options[key] = _parse_number(key, value, int, 0 if key == 'stop_after' else 1)
        elif key == 'unplugged_for':
            options[key] = _parse_number(key, value, float, 0)
        elif key == 'formats':
            options[key] = tuple(f.strip().lower() for f in value.split(',') if f.strip())
            unknown = [f for f in options[key] if f not in FORMATS]
            if unknown or not options[key]:
                raise ValueError('formats must be a comma-separated list of %s, got "%s"'
                                 % (', '.join(FORMATS), value))
        else:
            raise ValueError('unknown option "%s"; use synthetic?key=value&key=value with keys: %s'
                             % (key, _OPTIONS))
    if query and not options:
        raise ValueError('cannot read options "%s"; use key=value&key=value with keys: %s'
                         % (query, _OPTIONS))
    return options


def is_synthetic_spec(video_device):
    """Return True if a video_device string names the synthetic source."""
    return video_device == 'synthetic' or video_device.startswith('synthetic?')


def open_synthetic(spec, width, height, fps):
    """
    Open the synthetic camera a video_device string names; ValueError if the string is bad.

    The whole string names the device, so reopening it finds the same frame sequence and
    unplug state.
    """
    options = parse_synthetic_spec(spec)
    return SyntheticCamera(width, height, fps, name=spec, **options)
