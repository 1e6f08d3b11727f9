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
A pure-Python (numpy + OpenCV) replacement for ROS 2's ``cv_bridge`` Python module.

``from py_vision.cv_bridge import CvBridge, CvBridgeError`` gives the API rclpy programs know:
``imgmsg_to_cv2``, ``cv2_to_imgmsg``, ``compressed_imgmsg_to_cv2``, ``cv2_to_compressed_imgmsg``,
the encoding helpers, and the module-level ``getCvType`` and ``cvtColorForDisplay``. Depth
changes give exactly what upstream's ``cv::Mat::convertTo`` gives on x86 (rounding to nearest,
saturation, NaN and infinities); any ``<depth>C<n>`` encoding up to OpenCV's 512 channels works.
docs/cv_bridge.md describes it all.

Differences from upstream, all on the side of saying what is wrong instead of crashing or
returning a wrong image: every failure is a ``CvBridgeError`` (a ``TypeError``) naming the
problem; a malformed message (short or long data, a step smaller than a row) is rejected; and
``imgmsg_to_cv2`` returns a view of the message data (no copy) whenever it can, and a writable
copy when the data is read-only (``bytes``) or must be byte-swapped or converted.
"""

import array
import functools
import re
import struct
import sys

import cv2
import numpy as np
from py_vision.capture.pixel_formats import nv24_as_yuyv

from sensor_msgs.msg import CompressedImage, Image
from std_msgs.msg import Header

__all__ = ['CvBridge', 'CvBridgeError', 'cvtColorForDisplay', 'getCvType']


class CvBridgeError(TypeError):
    """Raised by the bridge for anything it cannot convert; the message says why."""


# --- encoding tables, built once at import ------------------------------------------------

_DEPTH_DTYPES = {'8U': 'uint8', '8S': 'int8', '16U': 'uint16', '16S': 'int16', '32S': 'int32',
                 '32F': 'float32', '64F': 'float64'}
_DTYPE_DEPTHS = {(np.dtype(v).kind, np.dtype(v).itemsize): k for k, v in _DEPTH_DTYPES.items()}

# OpenCV's CV_CN_MAX: the most channels a cv::Mat element can have.
_CN_MAX = 512
# OpenCV 5 widened the depth field of a type number (CV_CN_SHIFT went from 3 to 5) and
# OpenCV 4's Python module has no CV_MAKETYPE, so the layout is read from the running cv2.
_CN_SHIFT = (cv2.CV_8UC2 - cv2.CV_8UC1).bit_length() - 1
_DEPTH_NUMBERS = {getattr(cv2, 'CV_' + d): d for d in _DEPTH_DTYPES}
# A generic encoding: a depth and a channel count, or a bare depth for one channel.
_GENERIC_NAME = re.compile(r'(8U|8S|16U|16S|32S|32F|64F)(?:C([1-9][0-9]*))?')

_GRAY, _RGB, _BGR, _RGBA, _BGRA = 'GRAY', 'RGB', 'BGR', 'RGBA', 'BGRA'
_UYVY, _YUY2 = 'YUV422', 'YUV422_YUY2'
# Semi-planar YUV: the luma plane, then a plane of chroma pairs (rows of `step` bytes each).
_NV21, _NV24 = 'NV21', 'NV24'
_BAYERS = ('RGGB', 'BGGR', 'GBRG', 'GRBG')


class _Encoding:
    """What the bridge knows about one encoding string."""

    __slots__ = ('name', 'depth', 'dtype', 'channels', 'family', 'bits', 'cvtype_name',
                 'cvtype', 'pixel_bytes', 'rows')

    def __init__(self, name, depth, channels, family, rows=(1, 1)):
        self.name = name
        self.depth = depth
        self.dtype = np.dtype(_DEPTH_DTYPES[depth])
        self.channels = channels
        # The colour layout (None for the generic 8UC3-style encodings, which carry none).
        self.family = family
        self.bits = self.dtype.itemsize * 8
        self.cvtype_name = '%sC%d' % (depth, channels)
        self.cvtype = getattr(cv2, 'CV_' + depth) + ((channels - 1) << _CN_SHIFT)
        self.pixel_bytes = self.dtype.itemsize * channels
        # Rows of data per row of picture (numerator, denominator): 3/2 for nv21, whose
        # chroma plane has half as many rows as its luma, 3 for nv24. OpenCV's layout.
        self.rows = rows


def _build_encodings():
    """Return the named encodings; generic ones ('8UC5', '32F') are added as they are met."""
    table = {}
    for bits, depth in ((8, '8U'), (16, '16U')):
        table['mono%d' % bits] = _Encoding('mono%d' % bits, depth, 1, _GRAY)
        for family, channels in ((_RGB, 3), (_BGR, 3), (_RGBA, 4), (_BGRA, 4)):
            name = '%s%d' % (family.lower(), bits)
            table[name] = _Encoding(name, depth, channels, family)
        for pattern in _BAYERS:
            name = 'bayer_%s%d' % (pattern.lower(), bits)
            table[name] = _Encoding(name, depth, 1, 'BAYER_' + pattern)
    # 'uyvy' and 'yuyv' are the newer sensor_msgs names of the same two layouts.
    for name, family in (('yuv422', _UYVY), ('uyvy', _UYVY),
                         ('yuv422_yuy2', _YUY2), ('yuyv', _YUY2)):
        table[name] = _Encoding(name, '8U', 2, family)
    table['nv21'] = _Encoding('nv21', '8U', 1, _NV21, (3, 2))
    table['nv24'] = _Encoding('nv24', '8U', 1, _NV24, (3, 1))
    return table


_ENCODINGS = _build_encodings()


def _cv_code(name):
    return getattr(cv2, 'COLOR_' + name, None)


def _through_yuyv(code, im):
    return cv2.cvtColor(nv24_as_yuyv(im), code)


def _build_conversions():
    """Map (source family, destination family) to the cv2.cvtColor code (None: same layout)."""
    codes = {}
    plain = (_GRAY, _RGB, _BGR, _RGBA, _BGRA)
    for src in plain + (_UYVY, _YUY2):
        codes[(src, src)] = None
    for src in plain:
        for dst in plain:
            if src != dst:
                codes[(src, dst)] = _cv_code('%s2%s' % (src, dst))
    for family, suffix in ((_UYVY, 'UYVY'), (_YUY2, 'YUY2'), (_NV21, 'NV21')):
        for dst in plain:
            codes[(family, dst)] = _cv_code('YUV2%s_%s' % (dst, suffix))
    codes[(_NV21, _NV21)] = codes[(_NV24, _NV24)] = None
    for dst in plain:
        # OpenCV 4.6 has no NV24 conversion: through YUYV, its chroma halved across.
        codes[(_NV24, dst)] = functools.partial(_through_yuyv, _cv_code('YUV2%s_YUY2' % dst))
    # OpenCV names a Bayer pattern after the 2x2 block starting at pixel (1, 1).
    opencv_names = {'RGGB': 'BG', 'BGGR': 'RG', 'GBRG': 'GR', 'GRBG': 'GB'}
    for pattern, cv_name in opencv_names.items():
        for dst in plain:
            code = _cv_code('Bayer%s2%s' % (cv_name, dst))
            if code is not None:
                codes[('BAYER_' + pattern, dst)] = code
    return codes


_CONVERSIONS = _build_conversions()
# cv_bridge scales between the 8-bit and 16-bit ranges when only the bit depth changes.
_SCALE_8_TO_16, _SCALE_16_TO_8 = 65535.0 / 255.0, 255.0 / 65535.0
_PLANS = {}
_NATIVE_BIG = sys.byteorder == 'big'


def _encoding(name):
    try:
        return _ENCODINGS[name]
    except (KeyError, TypeError):
        pass
    match = _GENERIC_NAME.fullmatch(name) if isinstance(name, str) else None
    if match is None:
        raise CvBridgeError('Unrecognized image encoding [%s]' % (name,))
    channels = int(match.group(2) or 1)
    if channels > _CN_MAX:
        raise CvBridgeError('Unrecognized image encoding [%s]: %d channels, OpenCV allows at '
                            'most %d' % (name, channels, _CN_MAX))
    # Only valid names are kept, so the table stays bounded (7 depths by 512 channel counts).
    enc = _ENCODINGS[name] = _Encoding(name, match.group(1), channels, None)
    return enc


def _generic_encoding(depth, channels):
    return _encoding('%sC%d' % (depth, channels))


def _plan(src, dst):
    """Return the steps from encoding src to dst: ('cvt', code) and ('depth', alpha) tuples."""
    key = (src.name, dst.name)
    plan = _PLANS.get(key)
    if plan is not None:
        return plan
    alpha = 1.0
    if src.bits == 8 and dst.bits == 16:
        alpha = _SCALE_8_TO_16
    elif src.bits == 16 and dst.bits == 8:
        alpha = _SCALE_16_TO_8
    if src.family is None or dst.family is None:
        if src.family is None and dst.family is not None:
            raise CvBridgeError('[%s] is not a color format but [%s] is: the conversion does '
                                'not make sense' % (src.name, dst.name))
        if src.channels != dst.channels:
            raise CvBridgeError('[%s] and [%s] do not have the same number of channels (%d and '
                                '%d)' % (src.name, dst.name, src.channels, dst.channels))
        plan = (('depth', alpha),)
    else:
        pair = (src.family, dst.family)
        if pair not in _CONVERSIONS:
            raise CvBridgeError('Unsupported conversion from [%s] to [%s]' % (src.name, dst.name))
        code = _CONVERSIONS[pair]
        step = ('fn', code) if callable(code) else ('cvt', code)
        plan = (('depth', alpha),) if code is None else (step, ('depth', alpha))
    _PLANS[key] = plan
    return plan


# cv::Mat::convertTo skips the scaling when |alpha - 1| is below DBL_EPSILON.
_DBL_EPSILON = np.finfo(np.float64).eps


def _work_dtype(src, dst):
    """
    Return the type cv::Mat::convertTo does scaled arithmetic in for dtype src to dtype dst.

    Double only where OpenCV's result needs it (measured on OpenCV 4.6 and 5.0, see
    test_cv_bridge_convert_to.py): a 64F result, 32S from 32S or 64F, 32F from 64F.
    """
    if dst == np.float64 or (dst == np.int32 and src in (np.int32, np.float64)) or (
            dst == np.float32 and src == np.float64):
        return np.dtype(np.float64)
    return np.dtype(np.float32)


def _round_to_int(work, dtype):
    """
    Round floats to nearest (ties to even) and saturate to an integer dtype, as x86 OpenCV does.

    OpenCV rounds through int32 with the x86 conversion instructions, which give INT_MIN for
    NaN, for infinities and for anything outside int32; that INT_MIN is then saturated, so all
    of those become the smallest value of a signed type and 0 of an unsigned one.
    """
    with np.errstate(invalid='ignore'):
        rounded = np.rint(work)
        # Both bounds are exact in float32 and float64; NaN fails both comparisons.
        outside = ~((rounded >= -2147483648.0) & (rounded < 2147483648.0))
    if outside.any():
        rounded[outside] = -2147483648.0
    info = np.iinfo(dtype)
    np.clip(rounded, info.min, info.max, out=rounded)
    return rounded.astype(dtype)


def _saturate_int(im, dtype):
    """Return an integer image as another integer dtype, saturating (no scaling)."""
    src, dst = np.iinfo(im.dtype), np.iinfo(dtype)
    if src.min < dst.min or src.max > dst.max:
        # Bounds inside the source range: numpy 2 refuses to cast an out-of-range bound.
        im = np.clip(im, max(src.min, dst.min), min(src.max, dst.max))
    return im.astype(dtype)


def _convert_to(im, dtype, alpha=1.0):
    """
    Return im converted to dtype exactly as cv::Mat::convertTo(dst, depth, alpha) on x86.

    Scaled values are computed in OpenCV's work type (_work_dtype), rounded to nearest and
    saturated (_round_to_int); without scaling, integers saturate and floats round the same way.
    """
    dtype = np.dtype(dtype)
    if abs(alpha - 1.0) < _DBL_EPSILON:
        if im.dtype == dtype:
            return im
        if dtype.kind == 'f':
            # A double beyond float32's range becomes an infinity, as in C.
            with np.errstate(over='ignore'):
                return im.astype(dtype)
        if im.dtype.kind != 'f':
            return _saturate_int(im, dtype)
        return _round_to_int(im, dtype)
    if im.dtype.kind != 'f' and dtype.kind != 'f':
        if alpha > 0.0 and im.dtype in (np.uint8, np.uint16) and dtype == np.uint8:
            # Nothing is negative here, so OpenCV's convertScaleAbs is convertTo (the same float
            # arithmetic), in C: mono16 to mono8 in a fraction of numpy's time.
            return cv2.convertScaleAbs(im, alpha=alpha)
        # The other 8/16-bit scalings of cv_bridge, exact in integers.
        if alpha == _SCALE_8_TO_16 and im.dtype == np.uint8 and dtype == np.uint16:
            out = im.astype(np.uint16)
            out *= 257
            return out
        if alpha == _SCALE_8_TO_16 and im.dtype.itemsize == 1 and dtype.itemsize == 2:
            return _saturate_int(im.astype(np.int32) * 257, dtype)
        if alpha == _SCALE_16_TO_8 and im.dtype.itemsize == 2 and dtype.itemsize == 1:
            # v * 255 / 65535 is v / 257, never exactly halfway: round to nearest is this floor.
            return _saturate_int((im.astype(np.int32) + 128) // 257, dtype)
    work_dtype = _work_dtype(im.dtype, dtype)
    with np.errstate(over='ignore', invalid='ignore'):
        work = im.astype(work_dtype)
        work *= work_dtype.type(alpha)
        if dtype.kind == 'f':
            return work.astype(dtype)
    return _round_to_int(work, dtype)


def _add_scalar(im, value):
    """
    Return im + value in im's dtype, as cv::add(im, Scalar(value)) computes it on x86.

    For an integer image OpenCV rounds the scalar to int32 and adds in int32 (wrapping
    around), then saturates to the image's type; a float image adds in its own precision.
    """
    if im.dtype.kind == 'f':
        with np.errstate(over='ignore'):
            return im + im.dtype.type(value)
    offset = int(_round_to_int(np.array([value], np.float64), np.dtype(np.int32))[0])
    if im.itemsize <= 2 and abs(offset) < 2 ** 30:
        # Nothing can wrap around: int32 is enough, and faster.
        return _saturate_int(im.astype(np.int32) + offset, im.dtype)
    total = im.astype(np.int64) + offset
    return _saturate_int((total + 2 ** 31) % 2 ** 32 - 2 ** 31, im.dtype)


def _convert(im, src, dst):
    """Convert image im of encoding src to encoding dst, following cv_bridge's rules."""
    for step, value in _plan(src, dst):
        if step in ('cvt', 'fn'):
            if src.family in (_UYVY, _YUY2, _NV21, _NV24) and im.shape[1] % 2:
                # OpenCV 5 refuses this, but 4.6 converts it silently into a wrong image.
                raise CvBridgeError('A [%s] image must have an even width to convert to [%s]: '
                                    'its pixels come in pairs that share U and V, and this '
                                    'one is %d pixels wide' % (src.name, dst.name, im.shape[1]))
            try:
                im = value(im) if step == 'fn' else cv2.cvtColor(im, value)
            except cv2.error as exc:
                raise CvBridgeError('OpenCV cannot convert a %dx%d [%s] image to [%s]: %s' % (
                    im.shape[1], im.shape[0], src.name, dst.name,
                    str(exc).strip().splitlines()[-1])) from None
        else:
            im = _convert_to(im, dst.dtype, value)
    return im


