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
Depth conversions of py_vision.cv_bridge against OpenCV's own cv::Mat::convertTo.

Upstream cv_bridge changes depth with ``convertTo(dst, depth, scale)``: 65535/255 from 8 to 16
bits, 255/65535 from 16 to 8, 1 otherwise; ``cvtColorForDisplay`` subtracts the minimum
(``cv::add`` with a scalar) and scales to 8 bits the same way.

OpenCV's Python module has no ``convertTo``: ``cv2.Mat`` is a plain ndarray subclass,
``cv2.UMat`` has no such method, and ``cv2.convertScaleAbs`` takes the absolute value. So the
reference is ``cv2.normalize`` with ``NORM_INF``, which OpenCV implements (4.6 and 5.0 alike) as
one ``src.convertTo(dst, dtype, alpha / norm(src), 0)`` call. Appending a calibration element
of known norm and choosing ``alpha`` so that ``alpha / norm`` is exactly the scale makes it
that very ``convertTo``. With an infinity in the image the norm is infinite, and with a NaN
OpenCV 4.6 may find a NaN norm; there (float sources, whose scale is always 1) the reference is
``cv2.add(src, -0.0, dtype=...)``, which converts each element with the same functions:
test_add_with_dtype_agrees_with_convert_to checks that on every depth pair. The expectations
are x86's: NaN, infinities and values beyond int32 become INT_MIN, which then saturates.

OpenCV converts a row shorter than two of its vectors one element at a time, and there a double
source is scaled in double (``src[j] * alpha``), where the vector code of any longer row
scales in float: the reference pads every row to ROW elements, so that it sees what an image of
a camera's size gets.
"""

import math
import platform

import cv2
from hypothesis import assume, given, HealthCheck, settings, strategies as st
from hypothesis.extra import numpy as hnp
import numpy as np
from py_vision.cv_bridge import CvBridge, cvtColorForDisplay
import pytest

BRIDGE = CvBridge()
SETTINGS = settings(max_examples=300, deadline=None,
                    suppress_health_check=[HealthCheck.too_slow])
DEPTHS = {'8U': np.uint8, '8S': np.int8, '16U': np.uint16, '16S': np.int16, '32S': np.int32,
          '32F': np.float32, '64F': np.float64}
CV_DEPTH = {name: getattr(cv2, 'CV_' + name) for name in DEPTHS}
BITS = {name: np.dtype(dtype).itemsize * 8 for name, dtype in DEPTHS.items()}
X86 = platform.machine().lower() in ('x86_64', 'amd64', 'i386', 'i686')
# Other CPUs round NaN and out-of-range floats differently, and the bridge follows x86 there.
x86_only = pytest.mark.skipif(not X86, reason='OpenCV on this CPU does not round as x86 does')

# Float values where rounding, saturation and the int32 range are decided.
FLOAT_EDGES = [0.5, 1.5, 2.5, -0.5, -1.5, 126.5, 127.5, 128.5, -128.5, -129.5, 254.5, 255.5,
               256.5, 32766.5, 32767.5, -32768.5, 65534.5, 65535.5, 2147483520.0, 2147483647.0,
               2147483647.5, 2147483648.0, -2147483648.0, -2147483648.5, -2147483904.0, 3e9,
               -3e9, 1e300, -1e300, 5e-324, -0.0, np.nan, np.inf, -np.inf]


# Elements in each row the reference converts: more than two of the widest vector (AVX-512's
# 16 floats), see the top.
ROW = 64
# Products of a pixel and a scale from here on are beyond int32 and float32 (see cv_convert_to).
HUGE_PRODUCT = 2.0 ** 1022


def as_floats(values, dtype):
    """Return values in a float dtype, the large ones overflowing to infinity as a cast does."""
    with np.errstate(over='ignore'):
        return np.array(values, np.float64).astype(dtype)


def upstream_scale(src, dst):
    """Return the scale upstream's toCvCopyImpl passes to convertTo for a depth change."""
    if BITS[src] == 8 and BITS[dst] == 16:
        return 65535.0 / 255.0
    if BITS[src] == 16 and BITS[dst] == 8:
        return 255.0 / 65535.0
    return 1.0


