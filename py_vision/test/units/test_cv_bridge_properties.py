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


"""Property tests of py_vision.cv_bridge: round trips survive, bad input raises CvBridgeError."""

import array

import cv2
from hypothesis import given, HealthCheck, settings, strategies as st
from hypothesis.extra import numpy as hnp
import numpy as np
from py_vision.cv_bridge import CvBridge, CvBridgeError
from sensor_msgs.msg import CompressedImage, Image

BRIDGE = CvBridge()
SETTINGS = settings(max_examples=150, deadline=None,
                    suppress_health_check=[HealthCheck.too_slow])

DTYPES = ['uint8', 'int8', 'uint16', 'int16', 'int32', 'float32', 'float64']
ENCODINGS = ['mono8', 'mono16', 'rgb8', 'bgr8', 'rgba8', 'bgra8', 'rgb16', 'bgr16', 'rgba16',
             'bgra16', 'bayer_rggb8', 'bayer_bggr16', 'bayer_gbrg8', 'bayer_grbg16', 'yuv422',
             'yuv422_yuy2', '8UC1', '8UC2', '8SC3', '16UC4', '16SC1', '32SC2', '32FC1', '32FC3',
             '64FC1', '64FC4', '8UC5', '16SC8', '32FC17', '8U', '64F']


@st.composite
def images(draw):
    """Random arrays of every bridgeable type, in any memory layout and byte order."""
    dtype = np.dtype(draw(st.sampled_from(DTYPES)))
    if dtype.itemsize > 1 and draw(st.booleans()):
        dtype = dtype.newbyteorder('>')
    height, width = draw(st.integers(1, 9)), draw(st.integers(1, 9))
    channels = draw(st.sampled_from([None, 1, 2, 3, 4, 5, 8, 17]))
    shape = (height, width) if channels is None else (height, width, channels)
    im = draw(hnp.arrays(dtype, shape))
    layout = draw(st.sampled_from(['c', 'fortran', 'strided', 'reversed']))
    if layout == 'fortran':
        im = np.asfortranarray(im)
    elif layout == 'strided':
        im = np.repeat(np.repeat(im, 2, axis=0), 3, axis=1)[::2, ::3]
    elif layout == 'reversed':
        im = im[::-1, ::-1]
    return im


@SETTINGS
@given(images())
def test_arrays_survive_a_round_trip(im):
    msg = BRIDGE.cv2_to_imgmsg(im)
    out = BRIDGE.imgmsg_to_cv2(msg)
    expected = im[:, :, 0] if im.ndim == 3 and im.shape[2] == 1 else im
    assert out.dtype == im.dtype.newbyteorder('=') and out.shape == expected.shape
    np.testing.assert_array_equal(out, expected)
    assert len(msg.data) == msg.height * msg.step


@SETTINGS
@given(images(), st.sampled_from(ENCODINGS))
def test_named_encodings_round_trip_or_refuse(im, encoding):
    try:
        msg = BRIDGE.cv2_to_imgmsg(im, encoding)
    except CvBridgeError as exc:
        assert 'incompatible type' in str(exc)
        return
    assert msg.encoding == encoding
    out = BRIDGE.imgmsg_to_cv2(msg, encoding)
    np.testing.assert_array_equal(out, im.reshape(out.shape))


@st.composite
def messages(draw):
    """Image messages with any field values, as a hand-built or foreign message can carry."""
    msg = Image()
    fields = {
        'encoding': draw(st.one_of(st.sampled_from(ENCODINGS), st.text(max_size=8))),
        'height': draw(st.one_of(st.integers(-2, 12), st.integers(0, 2 ** 40))),
        'width': draw(st.one_of(st.integers(-2, 12), st.integers(0, 2 ** 40))),
        'step': draw(st.one_of(st.integers(-4, 80), st.integers(0, 2 ** 40))),
        'is_bigendian': draw(st.booleans()),
    }
    raw = draw(st.binary(max_size=400))
    kind = draw(st.sampled_from(['array', 'bytes', 'list', 'memoryview', 'bad-list']))
    fields['data'] = {'array': array.array('B', raw), 'bytes': raw, 'list': list(raw),
                      'memoryview': memoryview(raw),
                      'bad-list': list(raw) + [draw(st.integers(-300, 300))]}[kind]
    if draw(st.integers(0, 3)):
        # Build a well-formed size from the drawn shape so some messages get past the checks.
        fields['encoding'] = draw(st.sampled_from(ENCODINGS))
        fields['height'] = min(max(fields['height'], 1), 12)
        fields['width'] = min(max(fields['width'], 1), 12)
        dtype, channels = BRIDGE.encoding_to_dtype_with_channels(fields['encoding'])
        itemsize = np.dtype(dtype).itemsize
        row = fields['width'] * itemsize * channels
        fields['step'] = row + itemsize * draw(st.sampled_from([0, 0, 1, 3]))
        size = fields['step'] * max(fields['height'], 0) + draw(st.sampled_from([0, 0, -1, 1]))
        if 0 < size <= 5000:
            fields['data'] = array.array('B', bytes(size))
    for name, value in fields.items():
        object.__setattr__(msg, '_' + name, value)
    return msg


@SETTINGS
@given(messages(), st.sampled_from(ENCODINGS + ['passthrough']))
def test_malformed_messages_only_raise_bridge_errors(msg, desired):
    try:
        out = BRIDGE.imgmsg_to_cv2(msg, desired)
    except CvBridgeError as exc:
        assert str(exc)
        return
    # Whatever is accepted was well formed, and the image has the message's size.
    assert len(msg.data) == msg.height * msg.step
    assert out.shape[:2] == (msg.height, msg.width)


@SETTINGS
@given(st.binary(max_size=200), st.sampled_from([
    'jpeg', 'png', 'bgr8; jpeg compressed bgr8', '16UC1; compressedDepth png']))
def test_garbage_compressed_data_only_raises_bridge_errors(raw, fmt):
    msg = CompressedImage(format=fmt)
    msg.data = array.array('B', raw)
    try:
        BRIDGE.compressed_imgmsg_to_cv2(msg, 'bgr8')
    except CvBridgeError as exc:
        assert str(exc)


@SETTINGS
@given(st.sampled_from(DTYPES + ['bool', 'int64', 'uint32', 'float16', 'complex64']),
       st.lists(st.integers(0, 6), min_size=0, max_size=4),
       st.sampled_from(ENCODINGS + ['passthrough', 'nonsense']))
def test_any_array_converts_or_raises_a_bridge_error(dtype, shape, encoding):
    im = np.zeros(shape, dtype)
    try:
        msg = BRIDGE.cv2_to_imgmsg(im, encoding)
    except CvBridgeError as exc:
        assert str(exc)
        return
    assert (msg.height, msg.width) == im.shape[:2]
    try:
        jpeg = BRIDGE.cv2_to_compressed_imgmsg(im, 'png')
    except CvBridgeError:
        return
    assert cv2.imdecode(np.frombuffer(jpeg.data, np.uint8), cv2.IMREAD_UNCHANGED) is not None