def _byte_buffer(data):
    """Return the bytes of a message's data field as a 1-D uint8 array, a view when possible."""
    if isinstance(data, (bytes, bytearray)) or (
            isinstance(data, array.array) and data.itemsize == 1):
        return np.frombuffer(data, np.uint8)
    if isinstance(data, memoryview):
        if data.c_contiguous:
            return np.frombuffer(data, np.uint8)
        data = np.array(data)
    if isinstance(data, np.ndarray) and data.dtype == np.uint8:
        return data.reshape(-1)
    if isinstance(data, (str, bytes)) or not hasattr(data, '__len__'):
        raise CvBridgeError('Image data must be a sequence of bytes, not %s'
                            % type(data).__name__)
    try:
        values = np.asarray(data)
    except (TypeError, ValueError) as exc:
        raise CvBridgeError('Image data must be a sequence of bytes: %s' % exc) from None
    if values.size == 0:
        return np.empty(0, np.uint8)
    if values.dtype.kind not in 'iub' or values.min() < 0 or values.max() > 255:
        raise CvBridgeError('Image data must hold integers in [0, 255]')
    return values.astype(np.uint8).reshape(-1)


def _check_size(name, value):
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)):
        raise CvBridgeError('Image %s must be an integer, not %r' % (name, value))
    if value <= 0:
        raise CvBridgeError('Image %s is %d: the image is empty' % (name, value))
    return int(value)


