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
The pixel format table and the V4L2 structures py_vision streams with.

The names a user types find their format; layouts with padded rows read the same picture as
unpadded ones; a frame converts into a message's bytes as into an array of its own, and a JPEG
that does not decode is no picture whatever the output; the streaming structures have the
sizes and ioctl numbers of linux/videodev2.h on 64-bit machines. (docs/transport.md's table
is checked against this one by the repository's tests/test_docs_match_code.py: the package
alone has no docs/.)
"""

import re
import struct

import cv2
import numpy as np
from py_vision.capture import v4l2_stream
from py_vision.capture.devices import CAMERA, classify, FILE, SYNTHETIC
from py_vision.capture.pixel_formats import find, FORMATS, fourcc_code, fourcc_text, OUTPUTS
from py_vision.capture.source import Frame, SourceError
from py_vision.capture.synthetic_picture import synthetic_yuyv
from py_vision.control_names import pixel_format_fourcc
import pytest

RAW = [pixel_format for pixel_format in FORMATS.values() if not pixel_format.compressed]


@pytest.mark.parametrize('name,fourcc', [
    ('yuyv', 'YUYV'), ('YUYV', 'YUYV'), (' Nv12 ', 'NV12'), ('grey', 'GREY'), ('y16', 'Y16'),
    ('rgb3', 'RGB3'), ('bgr3', 'BGR3'), ('mjpg', 'MJPG'), ('yu12', 'YU12'),
    ('mjpeg', 'MJPG'), ('mono8', 'GREY'), ('mono16', 'Y16'), ('rgb24', 'RGB3'),
    ('bgr24', 'BGR3'), ('Mono8', 'GREY')])
def test_a_fourcc_or_usb_cams_name_finds_its_format(name, fourcc):
    assert find(pixel_format_fourcc(name)).fourcc == fourcc


def test_names_that_are_no_format_find_nothing():
    assert find('auto') is None and find('h265') is None and find('') is None
    assert find('mjpeg') is None   # usb_cam's name: control_names turns it into MJPG
    assert pixel_format_fourcc('auto') == 'auto'


def test_fourccs_are_v4l2s_numbers():
    assert fourcc_code('YUYV') == 0x56595559 and fourcc_text(0x56595559) == 'YUYV'
    assert fourcc_code('Y16') == 0x20363159 and fourcc_text(0x20363159) == 'Y16'
    assert all(fourcc_text(f.code) == f.fourcc for f in FORMATS.values())


@pytest.mark.parametrize('pixel_format', RAW, ids=lambda pixel_format: pixel_format.fourcc)
def test_padded_rows_give_the_same_picture(pixel_format):
    width, height, pad = 64, 48, 32
    sent = np.ascontiguousarray(pixel_format.from_yuyv(synthetic_yuyv(2, width, height)))
    sent = sent.reshape(-1).view(np.uint8)
    stride = pixel_format.bytesperline(width) + pad
    # The same planes as a driver with rows of `stride` bytes lays them out.
    padded, offset, first = [], 0, pixel_format.planes[0]
    for plane in pixel_format.planes:
        rows, row = plane.rows(height), plane.row_bytes(width)
        plane_stride = stride * plane.across * first.per // (plane.per * first.across)
        block = np.zeros((rows, plane_stride), np.uint8)
        block[:, :row] = sent[offset:offset + rows * row].reshape(rows, row)
        padded.append(block.reshape(-1))
        offset += rows * row
    padded = np.concatenate(padded)
    assert padded.size == pixel_format.frame_bytes(width, height, stride)
    plain = pixel_format.convert(pixel_format.view(sent, width, height), 'bgr8')
    spaced = pixel_format.convert(pixel_format.view(padded, width, height, stride), 'bgr8')
    assert np.array_equal(plain, spaced)


def sent_frame(pixel_format, width=64, height=48, index=2):
    """Return a frame's bytes (1-D uint8) as a camera of pixel_format sends them."""
    if pixel_format.compressed:
        picture = cv2.cvtColor(synthetic_yuyv(index, width, height), cv2.COLOR_YUV2BGR_YUYV)
        return cv2.imencode('.jpg', picture)[1].reshape(-1)
    sent = np.ascontiguousarray(pixel_format.from_yuyv(synthetic_yuyv(index, width, height)))
    return sent.reshape(-1).view(np.uint8)


