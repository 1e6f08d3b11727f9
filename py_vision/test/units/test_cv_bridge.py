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


"""py_vision.cv_bridge: encodings, conversions, message layouts, compressed images, bad input."""

import array

import cv2
import numpy as np
from py_vision.cv_bridge import CvBridge, CvBridgeError, cvtColorForDisplay, getCvType
import pytest
from sensor_msgs.msg import CompressedImage, Image
from std_msgs.msg import Header

BRIDGE = CvBridge()

# The specification, written out: encoding -> (numpy dtype, channels, colour family).
PLAIN = {'mono8': ('uint8', 1, 'gray'), 'mono16': ('uint16', 1, 'gray'),
         'rgb8': ('uint8', 3, 'rgb'), 'rgb16': ('uint16', 3, 'rgb'),
         'bgr8': ('uint8', 3, 'bgr'), 'bgr16': ('uint16', 3, 'bgr'),
         'rgba8': ('uint8', 4, 'rgba'), 'rgba16': ('uint16', 4, 'rgba'),
         'bgra8': ('uint8', 4, 'bgra'), 'bgra16': ('uint16', 4, 'bgra')}
BAYER = {'bayer_%s%d' % (p, b): ('uint%d' % b, 1, 'bayer_' + p)
         for p in ('rggb', 'bggr', 'gbrg', 'grbg') for b in (8, 16)}
YUV = {'yuv422': ('uint8', 2, 'uyvy'), 'uyvy': ('uint8', 2, 'uyvy'),
       'yuv422_yuy2': ('uint8', 2, 'yuy2'), 'yuyv': ('uint8', 2, 'yuy2')}
DEPTHS = {'8U': 'uint8', '8S': 'int8', '16U': 'uint16', '16S': 'int16', '32S': 'int32',
          '32F': 'float32', '64F': 'float64'}
GENERIC = {'%sC%d' % (d, c): (t, c, None) for d, t in DEPTHS.items() for c in (1, 2, 3, 4)}
ALL = {**PLAIN, **BAYER, **YUV, **GENERIC}


def cv_type_name(encoding):
    dtype, channels, _ = ALL[encoding]
    depth = {v: k for k, v in DEPTHS.items()}[dtype]
    return '%sC%d' % (depth, channels)


def allowed(src, dst):
    """Whether cv_bridge converts src to dst (its getConversionCode rules)."""
    if src == dst:
        return True
    s_dtype, s_ch, s_fam = ALL[src]
    d_dtype, d_ch, d_fam = ALL[dst]
    if s_fam is None:
        return d_fam is None and s_ch == d_ch
    if d_fam is None:
        return s_ch == d_ch
    if dst in PLAIN:
        return True
    # To Bayer or YUV only from the same YUV layout (an alias).
    return dst in YUV and s_fam == d_fam


def random_image(encoding, height=6, width=8, seed=0):
    dtype, channels, _ = ALL[encoding]
    rng = np.random.default_rng(seed)
    shape = (height, width) if channels == 1 else (height, width, channels)
    if np.dtype(dtype).kind == 'f':
        return rng.normal(0, 1000, shape).astype(dtype)
    info = np.iinfo(dtype)
    return rng.integers(info.min, info.max, shape, dtype=dtype, endpoint=True)


def make_msg(im, encoding, pad=0, bigendian=False, kind='array'):
    """Build an Image by hand (not with the bridge), with `pad` garbage bytes per row."""
    height, width = im.shape[:2]
    dtype = im.dtype.newbyteorder('>' if bigendian else '<')
    rows = np.ascontiguousarray(im, dtype=dtype).view(np.uint8).reshape(height, -1)
    padded = np.full((height, rows.shape[1] + pad), 0xEE, np.uint8)
    padded[:, :rows.shape[1]] = rows
    raw = padded.tobytes()
    msg = Image(height=height, width=width, encoding=encoding, step=padded.shape[1],
                is_bigendian=bigendian)
    msg.data = array.array('B', raw)
    if kind != 'array':
        # Bypass the message's field check, as a Humble or hand-built message can.
        msg._data = {'bytes': raw, 'bytearray': bytearray(raw), 'list': list(raw),
                     'memoryview': memoryview(raw), 'numpy': np.frombuffer(raw, np.uint8)}[kind]
    return msg


# --- the encoding table ---------------------------------------------------------------


def test_bridge_error_is_a_type_error():
    assert issubclass(CvBridgeError, TypeError)


@pytest.mark.parametrize('encoding', sorted(ALL))
def test_every_encoding_has_its_opencv_type(encoding):
    dtype, channels, _ = ALL[encoding]
    expected = getattr(cv2, 'CV_' + cv_type_name(encoding))
    assert getCvType(encoding) == expected
    assert BRIDGE.encoding_to_cvtype2(encoding) == expected
    assert BRIDGE.encoding_to_dtype_with_channels(encoding) == (dtype, channels)
    assert BRIDGE.cvtype2_to_dtype_with_channels(expected) == (dtype, channels)
    assert BRIDGE.dtype_with_channels_to_cvtype2(np.dtype(dtype), channels) == \
        cv_type_name(encoding)