def _image_from_msg(img_msg):
    """Return (numpy image in native byte order, its _Encoding) for a sensor_msgs/Image."""
    try:
        encoding, height, width = img_msg.encoding, img_msg.height, img_msg.width
        step, data, is_bigendian = img_msg.step, img_msg.data, img_msg.is_bigendian
    except AttributeError as exc:
        raise CvBridgeError('Expected a sensor_msgs/Image: %s' % exc) from None
    enc = _encoding(encoding)
    height = _check_size('height', height)
    width = _check_size('width', width)
    if isinstance(step, bool) or not isinstance(step, (int, np.integer)):
        raise CvBridgeError('Image step must be an integer, not %r' % (step,))
    row = width * enc.pixel_bytes
    if step < row:
        raise CvBridgeError('Image is wrongly formed: step %d is smaller than a row of %d pixels '
                            'of [%s] (%d bytes)' % (step, width, encoding, row))
    itemsize = enc.dtype.itemsize
    if step % itemsize:
        raise CvBridgeError('Image is wrongly formed: step %d is not a multiple of the %d-byte '
                            'element size of [%s]' % (step, itemsize, encoding))
    rows = _data_rows(enc, height, width)
    buf = _byte_buffer(data)
    if buf.size != rows * step:
        if rows == height:
            raise CvBridgeError('Image is wrongly formed: data has %d bytes but height x step '
                                'is %d x %d = %d' % (buf.size, height, step, height * step))
        raise CvBridgeError('Image is wrongly formed: data has %d bytes but a [%s] image %d '
                            'high has %d rows of step %d, %d bytes' % (
                                buf.size, encoding, height, rows, step, rows * step))
    swap = itemsize > 1 and bool(is_bigendian) != _NATIVE_BIG
    dtype = enc.dtype.newbyteorder('S') if swap else enc.dtype
    if enc.channels == 1:
        shape, strides = (rows, width), (step, itemsize)
    else:
        shape = (height, width, enc.channels)
        strides = (step, enc.pixel_bytes, itemsize)
    im = np.ndarray(shape, dtype=dtype, buffer=buf, strides=strides)
    if swap:
        im = im.astype(enc.dtype)
    elif not (im.flags.writeable and im.flags.aligned):
        # A read-only source (bytes) or an odd address: copy, so callers can draw on the image.
        im = im.copy()
    return im, enc