def calibration(flat, scale):
    """
    Return (element, alpha): an element whose magnitude is the norm, and alpha/norm == scale.

    Every product of an element of flat with scale must be below HUGE_PRODUCT.
    """
    if math.isinf(scale):
        return 1, scale  # inf / any norm is inf
    top = float(np.abs(flat.astype(np.float64)).max(initial=0.0))
    # A power of two: scale * 2**k is exact, so alpha / norm gives the scale back. At least 1
    # (normalize takes a norm below DBL_EPSILON for 0) and at least the one that makes alpha 1
    # or more (a subnormal alpha is inexact). Below 2 * max(top, 1, 1 / scale), alpha stays
    # under 2 * HUGE_PRODUCT: finite.
    power = 2 ** max(math.ceil(math.log2(max(top, 1.0))), math.ceil(-math.log2(scale)), 0)
    if flat.dtype.kind == 'f':
        candidates = [power] if flat.dtype.type(power) == power else [top]
    else:
        info = np.iinfo(flat.dtype)
        # Signed types reach one further below zero (but OpenCV 4.6's norm overflows on INT_MIN).
        sign = -1 if info.min < 0 and info.bits < 32 else 1
        largest = abs(info.min) if sign < 0 else info.max
        # Each of these is below 2 * max(top, 1, 1 / scale) when the power of two is too large.
        candidates = [sign * m for m in [power] if m <= largest] or (
            sign * m for m in range(largest, math.ceil(top) - 1, -1))
    for element in candidates:
        alpha = scale * abs(element)
        for _ in range(4):
            if alpha / abs(element) == scale:
                return element, alpha
            alpha = math.nextafter(alpha, math.inf)
    raise AssertionError('no calibration element for scale %r over %r' % (scale, flat.dtype))


def as_row(src, *extra):
    """Return src's elements, then extra, in one row of at least ROW elements (padded with 0)."""
    flat = np.append(src.ravel(), np.array(extra, src.dtype))
    return np.append(flat, np.zeros(max(0, ROW - flat.size), src.dtype)).reshape(1, -1)


def cv_convert_to(src, depth, scale=1.0):
    """Return what cv::Mat::convertTo(dst, CV_<depth>, scale) gives for src (see the top)."""
    flat = np.ascontiguousarray(src).reshape(1, -1)
    if flat.dtype.kind == 'f' and not np.isfinite(flat).all():
        assert scale == 1.0
        row = as_row(flat)
        out = cv2.add(row, np.full_like(row, -0.0), dtype=CV_DEPTH[depth])
        return out[0, :src.size].reshape(src.shape)
    if scale == 1.0:
        # alpha / norm is 1 whatever norm OpenCV finds (OpenCV 4.6 gets INT_MIN's wrong).
        row = as_row(flat, 1)
        alpha = cv2.norm(row, cv2.NORM_INF)
    else:
        assert scale > 0
        with np.errstate(over='ignore', invalid='ignore'):
            products = flat.astype(np.float64) * scale
        huge = np.abs(products) >= HUGE_PRODUCT
        if huge.any():
            # No finite alpha makes these a normalize: their product is beyond int32 and
            # float32 whatever OpenCV's work type, so they convert as the product itself does.
            out = np.empty(flat.shape, DEPTHS[depth])
            out[huge] = cv_convert_to(products[huge], depth)
            out[~huge] = cv_convert_to(flat[~huge], depth, scale)
            return out.reshape(src.shape)
        element, alpha = calibration(flat, scale)
        row = as_row(flat, element)
        assert cv2.norm(row, cv2.NORM_INF) == abs(element)
    out = cv2.normalize(row, None, alpha, 0, cv2.NORM_INF, CV_DEPTH[depth])
    return out[0, :src.size].reshape(src.shape)


