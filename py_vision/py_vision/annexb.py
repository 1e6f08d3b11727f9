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
H.264 and HEVC access units in Annex B form: what one camera frame holds, read without decoding.

A UVC camera's H.264 (or HEVC) frame is one access unit: NAL units each after a start code
(``00 00 01`` or ``00 00 00 01``). `inspect()` says what a receiver needs to know of it: whether
a decoder can start there (a keyframe, IDR or IRAP, with the parameter sets before it), and
for H.264 the picture size (from the SPS) and the codec string a browser's VideoDecoder is
configured with (``avc1.PPCCLL``: profile, constraint flags, level). Nothing here decodes a
picture: that is `video_decoder`'s.
"""

from dataclasses import dataclass
from typing import List, Optional, Tuple

__all__ = ['AUD', 'CODECS', 'inspect', 'leading_delimiter', 'nal_types', 'UnitInfo']

# pixel_format name -> the `format` foxglove_msgs/CompressedVideo (and ours) carries.
CODECS = {'h264': 'h264', 'hevc': 'h265'}
# An access unit delimiter that allows every picture type (primary_pic_type 7).
AUD = {'h264': b'\x00\x00\x00\x01\x09\xf0',
       'hevc': b'\x00\x00\x00\x01\x46\x01\x50'}

_H264_IDR, _H264_SPS, _H264_PPS, _H264_AUD = 5, 7, 8, 9
_HEVC_IRAP = range(16, 24)
_HEVC_VPS, _HEVC_SPS, _HEVC_PPS, _HEVC_AUD = 32, 33, 34, 35
# Profiles whose SPS carries chroma format, bit depths and scaling matrices (7.3.2.1.1).
_HIGH_PROFILES = frozenset((100, 110, 122, 244, 44, 83, 86, 118, 128, 138, 139, 134, 135))


@dataclass(frozen=True)
class UnitInfo:
    """What one access unit holds."""

    nal_types: Tuple[int, ...]
    keyframe: bool                  # an IDR (H.264) or IRAP (HEVC) picture
    parameter_sets: bool            # SPS and PPS (and VPS for HEVC) are in it
    width: int = 0                  # from its H.264 SPS; 0 when it has none
    height: int = 0
    codec_string: str = ''          # 'avc1.42c01e' from its H.264 SPS; '' when it has none

    @property
    def decodable_start(self) -> bool:
        """Return True when a decoder that saw nothing before can start at this unit."""
        return self.keyframe and self.parameter_sets


def _nal_spans(data: bytes) -> List[Tuple[int, int]]:
    """Return (start, end) of each NAL unit's bytes (after its start code) in data."""
    spans = []
    position = data.find(b'\x00\x00\x01')
    while position >= 0:
        start = position + 3
        position = data.find(b'\x00\x00\x01', start)
        end = len(data) if position < 0 else position
        # A four-byte start code's leading zero (and trailing_zero_8bits) belongs to no unit.
        while end > start and data[end - 1] == 0:
            end -= 1
        if end > start:
            spans.append((start, end))
    return spans


def nal_types(data: bytes, codec: str = 'h264') -> Tuple[int, ...]:
    """Return the NAL unit types in data, in order (H.264: 5 bits; HEVC: 6 bits)."""
    if codec == 'hevc':
        return tuple((data[start] >> 1) & 0x3F for start, _ in _nal_spans(data))
    return tuple(data[start] & 0x1F for start, _ in _nal_spans(data))


def leading_delimiter(data: bytes, codec: str = 'h264') -> int:
    """Return the length of the access unit delimiter data starts with (0: none)."""
    for start_code in (b'\x00\x00\x00\x01', b'\x00\x00\x01'):
        if data.startswith(start_code):
            header = len(start_code)
            if codec == 'hevc':
                found = len(data) >= header + 3 and (data[header] >> 1) & 0x3F == _HEVC_AUD
                return header + 3 if found else 0
            found = len(data) >= header + 2 and data[header] & 0x1F == _H264_AUD
            return header + 2 if found else 0
    return 0