def _data_rows(enc, height, width):
    """Return the rows of data of a picture `height` rows high (more for semi-planar YUV)."""
    numerator, denominator = enc.rows
    if numerator == 1:
        return height
    if height % denominator or width % 2:
        raise CvBridgeError('A [%s] image must have an even width and height (its chroma is '
                            'subsampled), this one is %dx%d' % (enc.name, width, height))
    return height * numerator // denominator


def _array_encoding(cvim):
    """Return the generic encoding ('8UC3', ...) of a numpy image, or raise CvBridgeError."""
    if not isinstance(cvim, np.ndarray):
        raise CvBridgeError('Your input type is not a numpy array but %s' % type(cvim).__name__)
    if cvim.ndim == 2:
        channels = 1
    elif cvim.ndim == 3:
        channels = cvim.shape[2]
    else:
        raise CvBridgeError('An image must have 2 or 3 dimensions (rows, columns[, channels]), '
                            'this array has shape %s' % (cvim.shape,))
    depth = _DTYPE_DEPTHS.get((cvim.dtype.kind, cvim.dtype.itemsize))
    if depth is None:
        raise CvBridgeError('No image encoding has the numpy type %s (use uint8, int8, uint16, '
                            'int16, int32, float32 or float64)' % cvim.dtype)
    if not 1 <= channels <= _CN_MAX:
        raise CvBridgeError('No image encoding has %d channels (shape %s): OpenCV allows 1 to %d'
                            % (channels, cvim.shape, _CN_MAX))
    if cvim.shape[0] == 0 or cvim.shape[1] == 0:
        raise CvBridgeError('The image is empty (shape %s)' % (cvim.shape,))
    return _generic_encoding(depth, channels)


