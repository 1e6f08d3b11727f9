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
The pixel formats py_vision knows: one table that the whole camera layer reads.

Each `PixelFormat` says once: its V4L2 FourCC (what `--list-formats` prints and
`pixel_format` takes, case-insensitive; usb_cam's names are control_names'), what it is, the
sensor_msgs encoding of its pixels as sent (None where image_encodings has none: Humble's and
Jazzy's define mono8, mono16, rgb8, bgr8, the 8-bit Bayer patterns, yuv422 for UYVY,
yuv422_yuy2 for YUYV, nv21 and nv24), whether it is compressed, how its bytes lie in a buffer
(`Plane`s: bytes per pixel across, pixels per row down, which also give its bus cost) and how
it converts to bgr8, rgb8, mono8 and mono16 (OpenCV on a view of the buffer, with what that
costs), into a new array or into one given (`convert(view, output, out)`: a message's own
bytes, so that a frame's pixels are written once on their way out). A camera's own video
(H.264, HEVC) is compressed and has no conversion of a frame on its own: its frames are
decoded as a stream (video_decoder), and `auto` never chooses it. Negotiation (`auto`),
listing, diagnostics, the frames, the synthetic camera and the emulated test cameras all read
it; `from_yuyv` is how the test cameras make a format from their YUYV picture. A new format is
one entry in `_table()`.
"""

from dataclasses import dataclass
from typing import Callable, Dict, Optional, Tuple

import cv2
import numpy as np

__all__ = ['COLOUR_OUTPUTS', 'find', 'FORMATS', 'fourcc_code', 'fourcc_text', 'JPEG_FORMATS',
           'names_accepted', 'nv24_as_yuyv', 'OPENCV_BGR', 'OUTPUTS', 'PixelFormat', 'placed',
           'Plane', 'VIDEO_FORMATS']

# What a frame converts to; 'native' is the camera's own pixels.
OUTPUTS = ('bgr8', 'rgb8', 'mono8', 'mono16', 'native')
COLOUR_OUTPUTS = ('bgr8', 'rgb8', 'native')
# What a conversion costs, for `auto`: a view of the buffer, a cheap pass (a channel swap, a
# shift), a colour conversion, a JPEG decode.
VIEW, CHEAP, CONVERT, DECODE = 0, 1, 2, 3


@dataclass(frozen=True)
class Plane:
    """One plane of a raw format: `across` bytes per `per` pixels of a row; a row per `down`."""

    across: int
    per: int = 1
    down: int = 1

    def row_bytes(self, width: int) -> int:
        """Return the bytes of one of this plane's rows for an image `width` pixels wide."""
        return -(-width * self.across // self.per)

    def rows(self, height: int) -> int:
        """Return how many rows the plane has for an image `height` pixels high."""
        return -(-height // self.down)


# (cost, function(view, out=None)): the function returns the converted image, written into
# `out` when given and the image fits it (same shape and type), else a new array.
Conversion = Tuple[int, Callable[..., np.ndarray]]


@dataclass(frozen=True, eq=False)   # each format is one object: compared and hashed by identity
class PixelFormat:
    """One pixel format, described once (see the module's text)."""

    fourcc: str                        # as V4L2 names it, trailing spaces stripped: 'Y16'
    description: str
    encoding: Optional[str]            # sensor_msgs encoding of the pixels as sent
    conversions: Dict[str, Conversion]  # output -> (cost, function of the view)
    planes: Tuple[Plane, ...] = ()     # none: compressed
    channels: int = 1                  # of the view (packed formats)
    dtype: str = 'uint8'               # of the view's elements (little-endian, as V4L2's)
    bits: int = 8                      # significant bits of a sample
    mono: bool = False
    from_yuyv: Optional[Callable[[np.ndarray], np.ndarray]] = None

    @property
    def compressed(self) -> bool:
        """Return True for a compressed format (its frames' sizes vary)."""
        return not self.planes

    @property
    def video(self) -> bool:
        """Return True for a camera's own video: its frames are access units of a stream."""
        return self.fourcc in VIDEO_FORMATS

    @property
    def jpeg(self) -> bool:
        """Return True when its frames are JPEG images (passed through to the compressed topic)."""
        return self.fourcc in JPEG_FORMATS

    @property
    def code(self) -> int:
        """Return the V4L2 pixel format number: 'YUYV' -> 0x56595559."""
        return fourcc_code(self.fourcc)

    @property
    def picture(self) -> str:
        """Return the 8-bit output that keeps what it shows (mono8, else bgr8): a JPEG's input."""
        return 'mono8' if self.mono else 'bgr8'

    @property
    def bus_bytes(self) -> Optional[float]:
        """Return the bytes per pixel it costs on the bus (None for a compressed format)."""
        if self.compressed:
            return None
        return sum(plane.across / plane.per / plane.down for plane in self.planes)

    @property
    def native_encoding(self) -> str:
        """Return the encoding output_encoding native publishes: its own, else the nearest."""
        if self.encoding is not None:
            return self.encoding
        if self.mono:
            return 'mono16' if self.bits > 8 else 'mono8'
        return 'bgr8'

    def bytesperline(self, width: int) -> int:
        """Return the bytes of a row of the first plane (V4L2's bytesperline; 0: compressed)."""
        return self.planes[0].row_bytes(width) if self.planes else 0

    def frame_bytes(self, width: int, height: int, bytesperline: int = 0) -> int:
        """Return the bytes of a whole frame; rows of `bytesperline` (0: no padding)."""
        stride = bytesperline or self.bytesperline(width)
        first = self.planes[0]
        return sum(plane.rows(height) * stride * plane.across * first.per
                   // (plane.per * first.across) for plane in self.planes)

    def cost(self, output: str) -> int:
        """Return what converting a frame to `output` costs (VIEW .. DECODE)."""
        if output == 'native':
            if self.encoding is not None:
                return VIEW
            output = self.native_encoding
        return self.conversions[output][0]

    def view(self, data: np.ndarray, width: int, height: int,
             bytesperline: int = 0) -> np.ndarray:
        """
        Return the frame's bytes as the image OpenCV converts, a view where the layout allows.

        Packed formats: rows x columns [x channels] of `dtype`; planar ones: the planes one
        after another as rows of `width` bytes (OpenCV's layout of NV12, I420...), copied
        together first when rows are padded; compressed ones: the bytes.
        """
        if self.compressed:
            return data
        stride = bytesperline or self.bytesperline(width)
        if len(self.planes) == 1:
            dtype = np.dtype(self.dtype).newbyteorder('<')
            size = dtype.itemsize
            shape, strides = (height, width), (stride, size * self.channels)
            if self.channels > 1:
                shape, strides = shape + (self.channels,), strides + (size,)
            return np.ndarray(shape, dtype, data, 0, strides)
        natural = self.bytesperline(width)
        if stride != natural:
            data = self._unpadded(data, width, height, stride)
        rows = self.frame_bytes(width, height) // width
        return data[:rows * width].reshape(rows, width)

    def _unpadded(self, data, width, height, stride):
        """Return the planes' rows without the padding at their ends, one after another."""
        parts, offset, first = [], 0, self.planes[0]
        for plane in self.planes:
            plane_stride = stride * plane.across * first.per // (plane.per * first.across)
            rows = plane.rows(height)
            block = data[offset:offset + rows * plane_stride].reshape(rows, plane_stride)
            parts.append(block[:, :plane.row_bytes(width)].reshape(-1))
            offset += rows * plane_stride
        return np.concatenate(parts)

    def convert(self, view: np.ndarray, output: str,
                out: Optional[np.ndarray] = None) -> Optional[np.ndarray]:
        """
        Return the image `view` (from view()) as `output`: bgr8, rgb8, mono8, mono16, native.

        With `out`, the image is written into it and `out` returned when it has the image's
        shape and type; otherwise (a JPEG of another size) the image comes back in an array of
        its own, `out` untouched. None: a compressed frame that does not decode.
        """
        if output == 'native':
            if self.encoding is not None:
                return _same(view, out)
            output = self.native_encoding
        return self.conversions[output][1](view, out)


def fourcc_text(code: int) -> str:
    """Return a V4L2 pixel format number as its FourCC: 0x56595559 -> 'YUYV'."""
    return ''.join(chr((int(code) >> shift) & 0xFF) for shift in (0, 8, 16, 24)).strip('\0 ')


def fourcc_code(fourcc: str) -> int:
    """Return the V4L2 number of a FourCC ('Y16' is 'Y16 ')."""
    text = fourcc.ljust(4)
    return ord(text[0]) | ord(text[1]) << 8 | ord(text[2]) << 16 | ord(text[3]) << 24


# --- conversions ---------------------------------------------------------------------------

def _fits(image: Optional[np.ndarray], out: Optional[np.ndarray]) -> bool:
    """Return True when out can hold image as it is (same shape, same type)."""
    return out is not None and image is not None and image.shape == out.shape and (
        image.dtype == out.dtype)


def placed(image: Optional[np.ndarray], out: Optional[np.ndarray]) -> Optional[np.ndarray]:
    """Return image copied into out where it fits, else image itself (None stays None)."""
    if not _fits(image, out):
        return image
    np.copyto(out, image)
    return out


def _cvt(code_name: str) -> Conversion:
    code = getattr(cv2, 'COLOR_' + code_name)
    return CONVERT, lambda view, out=None: _cvt_into(view, code, out)


def _cvt_into(view, code, out=None):
    """cv2.cvtColor into out; OpenCV makes an array of its own where out does not fit."""
    if out is None:
        return cv2.cvtColor(view, code)
    image = cv2.cvtColor(view, code, dst=out)
    # OpenCV hands back out itself, or a new array where out did not fit.
    return out if image.__array_interface__['data'][0] == out.ctypes.data else image


def _same(view, out=None):
    return view if out is None else placed(view, out)


def _widen(view, out=None):
    """8-bit to 16-bit as cv_bridge scales it (x 65535 / 255, i.e. x 257)."""
    if out is None or out.shape != view.shape or out.dtype != np.uint16:
        out = None
    return np.multiply(view, np.uint16(257), out=out, dtype=np.uint16)


def _narrow(view, out=None):
    """16-bit to 8-bit as cv_bridge scales it (x 255 / 65535, rounded)."""
    if out is None:
        return cv2.convertScaleAbs(view, alpha=255.0 / 65535.0)
    image = cv2.convertScaleAbs(view, dst=out, alpha=255.0 / 65535.0)
    return out if image.__array_interface__['data'][0] == out.ctypes.data else image


def _shift_right_2(view, out=None):
    """10 bits in 16 to 8 bits."""
    return placed((view >> 2).astype(np.uint8), out)


def _shift_left_6(view, out=None):
    """10 bits in 16 to 16 bits."""
    if out is None or out.shape != view.shape or out.dtype != view.dtype:
        return view << 6
    return np.left_shift(view, 6, out=out)


def _then(first: Conversion, second: Callable) -> Conversion:
    cost, step = first

    def both(view, out=None):
        image = step(view)
        return None if image is None else second(image, out)
    return max(cost, CHEAP), both


def _yuv(suffix: str) -> Dict[str, Conversion]:
    """YUV formats OpenCV converts itself: YUYV, UYVY, YVYU, NV12, NV21, I420, YV12."""
    gray = _cvt('YUV2GRAY_' + suffix)
    return {'bgr8': _cvt('YUV2BGR_' + suffix), 'rgb8': _cvt('YUV2RGB_' + suffix),
            'mono8': gray, 'mono16': _then(gray, _widen)}


def _grey(mono8: Conversion, mono16: Conversion) -> Dict[str, Conversion]:
    def colour(code):
        return _then(mono8, lambda view, out=None: _cvt_into(view, code, out))
    return {'mono8': mono8, 'mono16': mono16, 'bgr8': colour(cv2.COLOR_GRAY2BGR),
            'rgb8': colour(cv2.COLOR_GRAY2RGB)}


def _rgb(order: str) -> Dict[str, Conversion]:
    other = 'BGR' if order == 'RGB' else 'RGB'
    gray = _cvt('%s2GRAY' % order)
    return {order.lower() + '8': (VIEW, _same), other.lower() + '8': _cvt(order + '2' + other),
            'mono8': gray, 'mono16': _then(gray, _widen)}


def _bayer(opencv_name: str) -> Dict[str, Conversion]:
    # OpenCV names a pattern after the 2x2 block that starts at pixel (1, 1).
    gray = _cvt('Bayer%s2GRAY' % opencv_name)
    return {'bgr8': _cvt('Bayer%s2BGR' % opencv_name), 'rgb8': _cvt('Bayer%s2RGB' % opencv_name),
            'mono8': gray, 'mono16': _then(gray, _widen)}


def nv24_as_yuyv(view):
    """NV24 (Y plane, then U V for every pixel) as YUYV: every other pixel's chroma."""
    height = view.shape[0] // 3
    uv = view[height:].reshape(height, -1, 2)
    out = np.empty((height, view.shape[1], 2), np.uint8)
    out[:, :, 0] = view[:height]
    out[:, 0::2, 1] = uv[:, 0::2, 0]
    out[:, 1::2, 1] = uv[:, 0::2, 1]
    return out


def _nv24() -> Dict[str, Conversion]:
    """NV24 through YUYV: OpenCV 4.6 has no NV24 conversion (its chroma is halved across)."""
    def through_yuyv(step):
        return lambda view, out=None: step(nv24_as_yuyv(view), out)
    return {output: (CONVERT, through_yuyv(step)) for output, (_, step) in _yuv('YUYV').items()}


def _jpeg() -> Dict[str, Conversion]:
    # A JPEG decodes into an array of its own (cv2.imdecode takes none): copied into out.
    def decode(flag):
        return DECODE, lambda data, out=None: placed(cv2.imdecode(data, flag), out)

    def rgb(data, out=None):
        image = cv2.imdecode(data, cv2.IMREAD_COLOR)
        return None if image is None else _cvt_into(image, cv2.COLOR_BGR2RGB, out)
    gray = decode(cv2.IMREAD_GRAYSCALE)
    return {'bgr8': decode(cv2.IMREAD_COLOR), 'rgb8': (DECODE, rgb), 'mono8': gray,
            'mono16': _then(gray, _widen)}


# --- how the test cameras make each format from their YUYV picture --------------------------

def _luma(yuyv):
    return yuyv[:, :, 0]


def _chroma(yuyv, rows=slice(None)):
    """Return U and V, one sample per pixel pair, of the rows asked."""
    chroma = yuyv[rows, :, 1]
    return chroma[:, 0::2], chroma[:, 1::2]


def _packed_422(order):
    def make(yuyv):
        u, v = _chroma(yuyv)
        y = _luma(yuyv)
        samples = {'Y0': y[:, 0::2], 'Y1': y[:, 1::2], 'U': u, 'V': v}
        out = np.empty(yuyv.shape[:2] + (2,), np.uint8)
        quads = out.reshape(yuyv.shape[0], -1, 4)
        for position, name in enumerate(order):
            quads[:, :, position] = samples[name]
        return out
    return make


def _semi_planar(first):
    def make(yuyv):
        u, v = _chroma(yuyv, slice(0, None, 2))
        uv = np.stack([u, v] if first == 'U' else [v, u], axis=2)
        return np.concatenate([_luma(yuyv).reshape(-1), uv.reshape(-1)])
    return make


def _planar(first):
    def make(yuyv):
        u, v = _chroma(yuyv, slice(0, None, 2))
        planes = [u, v] if first == 'U' else [v, u]
        return np.concatenate([_luma(yuyv).reshape(-1)] + [p.reshape(-1) for p in planes])
    return make


def _nv24_from(yuyv):
    u, v = _chroma(yuyv)
    uv = np.empty(yuyv.shape[:2] + (2,), np.uint8)
    uv[:, 0::2, 0] = uv[:, 1::2, 0] = u
    uv[:, 0::2, 1] = uv[:, 1::2, 1] = v
    return np.concatenate([_luma(yuyv).reshape(-1), uv.reshape(-1)])


def _deep(shift):
    """8-bit luma as a 16-bit sample of `shift + 8` bits: Y16 repeats the byte, Y10 shifts."""
    def make(yuyv):
        y = _luma(yuyv).astype(np.uint16)
        return (y << 8 | y) if shift == 8 else (y << shift)
    return make


def _colour(code_name):
    code = getattr(cv2, 'COLOR_YUV2%s_YUYV' % code_name)
    return lambda yuyv: cv2.cvtColor(yuyv, code)


def _mosaic(pattern):
    """Sample a Bayer pattern ('BGGR': B G on even rows, G R on odd ones) from the picture."""
    channel = {'B': 0, 'G': 1, 'R': 2}

    def make(yuyv):
        bgr = cv2.cvtColor(yuyv, cv2.COLOR_YUV2BGR_YUYV)
        out = np.empty(bgr.shape[:2], np.uint8)
        for index, colour in enumerate(pattern):
            row, column = divmod(index, 2)
            out[row::2, column::2] = bgr[row::2, column::2, channel[colour]]
        return out
    return make


_PACKED_422 = (Plane(2),)
_PLANAR_420 = (Plane(1), Plane(1, 1, 2))             # Y, then interleaved chroma
_THREE_PLANES_420 = (Plane(1), Plane(1, 2, 2), Plane(1, 2, 2))
_ONE = (Plane(1),)
_TWO = (Plane(2),)


def _table():
    shift16, shift10 = (VIEW, _same), (CHEAP, _shift_left_6)
    formats = [
        PixelFormat('YUYV', 'YUYV 4:2:2', 'yuv422_yuy2', _yuv('YUYV'), _PACKED_422, 2,
                    from_yuyv=_packed_422(('Y0', 'U', 'Y1', 'V'))),
        PixelFormat('UYVY', 'UYVY 4:2:2', 'yuv422', _yuv('UYVY'), _PACKED_422, 2,
                    from_yuyv=_packed_422(('U', 'Y0', 'V', 'Y1'))),
        PixelFormat('YVYU', 'YVYU 4:2:2', None, _yuv('YVYU'), _PACKED_422, 2,
                    from_yuyv=_packed_422(('Y0', 'V', 'Y1', 'U'))),
        PixelFormat('NV12', 'Y/UV 4:2:0', None, _yuv('NV12'), _PLANAR_420,
                    from_yuyv=_semi_planar('U')),
        PixelFormat('NV21', 'Y/VU 4:2:0', 'nv21', _yuv('NV21'), _PLANAR_420,
                    from_yuyv=_semi_planar('V')),
        PixelFormat('YU12', 'Planar YUV 4:2:0', None, _yuv('I420'), _THREE_PLANES_420,
                    from_yuyv=_planar('U')),
        PixelFormat('YV12', 'Planar YVU 4:2:0', None, _yuv('YV12'), _THREE_PLANES_420,
                    from_yuyv=_planar('V')),
        PixelFormat('NV24', 'Y/UV 4:4:4', 'nv24', _nv24(), (Plane(1), Plane(2)),
                    from_yuyv=_nv24_from),
        PixelFormat('RGB3', '24-bit RGB 8-8-8', 'rgb8', _rgb('RGB'), (Plane(3),), 3,
                    from_yuyv=_colour('RGB')),
        PixelFormat('BGR3', '24-bit BGR 8-8-8', 'bgr8', _rgb('BGR'), (Plane(3),), 3,
                    from_yuyv=_colour('BGR')),
        PixelFormat('GREY', '8-bit Greyscale', 'mono8', _grey((VIEW, _same), (CHEAP, _widen)),
                    _ONE, mono=True, from_yuyv=_luma),
        PixelFormat('Y16', '16-bit Greyscale', 'mono16', _grey((CHEAP, _narrow), shift16),
                    _TWO, dtype='uint16', bits=16, mono=True, from_yuyv=_deep(8)),
        PixelFormat('Y10', '10-bit Greyscale', None,
                    _grey((CHEAP, _shift_right_2), shift10),
                    _TWO, dtype='uint16', bits=10, mono=True, from_yuyv=_deep(2)),
    ]
    for fourcc, pattern, opencv_name in (('BA81', 'BGGR', 'RG'), ('GBRG', 'GBRG', 'GR'),
                                         ('GRBG', 'GRBG', 'GB'), ('RGGB', 'RGGB', 'BG')):
        formats.append(PixelFormat(
            fourcc, '8-bit Bayer %s' % pattern, 'bayer_%s8' % pattern.lower(),
            _bayer(opencv_name), _ONE, from_yuyv=_mosaic(pattern)))
    for fourcc, description in (('MJPG', 'Motion-JPEG'), ('JPEG', 'JFIF JPEG')):
        formats.append(PixelFormat(fourcc, description, None, _jpeg()))
    for fourcc, description in (('H264', 'H.264'), ('HEVC', 'HEVC')):
        formats.append(PixelFormat(fourcc, description, None, {}))
    return {pixel_format.fourcc: pixel_format for pixel_format in formats}


JPEG_FORMATS = ('MJPG', 'JPEG')
# A camera's own video, published as it comes (transport.VideoPublisher): V4L2's FourCC -> the
# codec video_decoder and annexb take.
VIDEO_FORMATS = {'H264': 'h264', 'HEVC': 'hevc'}
# Every format, in the order `auto` prefers them when they cost the same.
FORMATS: Dict[str, PixelFormat] = _table()
# The layout of OpenCV's own images (what a video file gives).
OPENCV_BGR = FORMATS['BGR3']
_BY_NAME = {pixel_format.fourcc.lower(): pixel_format for pixel_format in FORMATS.values()}


def names_accepted() -> str:
    """Return, in words, the FourCCs a `pixel_format` may name."""
    return '%s (case-insensitive)' % ', '.join(fourcc.lower() for fourcc in FORMATS)


def find(name: str) -> Optional[PixelFormat]:
    """Return the format a FourCC names (case-insensitive: 'yuyv', 'Y16'), or None."""
    return _BY_NAME.get(str(name).strip().lower())
