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

"""annexb: what an access unit holds, read from the bytes a camera sends."""

from py_vision.annexb import AUD, inspect, nal_types
import pytest
from video_clip import access_units, FRAMES, HEIGHT, KEYINT, WIDTH

# SPS NAL units (with their start code) of sizes the clip does not have, from libx264
# (ffmpeg -f lavfi -i testsrc=size=...): 1920x1080 High (68 macroblock rows, cropped by 8
# lines) and 1280x720 High 4:4:4 (cropping counted in luma samples).
SPS_1080P = bytes.fromhex('0000000167640028acd940780227e5c044000003000400000300f03c60c658')
SPS_720P_444 = bytes.fromhex('0000000167f4001f919b280a00b76022000003000200000300781e30632c')


def test_the_clip_has_a_delimiter_before_each_frame_and_parameter_sets_with_each_idr():
    units = access_units()
    assert len(units) == FRAMES
    for index, unit in enumerate(units):
        info = inspect(unit)
        assert info.nal_types[0] == 9, 'frame %d starts with NAL type %d' % (
            index, info.nal_types[0])
        assert info.keyframe == (index % KEYINT == 0)
        assert info.decodable_start == info.keyframe
        assert 6 not in info.nal_types   # no SEI, as a camera's


def test_a_keyframe_tells_its_size_and_the_browser_codec_string():
    info = inspect(access_units()[0])
    assert (info.width, info.height) == (WIDTH, HEIGHT)
    assert info.codec_string == 'avc1.42c01e'   # constrained baseline, level 3.0
    delta = inspect(access_units()[1])
    assert (delta.width, delta.height, delta.codec_string) == (0, 0, '')


@pytest.mark.parametrize('sps, size, codec', [
    (SPS_1080P, (1920, 1080), 'avc1.640028'),
    (SPS_720P_444, (1280, 720), 'avc1.f4001f'),
])
def test_sizes_with_cropping_and_high_profiles(sps, size, codec):
    info = inspect(sps)
    assert (info.width, info.height) == size
    assert info.codec_string == codec
    assert not info.keyframe


def test_a_cut_short_sps_gives_no_size_and_no_error():
    info = inspect(SPS_1080P[:9])
    assert (info.width, info.height) == (0, 0)
    assert info.nal_types == (7,)


def test_three_and_four_byte_start_codes_and_hevc_types():
    h264 = b'\x00\x00\x01\x09\xf0' + b'\x00\x00\x00\x01\x65\x88'
    assert nal_types(h264) == (9, 5)
    # HEVC: AUD (35), VPS (32), SPS (33), PPS (34), IDR_W_RADL (19)
    hevc = AUD['hevc'] + b''.join(b'\x00\x00\x01' + bytes([kind << 1, 1]) + b'\xaa'
                                  for kind in (32, 33, 34, 19))
    info = inspect(hevc, 'hevc')
    assert info.nal_types == (35, 32, 33, 34, 19)
    assert info.decodable_start
    assert not inspect(hevc[:-12], 'hevc').keyframe