UNDECODABLE_JPEG = np.frombuffer(b'\xff\xd8' + bytes(200) + b'\xff\xd9', np.uint8)
CONVERTED = [pixel_format for pixel_format in FORMATS.values() if pixel_format.conversions]


@pytest.mark.parametrize('output', OUTPUTS)
@pytest.mark.parametrize('pixel_format', CONVERTED, ids=lambda pixel_format: pixel_format.fourcc)
def test_a_frame_converts_into_a_message_as_into_an_array_of_its_own(pixel_format, output):
    width, height = 64, 48
    view = pixel_format.view(sent_frame(pixel_format, width, height), width, height)
    own = pixel_format.convert(view, output)
    out = np.full_like(own, 77)
    written = pixel_format.convert(view, output, out)
    assert written is out, 'the image is written where the message wants it'
    assert np.array_equal(out, own)
    # An array of another size (a JPEG larger than announced) is not written into: the image
    # comes back in one of its own.
    small = np.full((own.shape[0] // 2,) + own.shape[1:], 77, own.dtype)
    other = pixel_format.convert(view, output, small)
    assert other is not small and np.array_equal(other, own) and (small == 77).all()


@pytest.mark.parametrize('output', OUTPUTS)
def test_a_whole_jpeg_that_does_not_decode_is_no_picture_in_any_output(output):
    # SOI, nothing a decoder can read, EOI: whole as far as the camera layer can tell, so it
    # reaches the decoder, which gives up. Every output says "no picture" (the frame is counted
    # as corrupt); none raises, which would end the capture thread and the node.
    frame = Frame(1, None, FORMATS['MJPG'], 64, 48, UNDECODABLE_JPEG)
    assert frame.image(output) is None and frame.corrupt


@pytest.mark.parametrize('output', OUTPUTS)
def test_a_jpeg_that_does_not_decode_writes_nothing_into_a_message(output):
    frame = Frame(2, None, FORMATS['MJPG'], 64, 48, UNDECODABLE_JPEG)
    out = np.full((48, 64, 3), 77, np.uint8)
    assert frame.image(output, out) is None and frame.corrupt and (out == 77).all()


def test_the_streaming_structures_are_videodev2s_on_64_bit():
    if struct.calcsize('P') != 8:
        pytest.skip('the numbers below are those of a 64-bit machine')
    assert v4l2_stream._BUFFER.size == 88    # struct v4l2_buffer
    assert v4l2_stream._FORMAT.size == 208   # struct v4l2_format
    assert (v4l2_stream.VIDIOC_S_FMT, v4l2_stream.VIDIOC_QUERYBUF, v4l2_stream.VIDIOC_QBUF,
            v4l2_stream.VIDIOC_DQBUF, v4l2_stream.VIDIOC_STREAMON,
            v4l2_stream.VIDIOC_STREAMOFF, v4l2_stream.VIDIOC_S_PARM) == (
        0xC0D05605, 0xC0585609, 0xC058560F, 0xC0585611, 0x40045612, 0x40045613, 0xC0CC5616)
    # index type bytesused flags field, pad, timeval, timecode, sequence memory, m, length...
    raw = struct.pack('=5I4xqq16x2IQI12x', 3, 1, 1234, 0x2000, 1, 17, 250000, 42, 1,
                      0x8000, 4096)
    assert v4l2_stream._DEQUEUED.unpack_from(raw) == (3, 1234, 0x2000, 17, 250000, 42)
    fields = v4l2_stream._BUFFER.unpack(raw)
    assert (fields[v4l2_stream._OFFSET], fields[v4l2_stream._LENGTH]) == (0x8000, 4096)
    assert v4l2_stream._MEMORY_AT == 60


def test_one_classifier_says_what_a_video_device_names(tmp_path):
    clip = tmp_path / 'clip.avi'
    clip.write_bytes(b'')
    assert classify('synthetic?formats=grey').kind == SYNTHETIC
    assert classify(str(clip)).kind == FILE
    assert classify('/dev/null') == classify('/dev/null')
    assert classify('/dev/null').kind == CAMERA   # a character device: V4L2's to judge
    for device, words in ((str(tmp_path), 'is a directory'),
                          (str(tmp_path / 'missing'), 'no such device or file'),
                          ('987', 'no camera 987 (/dev/video987 does not exist)')):
        with pytest.raises(SourceError, match=re.escape(words)):
            classify(device)