def assert_same(got, expected):
    assert got.dtype == expected.dtype and got.shape == expected.shape
    # NaN equals NaN here: a NaN pixel must stay NaN.
    np.testing.assert_array_equal(got, expected)


def values(dtype):
    """Elements of any value of a depth, floats with their edge cases and specials."""
    dtype = np.dtype(dtype)
    if dtype.kind == 'f':
        return st.one_of(st.sampled_from(as_floats(FLOAT_EDGES, dtype).tolist()),
                         st.floats(width=dtype.itemsize * 8, allow_subnormal=True),
                         st.floats(-70000, 70000, width=dtype.itemsize * 8))
    return st.integers(np.iinfo(dtype).min, np.iinfo(dtype).max)


@st.composite
def depth_images(draw, depth, max_channels=5):
    dtype = np.dtype(DEPTHS[depth])
    channels = draw(st.integers(1, max_channels))
    shape = (draw(st.integers(1, 6)), draw(st.integers(1, 9)))
    if channels > 1:
        shape += (channels,)
    return draw(hnp.arrays(dtype, shape, elements=values(dtype)))


def convert(im, src, dst, channels):
    msg = BRIDGE.cv2_to_imgmsg(im)
    assert msg.encoding == '%sC%d' % (src, channels)
    return BRIDGE.imgmsg_to_cv2(msg, '%sC%d' % (dst, channels))


# --- the reference itself -----------------------------------------------------------------


@pytest.mark.parametrize('dst', sorted(DEPTHS))
@pytest.mark.parametrize('src', sorted(DEPTHS))
def test_add_with_dtype_agrees_with_convert_to(src, dst):
    dtype = np.dtype(DEPTHS[src])
    rng = np.random.default_rng(BITS[src] + BITS[dst])
    if dtype.kind == 'f':
        finite = [v for v in FLOAT_EDGES if np.isfinite(v)]
        im = as_floats(np.concatenate([
            rng.normal(0, 1, 500) * 10.0 ** rng.integers(-3, 12, 500), finite]), dtype)
    else:
        info = np.iinfo(dtype)
        im = rng.integers(info.min, info.max, 600, dtype=dtype, endpoint=True)
    im = im.reshape(1, -1)
    added = cv2.add(im, np.full_like(im, -0.0), dtype=CV_DEPTH[dst])
    assert_same(added, cv_convert_to(im, dst))


# --- every depth pair through the bridge ----------------------------------------------------


@x86_only
@SETTINGS
@given(st.sampled_from(sorted(DEPTHS)), st.sampled_from(sorted(DEPTHS)), st.data())
def test_every_depth_pair_converts_as_opencv(src, dst, data):
    im = data.draw(depth_images(src))
    channels = 1 if im.ndim == 2 else im.shape[2]
    out = convert(im, src, dst, channels)
    assert_same(out, cv_convert_to(im, dst, upstream_scale(src, dst)))


@x86_only
@pytest.mark.parametrize('dst', sorted(DEPTHS))
@pytest.mark.parametrize('src', ['32F', '64F'])
def test_float_edges_convert_as_opencv(src, dst):
    im = as_floats(FLOAT_EDGES * 2, DEPTHS[src]).reshape(2, -1)
    assert_same(convert(im, src, dst, 1), cv_convert_to(im, dst))


@pytest.mark.parametrize('src', ['8U', '8S', '16U', '16S'])
def test_every_8_and_16_bit_value_scales_as_opencv(src):
    info = np.iinfo(DEPTHS[src])
    im = np.arange(info.min, info.max + 1, dtype=DEPTHS[src]).reshape(-1, 256)
    for dst in ('8U', '8S', '16U', '16S'):
        assert_same(convert(im, src, dst, 1), cv_convert_to(im, dst, upstream_scale(src, dst)))