@pytest.mark.parametrize('channels', [1, 2, 3, 4, 5, 6, 7, 8, 100, 512])
@pytest.mark.parametrize('depth', sorted(DEPTHS))
def test_any_channel_count_has_its_opencv_type(depth, channels):
    name = '%sC%d' % (depth, channels)
    # OpenCV's own type number: CV_MAKETYPE, written out from its constants (OpenCV 4's Python
    # module has no CV_MAKETYPE, and OpenCV 5 moved the channel bits).
    shift = (cv2.CV_8UC2 - cv2.CV_8UC1).bit_length() - 1
    expected = getattr(cv2, 'CV_' + depth) + ((channels - 1) << shift)
    if hasattr(cv2, 'CV_MAKETYPE'):
        assert cv2.CV_MAKETYPE(getattr(cv2, 'CV_' + depth), channels) == expected
    assert getCvType(name) == expected
    assert BRIDGE.encoding_to_dtype_with_channels(name) == (DEPTHS[depth], channels)
    assert BRIDGE.cvtype2_to_dtype_with_channels(expected) == (DEPTHS[depth], channels)
    assert BRIDGE.dtype_with_channels_to_cvtype2(np.dtype(DEPTHS[depth]), channels) == name


@pytest.mark.parametrize('depth', sorted(DEPTHS))
def test_bare_depth_is_one_channel(depth):
    assert getCvType(depth) == getattr(cv2, 'CV_%sC1' % depth)
    assert BRIDGE.encoding_to_dtype_with_channels(depth) == (DEPTHS[depth], 1)
    im = random_image('%sC1' % depth)
    msg = BRIDGE.cv2_to_imgmsg(im, depth)
    assert msg.encoding == depth and msg.step == 8 * im.itemsize
    np.testing.assert_array_equal(BRIDGE.imgmsg_to_cv2(msg), im)
    np.testing.assert_array_equal(BRIDGE.imgmsg_to_cv2(msg, '%sC1' % depth), im)
    with pytest.raises(CvBridgeError, match='incompatible type'):
        BRIDGE.cv2_to_imgmsg(np.dstack([im, im]), depth)


@pytest.mark.parametrize('channels', [5, 6, 7, 8, 33, 512])
def test_many_channels_round_trip_and_convert(channels):
    im = np.random.default_rng(channels).integers(0, 65536, (6, 7, channels), np.uint16)
    msg = BRIDGE.cv2_to_imgmsg(im)
    assert msg.encoding == '16UC%d' % channels and msg.step == 7 * channels * 2
    np.testing.assert_array_equal(BRIDGE.imgmsg_to_cv2(msg), im)
    padded = make_msg(im, '16UC%d' % channels, pad=6, bigendian=True)
    np.testing.assert_array_equal(BRIDGE.imgmsg_to_cv2(padded), im)
    narrow = BRIDGE.imgmsg_to_cv2(msg, '8UC%d' % channels)
    np.testing.assert_array_equal(narrow, np.round(im / 257.0).astype(np.uint8))
    floats = BRIDGE.imgmsg_to_cv2(msg, '32FC%d' % channels)
    np.testing.assert_array_equal(floats, im.astype(np.float32))
    with pytest.raises(CvBridgeError, match='same number of channels'):
        BRIDGE.imgmsg_to_cv2(msg, '8UC%d' % (channels - 1))
    with pytest.raises(CvBridgeError, match='not a color format'):
        BRIDGE.imgmsg_to_cv2(msg, 'bgr8')


@pytest.mark.parametrize('encoding', ['', 'BGR8', 'bgr 8', '16FC1', 'nv12', None, '8UC0',
                                      '8UC513', '8UC', '8uc3', '8UC03', ' 8UC3', '8UC3 ',
                                      '8UC-1', 'C3', '8'])
def test_unknown_encoding_is_named_in_the_error(encoding):
    with pytest.raises(CvBridgeError, match='Unrecognized image encoding'):
        getCvType(encoding)
    with pytest.raises(CvBridgeError):
        BRIDGE.imgmsg_to_cv2(make_msg(random_image('bgr8'), 'bgr8'), encoding or 'x')


def test_helpers_reject_what_has_no_type():
    with pytest.raises(CvBridgeError):
        BRIDGE.dtype_with_channels_to_cvtype2(np.dtype('int64'), 1)
    for channels in (0, 513, 2.0, '3'):
        with pytest.raises(CvBridgeError):
            BRIDGE.dtype_with_channels_to_cvtype2(np.dtype('uint8'), channels)
    shift = (cv2.CV_8UC2 - cv2.CV_8UC1).bit_length() - 1
    for cvtype in (-5, 512 << shift, 7, 'CV_8UC1', None):
        with pytest.raises(CvBridgeError):
            BRIDGE.cvtype2_to_dtype_with_channels(cvtype)