def inspect(data: bytes, codec: str = 'h264') -> UnitInfo:
    """Return what the access unit `data` (Annex B) holds; codec is 'h264' or 'hevc'."""
    data = bytes(data)
    spans = _nal_spans(data)
    if codec == 'hevc':
        types = tuple((data[start] >> 1) & 0x3F for start, _ in spans)
        found = set(types)
        return UnitInfo(types, any(t in _HEVC_IRAP for t in types),
                        {_HEVC_VPS, _HEVC_SPS, _HEVC_PPS} <= found)
    types = tuple(data[start] & 0x1F for start, _ in spans)
    found = set(types)
    width = height = 0
    codec_string = ''
    for (start, end), kind in zip(spans, types):
        if kind == _H264_SPS and end - start >= 4:
            codec_string = 'avc1.%02x%02x%02x' % tuple(data[start + 1:start + 4])
            size = _sps_size(_unescape(data[start + 1:end]))
            if size is not None:
                width, height = size
            break
    return UnitInfo(types, _H264_IDR in types, {_H264_SPS, _H264_PPS} <= found,
                    width, height, codec_string)


def _unescape(payload: bytes) -> bytes:
    """Return a NAL unit's payload without its emulation prevention bytes (00 00 03)."""
    return payload.replace(b'\x00\x00\x03', b'\x00\x00')


class _Bits:
    """Reads an RBSP bit by bit: fixed-width fields and Exp-Golomb codes."""

    def __init__(self, data: bytes):
        self._data = data
        self._position = 0

    def bit(self) -> int:
        byte = self._data[self._position >> 3]   # IndexError past the end: a short SPS
        value = (byte >> (7 - (self._position & 7))) & 1
        self._position += 1
        return value

    def bits(self, count: int) -> int:
        value = 0
        for _ in range(count):
            value = (value << 1) | self.bit()
        return value

    def ue(self) -> int:
        zeros = 0
        while self.bit() == 0:
            zeros += 1
            if zeros > 31:
                raise ValueError('an Exp-Golomb code longer than 32 bits')
        return (1 << zeros) - 1 + self.bits(zeros)

    def se(self) -> int:
        code = self.ue()
        return (code + 1) // 2 if code & 1 else -(code // 2)


def _skip_scaling_list(bits: _Bits, size: int) -> None:
    last = following = 8
    for _ in range(size):
        if following:
            following = (last + bits.se() + 256) % 256
        last = following or last


def _sps_size(rbsp: bytes) -> Optional[Tuple[int, int]]:
    """Return the (width, height) an H.264 SPS (its RBSP after the profile bytes) describes."""
    bits = _Bits(rbsp)
    try:
        profile = bits.bits(8)
        bits.bits(16)                      # constraint flags, level_idc
        bits.ue()                          # seq_parameter_set_id
        chroma_format = 1
        separate_planes = 0
        if profile in _HIGH_PROFILES:
            chroma_format = bits.ue()
            if chroma_format == 3:
                separate_planes = bits.bit()
            bits.ue()                      # bit_depth_luma_minus8
            bits.ue()                      # bit_depth_chroma_minus8
            bits.bit()                     # qpprime_y_zero_transform_bypass_flag
            if bits.bit():                 # seq_scaling_matrix_present_flag
                for index in range(8 if chroma_format != 3 else 12):
                    if bits.bit():
                        _skip_scaling_list(bits, 16 if index < 6 else 64)
        bits.ue()                          # log2_max_frame_num_minus4
        order_type = bits.ue()
        if order_type == 0:
            bits.ue()                      # log2_max_pic_order_cnt_lsb_minus4
        elif order_type == 1:
            bits.bit()
            bits.se()
            bits.se()
            for _ in range(bits.ue()):
                bits.se()
        bits.ue()                          # max_num_ref_frames
        bits.bit()                         # gaps_in_frame_num_value_allowed_flag
        width_mbs = bits.ue() + 1
        height_units = bits.ue() + 1
        frame_mbs_only = bits.bit()
        if not frame_mbs_only:
            bits.bit()                     # mb_adaptive_frame_field_flag
        bits.bit()                         # direct_8x8_inference_flag
        crop = (0, 0, 0, 0)
        if bits.bit():                     # frame_cropping_flag
            crop = (bits.ue(), bits.ue(), bits.ue(), bits.ue())
    except (IndexError, ValueError):
        return None
    width = width_mbs * 16
    height = height_units * 16 * (2 - frame_mbs_only)
    # Cropping is counted in chroma samples (in frame pairs for field coding) (7-19..7-22).
    if chroma_format == 0 or separate_planes:
        unit_x, unit_y = 1, 2 - frame_mbs_only
    else:
        unit_x = 1 if chroma_format == 3 else 2
        unit_y = (2 if chroma_format == 1 else 1) * (2 - frame_mbs_only)
    width -= unit_x * (crop[0] + crop[1])
    height -= unit_y * (crop[2] + crop[3])
    if width <= 0 or height <= 0:
        return None
    return width, height