def _copy_header(header):
    try:
        copy = Header(frame_id=header.frame_id)
        copy.stamp.sec = header.stamp.sec
        copy.stamp.nanosec = header.stamp.nanosec
    except (AttributeError, AssertionError, TypeError) as exc:
        raise CvBridgeError('header must be a std_msgs/Header: %s' % exc) from None
    return copy


def fill_message_data(msg, cvim):
    """
    Copy the bytes of array cvim, row after row, into msg.data (Image, CompressedImage) once.

    The message's own (empty) array.array is filled in place: rclpy's data setter copies its
    argument again unless ROS_PYTHON_CHECK_FIELDS=1, which doubles the cost of a frame.
    """
    data = msg.data
    if not isinstance(data, array.array) or data.typecode != 'B' or len(data):
        data = array.array('B')
        msg.data = data
        data = msg.data
    if not cvim.flags.c_contiguous:
        cvim = np.ascontiguousarray(cvim)
    data.frombytes(cvim.reshape(-1).view(np.uint8))


def share_message_data(msg, cvim):
    """
    Make msg.data (Image, CompressedImage) the bytes of array cvim themselves: no copy.

    For a message published at once: rclpy copies the bytes into the middleware's message
    when it publishes, from cvim's own memory (a camera's buffer, say), so the frame is copied
    once instead of twice. cvim must stay unchanged until then. The message's field is set
    as the generated message code reads it (any object with the buffer protocol), not through
    its setter, which would copy it element by element.
    """
    if not cvim.flags.c_contiguous:
        cvim = np.ascontiguousarray(cvim)
    msg._data = cvim.reshape(-1).view(np.uint8)


# --- compressed images ----------------------------------------------------------------

