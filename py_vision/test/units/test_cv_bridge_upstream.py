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
What upstream cv_bridge's own Python tests check, checked against py_vision.cv_bridge.

ros-perception/vision_opencv has the same three files on its humble and rolling branches,
cv_bridge/test/conversions.py, enumerants.py and python_bindings.py; each test below names the
one it follows. They are written here in our own words; where upstream still calls numpy's
removed ``tostring`` we compare ``tobytes``, and where it loops over many sizes we take a few.
"""

import sys

import cv2
import numpy as np
from py_vision.cv_bridge import CvBridge, CvBridgeError, cvtColorForDisplay, getCvType
import pytest
from sensor_msgs.msg import Image

BRIDGE = CvBridge()
SIZES = [(100, 100), (300, 200), (700, 500)]
DTYPES = ['uint8', 'int8', 'uint16', 'int16', 'int32', 'float32', 'float64']


def random_uint8(height, width, channels, seed=0):
    """Return a random uint8 image; channels None means no third axis."""
    shape = (height, width) if channels is None else (height, width, channels)
    return np.random.default_rng(seed).integers(0, 255, shape, np.uint8)


def assert_same_layout(original, decoded, channels):
    """As upstream: same dtype, same shape (a one-channel axis is dropped), same byte count."""
    assert decoded.dtype == original.dtype
    if channels == 1:
        assert decoded.shape == original.shape[:2]
    else:
        assert decoded.shape == original.shape
    assert len(decoded.tobytes()) == len(original.tobytes())


# --- conversions.py ---------------------------------------------------------------------------


def test_mono16_needs_a_colour_encoding():
    # conversions.py, test_mono16_cv2: passthrough makes 8UC3, which has no colour to make mono.
    im = random_uint8(480, 640, 3)
    with pytest.raises(CvBridgeError):
        BRIDGE.imgmsg_to_cv2(BRIDGE.cv2_to_imgmsg(im), 'mono16')
    mono = BRIDGE.imgmsg_to_cv2(BRIDGE.cv2_to_imgmsg(im, 'rgb8'), 'mono16')
    assert mono.shape == (480, 640) and mono.dtype == np.uint16


@pytest.mark.parametrize('dtype', DTYPES)
@pytest.mark.parametrize('channels', [None, 1, 2, 3, 4, 5])
@pytest.mark.parametrize('width,height', SIZES)
def test_passthrough_round_trip(width, height, channels, dtype):
    # conversions.py, test_encode_decode_cv2 (upstream lists the depths but sends only uint8;
    # we send every depth, and 5 channels travel as <depth>C5).
    original = random_uint8(height, width, channels).astype(dtype)
    msg = BRIDGE.cv2_to_imgmsg(original)
    decoded = CvBridge().imgmsg_to_cv2(msg)
    assert_same_layout(original, decoded, channels)
    np.testing.assert_array_equal(decoded.reshape(original.shape), original)


@pytest.mark.parametrize('fmt', ['jpg', 'jpeg', 'jpe', 'png', 'bmp', 'dib', 'sr', 'ras', 'tif',
                                 'tiff'])
@pytest.mark.parametrize('channels', [None, 1, 3])
@pytest.mark.parametrize('width,height', SIZES[:2])
def test_compressed_round_trip_keeps_the_layout(width, height, channels, fmt):
    # conversions.py, test_encode_decode_cv2_compressed (jp2 is left out there too).
    original = random_uint8(height, width, channels)
    msg = BRIDGE.cv2_to_compressed_imgmsg(original, fmt)
    decoded = CvBridge().compressed_imgmsg_to_cv2(msg)
    assert_same_layout(original, decoded, channels)
    # Beyond upstream: lossless formats give the pixels back, except a grey Sun raster, which
    # OpenCV's own reader returns as zeros (cv2.imdecode alone does that).
    if fmt in ('png', 'bmp', 'dib', 'tif', 'tiff') or (fmt in ('sr', 'ras') and channels == 3):
        np.testing.assert_array_equal(decoded.reshape(original.shape), original)


def test_big_endian_int32_round_trip():
    # conversions.py, test_endianness.
    values = np.random.default_rng(3).integers(0, 255, (30, 40))
    msg = BRIDGE.cv2_to_imgmsg(values.astype(np.dtype('int32').newbyteorder('>')))
    assert msg.is_bigendian and msg.encoding == '32SC1'
    np.testing.assert_array_equal(BRIDGE.imgmsg_to_cv2(msg), values)


# --- enumerants.py ----------------------------------------------------------------------------


def test_hand_built_rgba8_message():
    # enumerants.py, test_enumerants_cv2.
    msg = Image(width=640, height=480, encoding='rgba8', step=640 * 4)
    msg.data = (640 * 480 * '1234').encode()
    cvim = BRIDGE.imgmsg_to_cv2(msg, 'rgb8')
    # Nothing else holds on to the converted image (the call's argument is the other count).
    assert sys.getrefcount(cvim) == 2
    assert cvim.shape == (480, 640, 3) and tuple(cvim[5, 7]) == (ord('1'), ord('2'), ord('3'))
    with pytest.raises(CvBridgeError):
        BRIDGE.cv2_to_imgmsg(cvim, 'rgba8')
    assert BRIDGE.cv2_to_imgmsg(cvim, 'rgb8').encoding == 'rgb8'
    assert BRIDGE.cv2_to_imgmsg(cvim, 'bgr8').encoding == 'bgr8'


def test_opencv_type_numbers():
    # enumerants.py, test_enumerants_cv2: a bare depth is one channel.
    assert getCvType('32FC4') != cv2.CV_8UC4
    assert getCvType('8UC1') == cv2.CV_8UC1
    assert getCvType('8U') == cv2.CV_8UC1


def test_not_an_array_is_a_type_error():
    # enumerants.py, test_numpy_types.
    with pytest.raises(TypeError):
        BRIDGE.cv2_to_imgmsg(1, 'rgba8')


# --- python_bindings.py -----------------------------------------------------------------------


def test_label_image_for_display():
    # python_bindings.py, test_cvtColorForDisplay: a 3 x 4 grid of labels 0..11.
    label = np.zeros((480, 640), np.int32)
    for row in range(3):
        for col in range(4):
            label[row * 160:(row + 1) * 160, col * 160:(col + 1) * 160] = row * 4 + col
    shown = cvtColorForDisplay(label, '32SC1', 'bgr8')
    assert shown.dtype == np.uint8 and shown.shape == (480, 640, 3)
    assert shown.min() == 0 and shown.max() == 255


def test_mono8_keeps_two_dimensions():
    # python_bindings.py, test_cvtColorForDisplay, its second half.
    mono = (np.random.default_rng(4).random((100, 100)) * 255).astype(np.uint8)
    output = BRIDGE.imgmsg_to_cv2(BRIDGE.cv2_to_imgmsg(mono, encoding='mono8'),
                                  desired_encoding='mono8')
    assert output.shape == (100, 100)