# --- round trips and layouts ----------------------------------------------------------


@pytest.mark.parametrize('encoding', sorted(ALL))
def test_round_trip_every_encoding(encoding):
    im = random_image(encoding, seed=len(encoding))
    msg = BRIDGE.cv2_to_imgmsg(im, encoding)
    dtype, channels, _ = ALL[encoding]
    assert (msg.height, msg.width, msg.encoding) == (6, 8, encoding)
    assert msg.step == 8 * channels * np.dtype(dtype).itemsize
    assert len(msg.data) == msg.step * msg.height and not msg.is_bigendian
    back = BRIDGE.imgmsg_to_cv2(msg)
    assert back.dtype == im.dtype and back.shape == im.shape
    np.testing.assert_array_equal(back, im)
    np.testing.assert_array_equal(BRIDGE.imgmsg_to_cv2(msg, encoding), im)


@pytest.mark.parametrize('encoding', sorted(GENERIC))
def test_passthrough_encoding_is_the_opencv_type(encoding):
    im = random_image(encoding)
    assert BRIDGE.cv2_to_imgmsg(im).encoding == encoding


def test_one_channel_third_axis_is_mono():
    im = random_image('mono8')[:, :, None]
    msg = BRIDGE.cv2_to_imgmsg(im, 'mono8')
    np.testing.assert_array_equal(BRIDGE.imgmsg_to_cv2(msg), im[:, :, 0])


@pytest.mark.parametrize('encoding', ['mono8', 'bgr8', 'rgba16', 'bayer_gbrg16', 'yuv422',
                                      '32FC1', '64FC3', '16SC2'])
@pytest.mark.parametrize('pad', [1, 3, 8, 64])
def test_padded_rows(encoding, pad):
    itemsize = np.dtype(ALL[encoding][0]).itemsize
    pad = pad * itemsize
    im = random_image(encoding, 5, 7)
    msg = make_msg(im, encoding, pad=pad)
    out = BRIDGE.imgmsg_to_cv2(msg)
    np.testing.assert_array_equal(out, im)
    assert np.shares_memory(out, np.frombuffer(msg.data, np.uint8))
    if encoding in PLAIN:
        np.testing.assert_array_equal(BRIDGE.imgmsg_to_cv2(msg, 'bgr8'),
                                      BRIDGE.imgmsg_to_cv2(make_msg(im, encoding), 'bgr8'))


@pytest.mark.parametrize('encoding', ['mono16', 'bgr16', 'rgba16', 'bayer_rggb16', '16SC3',
                                      '32SC1', '32FC2', '64FC4', 'bgr8', '8SC2'])
def test_big_endian_message_gives_native_values(encoding):
    im = random_image(encoding)
    msg = make_msg(im, encoding, pad=4 * np.dtype(im.dtype).itemsize, bigendian=True)
    out = BRIDGE.imgmsg_to_cv2(msg)
    assert out.dtype.isnative and out.dtype == im.dtype
    np.testing.assert_array_equal(out, im)
    if encoding in ('mono16', 'bgr16'):
        np.testing.assert_array_equal(BRIDGE.imgmsg_to_cv2(msg, 'bgr8'),
                                      BRIDGE.imgmsg_to_cv2(make_msg(im, encoding), 'bgr8'))


def test_big_endian_array_sets_the_flag():
    im = random_image('mono16')
    msg = BRIDGE.cv2_to_imgmsg(im.astype('>u2'), 'mono16')
    assert msg.is_bigendian
    assert bytes(msg.data) == im.astype('>u2').tobytes()
    np.testing.assert_array_equal(BRIDGE.imgmsg_to_cv2(msg), im)


@pytest.mark.parametrize('make', [
    lambda im: im[::2, ::3], lambda im: im[1:-1, 2:-1], lambda im: np.asfortranarray(im),
    lambda im: im[:, :, ::-1], lambda im: im.transpose(1, 0, 2)], ids=[
    'strided', 'crop', 'fortran', 'reversed-channels', 'transposed'])
@pytest.mark.parametrize('encoding', ['bgr8', '16UC3', '32FC3'])
def test_non_contiguous_arrays_in(make, encoding):
    view = make(random_image(encoding, 12, 10))
    msg = BRIDGE.cv2_to_imgmsg(view, encoding)
    assert (msg.height, msg.width) == view.shape[:2]
    np.testing.assert_array_equal(BRIDGE.imgmsg_to_cv2(msg), view)


def test_header_is_copied():
    header = Header(frame_id='usb_camera')
    header.stamp.sec, header.stamp.nanosec = 12, 345
    msg = BRIDGE.cv2_to_imgmsg(random_image('bgr8'), 'bgr8', header=header)
    assert msg.header == header
    header.frame_id = 'changed'
    assert msg.header.frame_id == 'usb_camera'
    assert BRIDGE.cv2_to_imgmsg(random_image('bgr8')).header == Header()


