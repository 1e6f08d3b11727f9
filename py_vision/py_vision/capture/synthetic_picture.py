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
The synthetic camera's picture: what its sensor sees, as YUYV, BGR and JPEG, and its code.

Every frame shows 75% colour bars with a moving box, a grey ramp and, in a dark strip at the
bottom, the frame index as digits and as a 4 x 11 grid of black/white blocks that
`read_frame_index` decodes (32 bits of index, an 8-bit CRC and four corner sync blocks). The
blocks are pure luma over neutral chroma, so they stay grey through YUYV, JPEG and the bridge.
A block is 1/40 of the width or 1/30 of the height, whichever is smaller, kept within 4..32
pixels; frames smaller than 64 x 48 (`MIN_CODE_SIZE`) carry the bars and the box only. Each
frame is built from a YUYV background precomputed once per size.

A real camera encodes JPEG in hardware, so the synthetic one does not pay for a whole encode
per frame: the scene above the frame code repeats every 64 frames and is encoded once per cycle
position, and only the MCU rows of the code strip are encoded per frame and spliced in (restart
markers at every MCU row make the two encodings' rows interchangeable: the result is the same
bytes as a full encode). `apply_controls` is what the camera's controls do to the picture.
"""

import functools
import re

import cv2
import numpy as np
from py_vision.capture.controls import CID, EXPOSURE_MANUAL

MIN_CODE_SIZE = (64, 48)
JPEG_QUALITY = 90

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
def frame_layout(width, height):
    """Return the precomputed background and glyphs of frames of this size."""
    return _Layout(width, height)


def synthetic_yuyv(index, width, height):
    """Return the YUYV buffer of frame `index` at this size (a new array)."""
    layout = frame_layout(width, height)
    buf = layout.background.copy()
    layout.render(index, buf, fresh=True)
    return buf


def synthetic_frame(index, width, height):
    """Return exactly the BGR image a SyntheticCamera of this size gives for frame `index`."""
    return yuyv_to_bgr(synthetic_yuyv(index, width, height))


def apply_controls(yuyv, values, neutral):
    """
    Return the YUYV buffer as the camera's controls make it look (the same array at neutral).

    `values` and `neutral` (the camera's defaults) map V4L2 control ids to values. Luma is
    offset by brightness, scaled around mid-grey by contrast and brightened by gain and, with
    auto exposure manual (1), by exposure time; chroma is scaled by saturation and, with
    automatic white balance off, shifted by the temperature (lower temperatures bluer);
    sharpness away from its default sharpens or softens and, with continuous autofocus off, a
    focus away from 0 blurs.
    """
    if values == neutral:
        return yuyv
    v, n = values, neutral
    luma = yuyv[:, :, 0].astype(np.float32)
    chroma = yuyv[:, :, 1].astype(np.float32)
    gain = 1.0 + v[CID.GAIN] / 100.0
    if v[CID.EXPOSURE_AUTO] == EXPOSURE_MANUAL:
        gain *= v[CID.EXPOSURE_ABSOLUTE] / float(n[CID.EXPOSURE_ABSOLUTE])
    luma = (luma - 128.0) * (v[CID.CONTRAST] / float(n[CID.CONTRAST])) + 128.0 \
        + v[CID.BRIGHTNESS]
    luma = (luma - 16.0) * gain + 16.0
    blur = v[CID.FOCUS_ABSOLUTE] / 25.0 if v[CID.FOCUS_AUTO] == 0 else 0.0
    if blur > 0:
        luma = cv2.GaussianBlur(luma, (0, 0), blur)
    if v[CID.SHARPNESS] != n[CID.SHARPNESS]:
        soft = cv2.GaussianBlur(luma, (0, 0), 1.5)
        luma = luma + (luma - soft) * ((v[CID.SHARPNESS] - n[CID.SHARPNESS]) / 3.0)
    chroma = (chroma - 128.0) * (v[CID.SATURATION] / float(n[CID.SATURATION])) + 128.0
    if v[CID.AUTO_WHITE_BALANCE] == 0:
        shift = (n[CID.WHITE_BALANCE_TEMPERATURE] - v[CID.WHITE_BALANCE_TEMPERATURE]) / 50.0
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
            full = self.encode_whole(yuyv_to_bgr(yuyv))
            header, rows = _jpeg_rows(full)
            self.scenes[key] = (header, rows[:self.split // self.MCU])
            return full
        header, top = self.scenes[key]
        rows = top + _jpeg_rows(self.encode_whole(yuyv_to_bgr(yuyv[self.split:])))[1]
        out = bytearray(header)
        for number, row in enumerate(rows):
            out += row
            out += b'\xff%c' % (0xD0 + number % 8) if number < len(rows) - 1 else b'\xff\xd9'
        return bytes(out)

    def encode_whole(self, bgr):
        ok, buffer = cv2.imencode('.jpg', bgr, self.params)
        if not ok:
            raise ValueError('JPEG encoding failed for a %s frame' % (bgr.shape,))
        return buffer.tobytes()


@functools.lru_cache(maxsize=4)
def mjpeg_encoder(width, height):
    """Return the JPEG encoder of frames of this size (its cached rows are shared)."""
    return _MjpegEncoder(width, height)


def synthetic_jpeg(index, width, height):
    """Return exactly the JPEG bytes a SyntheticCamera of this size gives in MJPEG mode."""
    return mjpeg_encoder(width, height).encode(index, synthetic_yuyv(index, width, height))


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