_DECODED_ENCODINGS = {(1, 8): 'mono8', (1, 16): 'mono16', (3, 8): 'bgr8', (3, 16): 'bgr16',
                      (4, 8): 'bgra8', (4, 16): 'bgra16'}
_DEPTH_HEADER = struct.Struct('<iff')


def _decode_compressed(msg):
    """Return (numpy image, encoding name) for a sensor_msgs/CompressedImage."""
    try:
        fmt, data = msg.format, msg.data
    except AttributeError as exc:
        raise CvBridgeError('Expected a sensor_msgs/CompressedImage: %s' % exc) from None
    buf = _byte_buffer(data)
    if buf.size == 0:
        raise CvBridgeError('CompressedImage has no data (format %r)' % (fmt,))
    fmt = str(fmt)
    if 'compresseddepth' in fmt.lower():
        return _decode_compressed_depth(fmt, buf)
    im = cv2.imdecode(buf, cv2.IMREAD_UNCHANGED)
    if im is None:
        raise CvBridgeError('Could not decode the %d bytes of a CompressedImage with format %r'
                            % (buf.size, fmt))
    channels = 1 if im.ndim == 2 else im.shape[2]
    name = _DECODED_ENCODINGS.get((channels, im.dtype.itemsize * 8))
    if name is None:
        name = _array_encoding(im).name
    return im, name


def _decode_compressed_depth(fmt, buf):
    """Decode image_transport's compressedDepth format (a 12-byte header, then a PNG)."""
    original = fmt.split(';')[0].strip()
    if buf.size <= _DEPTH_HEADER.size:
        raise CvBridgeError('compressedDepth data is too short (%d bytes)' % buf.size)
    _, quant_a, quant_b = _DEPTH_HEADER.unpack(buf[:_DEPTH_HEADER.size].tobytes())
    im = cv2.imdecode(buf[_DEPTH_HEADER.size:], cv2.IMREAD_UNCHANGED)
    if im is None or im.dtype != np.uint16 or im.ndim != 2:
        raise CvBridgeError('Could not decode compressedDepth data with format %r' % (fmt,))
    if original == '32FC1':
        inv = im.astype(np.float32)
        with np.errstate(divide='ignore'):
            depth = np.float32(quant_a) / (inv - np.float32(quant_b))
        depth[im == 0] = np.nan
        return depth, '32FC1'
    return im, original if original in ('16UC1', 'mono16') else '16UC1'


# --- the bridge -----------------------------------------------------------------------