def test_message_data_is_an_array_of_bytes():
    msg = BRIDGE.cv2_to_imgmsg(random_image('bgr8'), 'bgr8')
    assert isinstance(msg.data, array.array) and msg.data.typecode == 'B'


# --- no copy, and writable results ------------------------------------------------------


@pytest.mark.parametrize('desired', ['passthrough', 'bgr8'])
def test_same_encoding_is_a_writable_view(desired):
    msg = BRIDGE.cv2_to_imgmsg(random_image('bgr8', 120, 160), 'bgr8')
    out = BRIDGE.imgmsg_to_cv2(msg, desired)
    assert np.shares_memory(out, np.frombuffer(msg.data, np.uint8))
    cv2.circle(out, (60, 60), 30, (0, 0, 255), -1)
    np.testing.assert_array_equal(BRIDGE.imgmsg_to_cv2(msg)[60, 60], [0, 0, 255])


@pytest.mark.parametrize('src,dst', [('mono8', '8UC1'), ('8U', '8UC1'), ('yuv422', 'uyvy'),
                                     ('bgra16', '16UC4')])
def test_renaming_without_changing_pixels_is_a_view(src, dst):
    msg = BRIDGE.cv2_to_imgmsg(random_image(src if src in ALL else src + 'C1', 10, 12), src)
    out = BRIDGE.imgmsg_to_cv2(msg, dst)
    assert np.shares_memory(out, np.frombuffer(msg.data, np.uint8))
    np.testing.assert_array_equal(out, BRIDGE.imgmsg_to_cv2(msg))


@pytest.mark.parametrize('kind', ['bytes', 'bytearray', 'list', 'memoryview', 'numpy'])
@pytest.mark.parametrize('encoding', ['bgr8', 'mono16', '32FC1'])
def test_other_data_containers(kind, encoding):
    im = random_image(encoding, 70, 80)
    msg = make_msg(im, encoding, pad=8, kind=kind)
    out = BRIDGE.imgmsg_to_cv2(msg)
    np.testing.assert_array_equal(out, im)
    assert out.flags.writeable
    if encoding == 'bgr8':
        # cv_bridge_test draws straight on the converted image, whatever held the data.
        cv2.circle(BRIDGE.imgmsg_to_cv2(msg, 'bgr8'), (60, 60), 30, (0, 0, 255), -1)


@pytest.mark.parametrize('kind', ['bytes', 'memoryview'])
def test_read_only_data_is_copied_not_modified(kind):
    im = random_image('bgr8')
    msg = make_msg(im, 'bgr8', kind=kind)
    out = BRIDGE.imgmsg_to_cv2(msg, 'bgr8')
    out[...] = 0
    np.testing.assert_array_equal(BRIDGE.imgmsg_to_cv2(msg), im)


# --- conversions --------------------------------------------------------------------------


@pytest.mark.parametrize('src', sorted(ALL))
def test_every_encoding_pair(src):
    msg = BRIDGE.cv2_to_imgmsg(random_image(src, 4, 6), src)
    for dst in sorted(ALL):
        if allowed(src, dst):
            out = BRIDGE.imgmsg_to_cv2(msg, dst)
            dtype, channels, _ = ALL[dst]
            expected_shape = (4, 6) if channels == 1 else (4, 6, channels)
            assert (out.dtype, out.shape) == (np.dtype(dtype), expected_shape), (src, dst)
        else:
            with pytest.raises(CvBridgeError, match=r'\[%s\].*\[%s\]' % (src, dst)):
                BRIDGE.imgmsg_to_cv2(msg, dst)


B, G, R = 10, 200, 77


def test_colour_order_and_alpha():
    bgr = np.zeros((3, 4, 3), np.uint8)
    bgr[...] = (B, G, R)
    msg = BRIDGE.cv2_to_imgmsg(bgr, 'bgr8')
    assert tuple(BRIDGE.imgmsg_to_cv2(msg, 'rgb8')[1, 2]) == (R, G, B)
    assert tuple(BRIDGE.imgmsg_to_cv2(msg, 'bgra8')[1, 2]) == (B, G, R, 255)
    assert tuple(BRIDGE.imgmsg_to_cv2(msg, 'rgba8')[1, 2]) == (R, G, B, 255)
    rgba = BRIDGE.cv2_to_imgmsg(np.dstack([bgr[:, :, ::-1], np.full((3, 4), 9, np.uint8)]),
                                'rgba8')
    assert tuple(BRIDGE.imgmsg_to_cv2(rgba, 'bgr8')[0, 0]) == (B, G, R)