@pytest.mark.parametrize('encoding,channels', [
    ('mono16', 1), ('rgb16', 3), ('bgra16', 4), ('bayer_grbg16', 1), ('mono8', 1),
    ('rgb8', 3), ('bayer_rggb8', 1)])
@pytest.mark.parametrize('dst', ['8S', '8U', '16S', '16U'])
def test_named_encodings_to_generic_depths(encoding, channels, dst):
    dtype, _ = BRIDGE.encoding_to_dtype_with_channels(encoding)
    info = np.iinfo(dtype)
    shape = (16, 32) if channels == 1 else (16, 32, channels)
    im = np.random.default_rng(channels).integers(info.min, info.max, shape, dtype, endpoint=True)
    out = BRIDGE.imgmsg_to_cv2(BRIDGE.cv2_to_imgmsg(im, encoding), '%sC%d' % (dst, channels))
    src = '%dU' % (info.bits,)
    assert_same(out, cv_convert_to(im, dst, upstream_scale(src, dst)))


# --- cvtColorForDisplay's scaling -----------------------------------------------------------


@st.composite
def display_cases(draw):
    """Draw a one-channel image of any depth and a min < max range to show it with."""
    depth = draw(st.sampled_from(sorted(DEPTHS)))
    dtype = np.dtype(DEPTHS[depth])
    if dtype.kind == 'f':
        elements = st.floats(-1e6, 1e6, width=dtype.itemsize * 8)
        bound = st.floats(-1e6, 1e6)
    else:
        # In 32S, image - min stays away from INT_MIN, on which OpenCV 4.6's norm (the
        # reference's calibration) overflows.
        smallest, largest = max(np.iinfo(dtype).min, -2 ** 29), min(np.iinfo(dtype).max, 2 ** 29)
        elements = st.integers(smallest, largest)
        bound = st.one_of(st.integers(smallest, largest), st.floats(smallest, largest))
    im = draw(hnp.arrays(dtype, (draw(st.integers(1, 6)), draw(st.integers(1, 9))),
                         elements=elements))
    low, high = draw(bound), draw(bound)
    assume(low < high)
    return depth, im, float(low), float(high)


def cv_add_scalar(im, value):
    """Return cv2.add(im, value) with value taken as a scalar, in the image's type."""
    # A (1, n > 4) row: OpenCV cannot mistake a Python number for an array of its size.
    flat = np.append(im.ravel(), np.zeros(5, im.dtype)).reshape(1, -1)
    return cv2.add(flat, value)[0, :im.size].reshape(im.shape)


@SETTINGS
@given(display_cases())
def test_display_scaling_converts_as_opencv(case):
    depth, im, low, high = case
    # Upstream: cv::Mat(image - min).convertTo(CV_8U, 255 / (max - min)), where OpenCV
    # evaluates image - min as cv::add(image, Scalar(-min)).
    expected = cv_convert_to(cv_add_scalar(im, -low), '8U', 255.0 / (high - low))
    out = cvtColorForDisplay(im, '%sC1' % depth, 'mono8', False, low, high)
    assert_same(out, expected)


def test_display_nan_is_black_with_a_colormap():
    depth = np.linspace(0.5, 4.5, 6 * 8, dtype=np.float32).reshape(6, 8)
    depth[2, 3] = depth[0, 0] = np.nan
    for dtype, encoding in ((np.float32, '32FC1'), (np.float64, '64FC1')):
        image = depth.astype(dtype)
        out = cvtColorForDisplay(image, encoding, 'bgr8', True, colormap=cv2.COLORMAP_JET)
        assert (out[np.isnan(image)] == 0).all()
        # Every other pixel has its colour from the map, none black.
        assert (out[~np.isnan(image)].max(axis=1) > 0).all()
        scaled = cvtColorForDisplay(image, encoding, 'mono8', True)
        np.testing.assert_array_equal(
            out[~np.isnan(image)],
            cv2.applyColorMap(scaled, cv2.COLORMAP_JET)[~np.isnan(image)])