class CvBridge:
    """Convert between ROS sensor_msgs/Image (and CompressedImage) and numpy/OpenCV images."""

    # The lookup tables upstream exposes as instance attributes (1 to 4 channels, as there).
    cvtype_to_name = {_generic_encoding(d, c).cvtype: '%sC%d' % (d, c)
                      for d in _DEPTH_DTYPES for c in (1, 2, 3, 4)}
    numpy_type_to_cvtype = dict(list({v: k for k, v in _DEPTH_DTYPES.items()}.items())
                                + list(_DEPTH_DTYPES.items()))
    cvdepth_to_numpy_depth = {getattr(cv2, 'CV_' + d): v for d, v in _DEPTH_DTYPES.items()}

    def dtype_with_channels_to_cvtype2(self, dtype, n_channels):
        """Return the OpenCV type name ('8UC3', '8UC5', ...) of a numpy dtype and channel count."""
        try:
            dtype = np.dtype(dtype)
        except TypeError:
            raise CvBridgeError('%r is not a numpy dtype' % (dtype,)) from None
        depth = _DTYPE_DEPTHS.get((dtype.kind, dtype.itemsize))
        if depth is None or isinstance(n_channels, bool) or not isinstance(
                n_channels, (int, np.integer)) or not 1 <= n_channels <= _CN_MAX:
            raise CvBridgeError('No OpenCV type for numpy %s with %s channels'
                                % (dtype, n_channels))
        return _generic_encoding(depth, n_channels).name

    def cvtype2_to_dtype_with_channels(self, cvtype):
        """Return (numpy dtype name, channels) of an OpenCV type number such as cv2.CV_8UC3."""
        if isinstance(cvtype, bool) or not isinstance(cvtype, (int, np.integer)) or cvtype < 0:
            raise CvBridgeError('Unrecognized OpenCV type %r' % (cvtype,))
        depth = _DEPTH_NUMBERS.get(int(cvtype) & ((1 << _CN_SHIFT) - 1))
        channels = (int(cvtype) >> _CN_SHIFT) + 1
        if depth is None or channels > _CN_MAX:
            raise CvBridgeError('Unrecognized OpenCV type %r' % (cvtype,))
        return _DEPTH_DTYPES[depth], channels

    def encoding_to_cvtype2(self, encoding):
        """Return the OpenCV type number of an image encoding."""
        return getCvType(encoding)

    def encoding_to_dtype_with_channels(self, encoding):
        """Return (numpy dtype name, channels) of an image encoding, e.g. ('uint8', 3)."""
        enc = _encoding(encoding)
        return enc.dtype.name, enc.channels

    def imgmsg_to_cv2(self, img_msg, desired_encoding='passthrough'):
        """
        Convert a sensor_msgs/Image to a numpy image.

        With ``desired_encoding`` 'passthrough' (or the message's own encoding) the result is a
        view of the message data, in native byte order; otherwise it is converted as cv_bridge
        does (colour order, alpha, mono, 8/16-bit scaling, Bayer and YUV 4:2:2 to colour).
        One-channel images have two dimensions. Raises CvBridgeError when the message is
        malformed or the conversion is not possible.
        """
        im, enc = _image_from_msg(img_msg)
        if desired_encoding in ('passthrough', '', enc.name):
            return im
        return _convert(im, enc, _encoding(desired_encoding))

    def cv2_to_imgmsg(self, cvim, encoding='passthrough', header=None, share=False):
        """
        Convert a numpy image to a sensor_msgs/Image holding a copy of its pixels.

        With 'passthrough' the encoding is the array's OpenCV type ('8UC3', '16UC1', ...);
        otherwise ``encoding`` must have the array's type and channel count. ``header`` (a
        std_msgs/Header) is copied into the message. With ``share`` (not upstream's) the
        message holds cvim's own bytes instead of a copy (`share_message_data`): for a message
        published at once, while cvim is unchanged.
        """
        array_enc = _array_encoding(cvim)
        if encoding == 'passthrough':
            name = array_enc.name
        else:
            enc = _encoding(encoding)
            if enc.cvtype_name != array_enc.name:
                raise CvBridgeError('encoding specified as %s, but image has incompatible type %s'
                                    % (encoding, array_enc.name))
            name = enc.name
        img_msg = Image()
        if header is not None:
            img_msg.header = _copy_header(header)
        img_msg.height, img_msg.width = int(cvim.shape[0]), int(cvim.shape[1])
        numerator, denominator = _encoding(name).rows
        if numerator != 1:
            # A semi-planar image's array holds its chroma rows below its luma rows.
            height = img_msg.height * denominator // numerator
            if height * numerator != img_msg.height * denominator:
                raise CvBridgeError('A [%s] array has %d rows for each %d rows of picture: %d '
                                    'rows is not a picture' % (name, numerator, denominator,
                                                               img_msg.height))
            _data_rows(_encoding(name), height, img_msg.width)
            img_msg.height = height
        img_msg.encoding = name
        byteorder = cvim.dtype.byteorder
        img_msg.is_bigendian = cvim.dtype.itemsize > 1 and (
            byteorder == '>' or (byteorder == '=' and _NATIVE_BIG))
        img_msg.step = img_msg.width * array_enc.pixel_bytes
        (share_message_data if share else fill_message_data)(img_msg, cvim)
        return img_msg

    def compressed_imgmsg_to_cv2(self, cmprs_img_msg, desired_encoding='passthrough'):
        """
        Decode a sensor_msgs/CompressedImage (jpeg, png, ... and compressedDepth).

        'passthrough' returns the decoded image as OpenCV gives it (BGR order, or one channel
        for a mono image); any other encoding converts from there.
        """
        im, name = _decode_compressed(cmprs_img_msg)
        if desired_encoding in ('passthrough', '', name):
            return im
        return _convert(im, _ENCODINGS[name], _encoding(desired_encoding))

    def cv2_to_compressed_imgmsg(self, cvim, dst_format='jpg', header=None):
        """Compress a numpy image (BGR order) into a sensor_msgs/CompressedImage."""
        _array_encoding(cvim)
        fmt = str(dst_format).lstrip('.')
        try:
            ok, buf = cv2.imencode('.' + fmt, cvim)
        except cv2.error as exc:
            raise CvBridgeError('OpenCV cannot encode a %s %s image as %r: %s' % (
                cvim.shape, cvim.dtype, dst_format,
                str(exc).strip().splitlines()[-1])) from None
        if not ok:
            raise CvBridgeError('OpenCV could not encode the image as %r' % (dst_format,))
        msg = CompressedImage()
        if header is not None:
            msg.header = _copy_header(header)
        msg.format = fmt
        fill_message_data(msg, buf)
        return msg


def getCvType(encoding):
    """Return the OpenCV type number (e.g. cv2.CV_8UC3) of an image encoding."""
    return _encoding(encoding).cvtype