def test_colour_to_mono_and_back():
    bgr = np.zeros((3, 4, 3), np.uint8)
    bgr[...] = (B, G, R)
    mono = BRIDGE.imgmsg_to_cv2(BRIDGE.cv2_to_imgmsg(bgr, 'bgr8'), 'mono8')
    assert mono.shape == (3, 4)
    assert abs(int(mono[0, 0]) - (0.114 * B + 0.587 * G + 0.299 * R)) <= 1
    grey = BRIDGE.imgmsg_to_cv2(BRIDGE.cv2_to_imgmsg(mono, 'mono8'), 'bgr8')
    assert (grey == mono[:, :, None]).all()


def test_8_and_16_bit_scaling():
    values = np.arange(256, dtype=np.uint8).reshape(16, 16)
    wide = BRIDGE.imgmsg_to_cv2(BRIDGE.cv2_to_imgmsg(values, 'mono8'), 'mono16')
    np.testing.assert_array_equal(wide, values.astype(np.uint16) * 257)
    deep = np.arange(0, 65536, 7, dtype=np.uint16)[:9360].reshape(90, 104)
    narrow = BRIDGE.imgmsg_to_cv2(BRIDGE.cv2_to_imgmsg(deep, 'mono16'), 'mono8')
    np.testing.assert_array_equal(narrow, np.round(deep / 257.0).astype(np.uint8))
    rgb16 = BRIDGE.imgmsg_to_cv2(BRIDGE.cv2_to_imgmsg(random_image('bgr8'), 'bgr8'), 'rgb16')
    np.testing.assert_array_equal(rgb16, random_image('bgr8')[:, :, ::-1].astype(np.int64) * 257)


def test_generic_types_convert_without_colour():
    floats = np.array([[-3.6, 0.5, 1.5, 254.5, 300.0, np.nan]], np.float32)
    out = BRIDGE.imgmsg_to_cv2(BRIDGE.cv2_to_imgmsg(floats), '8UC1')
    np.testing.assert_array_equal(out, [[0, 0, 2, 254, 255, 0]])
    assert out.dtype == np.uint8
    bgr = random_image('bgr8')
    np.testing.assert_array_equal(
        BRIDGE.imgmsg_to_cv2(BRIDGE.cv2_to_imgmsg(bgr, 'bgr8'), '32FC3'), bgr.astype(np.float32))


@pytest.mark.parametrize('pattern,code', [('rggb', 'BayerBG'), ('bggr', 'BayerRG'),
                                          ('gbrg', 'BayerGR'), ('grbg', 'BayerGB')])
@pytest.mark.parametrize('bits', [8, 16])
def test_bayer_demosaicing(pattern, code, bits):
    # A flat colour seen through the pattern must come back as that colour.
    colour = {'r': 200, 'g': 120, 'b': 40}
    mosaic = np.zeros((8, 8), np.uint8)
    for dy in (0, 1):
        for dx in (0, 1):
            mosaic[dy::2, dx::2] = colour[pattern[2 * dy + dx]]
    if bits == 16:
        mosaic = mosaic.astype(np.uint16) * 257
    msg = BRIDGE.cv2_to_imgmsg(mosaic, 'bayer_%s%d' % (pattern, bits))
    bgr = BRIDGE.imgmsg_to_cv2(msg, 'bgr8')
    np.testing.assert_array_equal(bgr[2:6, 2:6], np.broadcast_to([40, 120, 200], (4, 4, 3)))
    rgb = BRIDGE.imgmsg_to_cv2(msg, 'rgb%d' % bits)
    np.testing.assert_array_equal(
        rgb, cv2.cvtColor(mosaic, getattr(cv2, 'COLOR_%s2RGB' % code)))


@pytest.mark.parametrize('encoding,code', [('yuv422', 'UYVY'), ('yuv422_yuy2', 'YUY2')])
def test_yuv422_to_colour(encoding, code):
    packed = random_image(encoding, 6, 8)
    msg = BRIDGE.cv2_to_imgmsg(packed, encoding)
    for dst in ('bgr8', 'rgb8', 'mono8', 'bgra8'):
        expected = cv2.cvtColor(packed, getattr(cv2, 'COLOR_YUV2%s_%s' % (
            {'mono8': 'GRAY'}.get(dst, dst[:-1].upper()), code)))
        np.testing.assert_array_equal(BRIDGE.imgmsg_to_cv2(msg, dst), expected)
    # Mid grey has Y = U = V = 128 in both layouts.
    grey = BRIDGE.cv2_to_imgmsg(np.full((2, 4, 2), 128, np.uint8), encoding)
    assert abs(int(BRIDGE.imgmsg_to_cv2(grey, 'bgr8').astype(int).mean()) - 128) <= 2


