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
The recorded H.264 clip (uvc_emulator/clips/, made by make_clip.py), as access units.

Frame i of the clip shows index i in the synthetic picture's code (`read_frame_index`); an IDR
with its SPS and PPS every `KEYINT` frames.
"""

from pathlib import Path
from typing import List

CLIP = Path(__file__).resolve().parent / 'uvc_emulator' / 'clips' / 'synthetic_640x480.h264'
WIDTH, HEIGHT, FRAMES, KEYINT = 640, 480, 60, 15
_DELIMITER = b'\x00\x00\x00\x01\x09'   # every access unit of the clip starts with its AUD


def access_units(path: Path = CLIP) -> List[bytes]:
    """Return the clip's access units, in order, each starting with its delimiter."""
    data = path.read_bytes()
    starts = []
    position = data.find(_DELIMITER)
    while position >= 0:
        starts.append(position)
        position = data.find(_DELIMITER, position + 1)
    return [data[start:end] for start, end in zip(starts, starts[1:] + [len(data)])]