# --- display --------------------------------------------------------------------------


def _label_colors(count=64):
    """Return a BGR lookup table of well separated colours for label images."""
    hues = (np.arange(count) * 0.6180339887 % 1.0 * 180).astype(np.uint8)
    sat = np.where(np.arange(count) % 2, 200, 255).astype(np.uint8)
    val = np.where(np.arange(count) % 3 == 2, 180, 255).astype(np.uint8)
    hsv = np.stack([hues, sat, val], axis=1).reshape(1, count, 3)
    return cv2.cvtColor(hsv, cv2.COLOR_HSV2BGR).reshape(count, 3)


_LABEL_COLORS = _label_colors()
_DISPLAY_GUESS = {'8UC1': 'mono8', '8UC3': 'bgr8', '8UC4': 'bgra8',
                  '16UC1': 'mono16', '16UC3': 'bgr16', '16UC4': 'bgra16'}


def cvtColorForDisplay(source, encoding_in='', encoding_out='', do_dynamic_scaling=False,
                       min_image_value=0.0, max_image_value=0.0, colormap=-1, bg_label=-1):
    """
    Return an 8-bit image of ``source`` fit for display (bgr8 unless ``encoding_out`` says).

    ``encoding_in`` names the encoding of ``source`` (guessed from the array when empty).
    ``do_dynamic_scaling`` maps the image's finite min..max to 0..255; otherwise a
    ``min_image_value`` different from ``max_image_value`` maps that range (one-channel images
    only), through the OpenCV ``colormap`` when it is not -1 (NaN pixels are then black). A
    32SC1 image shown as bgr8 is a label image: one colour per label, black for ``bg_label``.
    Float and other non-colour images need scaling; without it a CvBridgeError says so.
    """
    src = _array_encoding(source) if not encoding_in else _encoding(encoding_in)
    got = _array_encoding(source)
    if got.cvtype_name != src.cvtype_name:
        raise CvBridgeError('cvtColorForDisplay: the image is %s but encoding_in [%s] needs %s'
                            % (got.name, src.name, src.cvtype_name))
    out = _encoding(encoding_out) if encoding_out else _ENCODINGS['bgr8']
    if out.family not in (_GRAY, _RGB, _BGR, _RGBA, _BGRA) or out.bits != 8:
        raise CvBridgeError('cvtColorForDisplay: the output encoding [%s] must be an 8-bit '
                            'color or mono encoding' % out.name)
    if src.family is None and src.cvtype_name == '32SC1' and out.name == 'bgr8':
        labels = source.astype(np.int64)
        result = _LABEL_COLORS[labels % len(_LABEL_COLORS)]
        result[labels == bg_label] = 0
        return result
    if do_dynamic_scaling:
        finite = source[np.isfinite(source)] if source.dtype.kind == 'f' else source
        if finite.size == 0 or finite.min() == finite.max():
            shape = source.shape[:2] if out.channels == 1 else source.shape[:2] + (out.channels,)
            return np.full(shape, 128, np.uint8)
        min_image_value, max_image_value = float(finite.min()), float(finite.max())
    if min_image_value != max_image_value:
        if src.channels != 1:
            raise CvBridgeError('cvtColorForDisplay: scaling is only supported for one-channel '
                                'images, [%s] has %d' % (src.name, src.channels))
        # Upstream's cv::Mat(image - min).convertTo(8-bit, 255 / (max - min)): the
        # expression is evaluated as cv::add(image, Scalar(-min)).
        shifted = _add_scalar(source, -float(min_image_value))
        scaled = _convert_to(shifted, np.uint8,
                             255.0 / (float(max_image_value) - float(min_image_value)))
        if colormap != -1:
            coloured = cv2.applyColorMap(scaled, colormap)
            if source.dtype.kind == 'f':
                # A NaN pixel has no value to colour: black, as upstream paints it.
                coloured[np.isnan(source.reshape(source.shape[:2]))] = 0
            return _convert(coloured, _ENCODINGS['bgr8'], out)
        return _convert(scaled, _ENCODINGS['mono8'], out)
    typed = src
    if src.family is None and src.cvtype_name in _DISPLAY_GUESS:
        typed = _ENCODINGS[_DISPLAY_GUESS[src.cvtype_name]]
    if typed.name == out.name:
        return source
    try:
        return _convert(source, typed, out)
    except CvBridgeError as exc:
        raise CvBridgeError('cvtColorForDisplay: cannot show a [%s] image as [%s] (%s); for '
                            'depth or float images pass do_dynamic_scaling=True or a '
                            'min_image_value/max_image_value range' % (src.name, out.name, exc)
                            ) from None