@pytest.mark.parametrize('encoding', ['nv21', 'nv24'])
def test_semi_planar_yuv_a_camera_sends(encoding):
    # What a camera sends in the V4L2 formats NV21 and NV24, as py_vision's native output.
    from py_vision.capture.pixel_formats import find
    from py_vision.capture.synthetic_picture import synthetic_frame, synthetic_yuyv
    layout = find(encoding.upper())
    planes = np.ascontiguousarray(layout.from_yuyv(synthetic_yuyv(4, 64, 48))).reshape(-1)
    array = planes.view(np.uint8).reshape(-1, 64)
    msg = BRIDGE.cv2_to_imgmsg(array, encoding)
    # The message is the picture's size; its data the planes, rows of `step` bytes.
    assert (msg.height, msg.width, msg.step, len(msg.data)) == (48, 64, 64, planes.size)
    assert np.array_equal(BRIDGE.imgmsg_to_cv2(msg), array)
    for dst in ('bgr8', 'rgb8', 'mono8', 'bgra8', 'mono16'):
        assert np.array_equal(BRIDGE.imgmsg_to_cv2(msg, dst),
                              layout.convert(array, dst) if dst != 'bgra8' else cv2.cvtColor(
                                  layout.convert(array, 'bgr8'), cv2.COLOR_BGR2BGRA))
    bgr = BRIDGE.imgmsg_to_cv2(msg, 'bgr8')
    assert np.abs(bgr.astype(int) - synthetic_frame(4, 64, 48)).mean() < 2.0
    assert np.array_equal(cvtColorForDisplay(array, encoding), bgr)
    with pytest.raises(CvBridgeError, match='even width and height'):
        BRIDGE.cv2_to_imgmsg(np.zeros((21, 63), np.uint8), encoding)
    if encoding == 'nv21':
        with pytest.raises(CvBridgeError, match='22 rows is not a picture'):
            BRIDGE.cv2_to_imgmsg(np.zeros((22, 64), np.uint8), encoding)
    short = BRIDGE.cv2_to_imgmsg(array, encoding)
    short.data = short.data[:-64]
    with pytest.raises(CvBridgeError, match='wrongly formed'):
        BRIDGE.imgmsg_to_cv2(short)


def test_a_shared_message_holds_the_arrays_own_bytes_and_serializes():
    # What ImagePublisher publishes: no copy of a frame until rclpy's own, at publish.
    from rclpy.serialization import deserialize_message, serialize_message
    image = random_image('bgr8', 6, 8)
    msg = BRIDGE.cv2_to_imgmsg(image, 'bgr8', share=True)
    image[0, 0, 0] = 7
    assert bytes(msg.data)[0] == 7 and (msg.height, msg.width, msg.step) == (6, 8, 24)
    back = deserialize_message(serialize_message(msg), Image)
    assert np.array_equal(BRIDGE.imgmsg_to_cv2(back), image)
    copied = BRIDGE.cv2_to_imgmsg(image, 'bgr8')
    image[0, 0, 0] = 9
    assert bytes(copied.data)[0] == 7


# --- bad input ------------------------------------------------------------------------------


def good_msg():
    return make_msg(random_image('bgr8'), 'bgr8')


def with_fields(**fields):
    msg = good_msg()
    for name, value in fields.items():
        object.__setattr__(msg, '_' + name, value)
    return msg


@pytest.mark.parametrize('msg,words', [
    (with_fields(data=array.array('B', bytes(6 * 24 - 1))), 'data has 143 bytes'),
    (with_fields(data=array.array('B', bytes(6 * 24 + 24))), 'data has 168 bytes'),
    (with_fields(step=23), 'step 23 is smaller than a row'),
    (with_fields(step=0), 'step 0 is smaller'),
    (with_fields(height=0), 'height is 0'),
    (with_fields(width=0), 'width is 0'),
    (with_fields(height=2 ** 31), 'height x step'),
    (with_fields(width=2 ** 30), 'smaller than a row'),
    (with_fields(encoding='rgb24'), 'Unrecognized image encoding'),
    (with_fields(encoding='mono16', step=7, width=3), 'not a multiple'),
    (with_fields(data='not bytes'), 'sequence of bytes'),
    (with_fields(data=[0, 1, 256]), r'\[0, 255\]'),
    (with_fields(data=[0.5] * 144), r'\[0, 255\]'),
    (with_fields(height=2.0), 'integer'),
    ('not a message', 'sensor_msgs/Image'),
], ids=lambda v: v if isinstance(v, str) else None)
def test_malformed_messages(msg, words):
    with pytest.raises(CvBridgeError, match=words):
        BRIDGE.imgmsg_to_cv2(msg)


@pytest.mark.parametrize('cvim,encoding,words', [
    (np.zeros((4, 4), bool), 'passthrough', 'numpy type bool'),
    (np.zeros((4, 4), np.int64), 'passthrough', 'numpy type int64'),
    (np.zeros((4, 4), np.float16), 'passthrough', 'float16'),
    (np.zeros((4, 4), np.complex64), 'passthrough', 'complex64'),
    (np.zeros((4, 4, 513), np.uint8), 'passthrough', '513 channels'),
    (np.zeros((4, 4, 0), np.uint8), 'passthrough', '0 channels'),
    (np.zeros((4, 4, 5), np.uint8), 'bgr8', 'incompatible type 8UC5'),
    (np.zeros((4, 4, 3, 1), np.uint8), 'passthrough', 'shape'),
    (np.zeros(4, np.uint8), 'passthrough', 'shape'),
    (np.zeros((0, 4, 3), np.uint8), 'passthrough', 'empty'),
    (np.uint8(3), 'passthrough', 'not a numpy array'),
    ([[1, 2], [3, 4]], 'passthrough', 'not a numpy array'),
    (np.zeros((4, 4), np.uint8), 'bgr8', 'incompatible type 8UC1'),
    (np.zeros((4, 4, 3), np.uint16), 'bgr8', 'incompatible type 16UC3'),
    (np.zeros((4, 4, 3), np.uint8), 'bgr', 'Unrecognized image encoding'),
])
def test_arrays_without_an_encoding(cvim, encoding, words):
    with pytest.raises(CvBridgeError, match=words):
        BRIDGE.cv2_to_imgmsg(cvim, encoding)


@pytest.mark.parametrize('encoding', sorted(YUV))
def test_odd_width_yuv_conversion_is_a_bridge_error(encoding):
    # 4:2:2 pixels come in pairs sharing U and V; OpenCV 4.6 converts an odd width anyway.
    packed = random_image(encoding, 4, 5)
    msg = BRIDGE.cv2_to_imgmsg(packed, encoding)
    np.testing.assert_array_equal(BRIDGE.imgmsg_to_cv2(msg), packed)
    for dst in sorted(PLAIN):
        with pytest.raises(CvBridgeError, match=r'\[%s\].*even width.*5 pixels' % encoding):
            BRIDGE.imgmsg_to_cv2(msg, dst)
    for alias in sorted(YUV):
        if ALL[alias][2] == ALL[encoding][2]:
            np.testing.assert_array_equal(BRIDGE.imgmsg_to_cv2(msg, alias), packed)


# --- compressed images -----------------------------------------------------------------------


def smooth_bgr(height=48, width=64):
    y, x = np.mgrid[0:height, 0:width]
    return np.dstack([x * 3, y * 4, (x + y) * 2]).astype(np.uint8)


@pytest.mark.parametrize('fmt', ['jpg', 'jpeg', 'png'])
def test_compressed_round_trip(fmt):
    im = smooth_bgr()
    header = Header(frame_id='cam')
    msg = BRIDGE.cv2_to_compressed_imgmsg(im, fmt, header=header)
    assert isinstance(msg, CompressedImage) and msg.format == fmt and msg.header == header
    out = BRIDGE.compressed_imgmsg_to_cv2(msg)
    assert out.shape == im.shape and out.dtype == np.uint8
    if fmt == 'png':
        np.testing.assert_array_equal(out, im)
    else:
        assert np.abs(out.astype(int) - im).mean() < 3
    np.testing.assert_array_equal(BRIDGE.compressed_imgmsg_to_cv2(msg, 'rgb8'), out[:, :, ::-1])
    assert BRIDGE.compressed_imgmsg_to_cv2(msg, 'mono8').shape == im.shape[:2]


@pytest.mark.parametrize('fmt', ['bgr8; jpeg compressed bgr8', 'rgb8; jpeg compressed bgr8',
                                 'jpeg', 'png', 'bgr8; png compressed bgr8', ''])
def test_image_transport_format_strings(fmt):
    im = smooth_bgr()
    ext = '.png' if 'png' in fmt else '.jpg'
    msg = CompressedImage(format=fmt)
    msg.data = array.array('B', cv2.imencode(ext, im)[1].tobytes())
    out = BRIDGE.compressed_imgmsg_to_cv2(msg, 'bgr8')
    assert out.shape == im.shape and np.abs(out.astype(int) - im).mean() < 3


@pytest.mark.parametrize('im,fmt,encoding', [
    (smooth_bgr()[:, :, 0], 'png', 'mono8'),
    (smooth_bgr()[:, :, 0].astype(np.uint16) * 250, 'png', 'mono16'),
    (smooth_bgr().astype(np.uint16) * 250, 'png', 'bgr16'),
    (np.dstack([smooth_bgr(), smooth_bgr()[:, :, :1]]), 'png', 'bgra8'),
])
def test_compressed_mono_deep_and_alpha(im, fmt, encoding):
    msg = BRIDGE.cv2_to_compressed_imgmsg(im, fmt)
    np.testing.assert_array_equal(BRIDGE.compressed_imgmsg_to_cv2(msg), im)
    np.testing.assert_array_equal(BRIDGE.compressed_imgmsg_to_cv2(msg, encoding), im)
    assert BRIDGE.compressed_imgmsg_to_cv2(msg, 'bgr8').shape == im.shape[:2] + (3,)


def test_compressed_depth_16uc1():
    depth = (np.arange(48 * 64, dtype=np.uint16) * 13).reshape(48, 64)
    msg = CompressedImage(format='16UC1; compressedDepth png')
    payload = bytes(12) + cv2.imencode('.png', depth)[1].tobytes()
    msg.data = array.array('B', payload)
    out = BRIDGE.compressed_imgmsg_to_cv2(msg)
    np.testing.assert_array_equal(out, depth)


@pytest.mark.parametrize('data,words', [
    (b'', 'no data'), (b'\xff\xd8 not really a jpeg', 'Could not decode'),
    (bytes(100), 'Could not decode')])
def test_bad_compressed_data(data, words):
    msg = CompressedImage(format='jpeg')
    msg.data = array.array('B', data)
    with pytest.raises(CvBridgeError, match=words):
        BRIDGE.compressed_imgmsg_to_cv2(msg)


def test_bad_compressed_output():
    with pytest.raises(CvBridgeError):
        BRIDGE.cv2_to_compressed_imgmsg(smooth_bgr(), 'nosuchformat')
    with pytest.raises(CvBridgeError, match='not a numpy array'):
        BRIDGE.cv2_to_compressed_imgmsg(b'abc')


# --- cvtColorForDisplay ----------------------------------------------------------------------


def test_display_colour_images():
    bgr = random_image('bgr8')
    assert cvtColorForDisplay(bgr, 'bgr8', 'bgr8') is bgr
    np.testing.assert_array_equal(cvtColorForDisplay(bgr[:, :, ::-1], 'rgb8'), bgr)
    np.testing.assert_array_equal(cvtColorForDisplay(bgr), bgr)
    mono = random_image('mono8')
    np.testing.assert_array_equal(cvtColorForDisplay(mono, 'mono8'), np.dstack([mono] * 3))
    np.testing.assert_array_equal(cvtColorForDisplay(mono, 'mono8', 'mono8'), mono)


def test_display_16_bit_and_bayer():
    deep = random_image('mono16')
    out = cvtColorForDisplay(deep, 'mono16', 'bgr8')
    np.testing.assert_array_equal(out[:, :, 1], np.round(deep / 257.0).astype(np.uint8))
    mosaic = random_image('bayer_rggb8')
    np.testing.assert_array_equal(cvtColorForDisplay(mosaic, 'bayer_rggb8', 'bgr8'),
                                  cv2.cvtColor(mosaic, cv2.COLOR_BayerBG2BGR))


def test_display_float_depth_needs_scaling():
    depth = np.linspace(0.5, 4.5, 6 * 8, dtype=np.float32).reshape(6, 8)
    depth[0, 0] = np.nan
    with pytest.raises(CvBridgeError, match='do_dynamic_scaling'):
        cvtColorForDisplay(depth, '32FC1', 'bgr8')
    out = cvtColorForDisplay(depth, '32FC1', 'bgr8', do_dynamic_scaling=True)
    assert out.shape == (6, 8, 3) and out.dtype == np.uint8
    assert out[0, 1, 0] == 0 and out[-1, -1, 0] == 255
    ranged = cvtColorForDisplay(depth, '32FC1', 'mono8', False, 0.5, 2.5)
    assert ranged.shape == (6, 8) and ranged[-1, -1] == 255 and ranged[0, 0] == 0
    assert ranged[0, 1] == round((depth[0, 1] - 0.5) * 255 / 2.0)
    coloured = cvtColorForDisplay(depth, '32FC1', 'bgr8', True, colormap=cv2.COLORMAP_JET)
    assert coloured.shape == (6, 8, 3) and len({tuple(p) for p in coloured.reshape(-1, 3)}) > 10
    flat = cvtColorForDisplay(np.ones((3, 3), np.float32), '32FC1', 'bgr8', True)
    assert (flat == 128).all()


def test_display_labels():
    labels = np.array([[-1, 0, 1], [2, 1, -1]], np.int32)
    out = cvtColorForDisplay(labels, '32SC1', 'bgr8')
    assert (out[0, 0] == 0).all() and (out[1, 2] == 0).all()
    assert (out[0, 2] == out[1, 1]).all()
    assert len({tuple(out[0, 1]), tuple(out[0, 2]), tuple(out[1, 0])}) == 3


def test_display_bad_requests():
    with pytest.raises(CvBridgeError, match='8-bit'):
        cvtColorForDisplay(random_image('bgr8'), 'bgr8', 'bgr16')
    with pytest.raises(CvBridgeError, match='needs 8UC3'):
        cvtColorForDisplay(random_image('mono8'), 'bgr8')
    with pytest.raises(CvBridgeError, match='one-channel'):
        cvtColorForDisplay(random_image('bgr8'), 'bgr8', 'bgr8', False, 0, 10)
