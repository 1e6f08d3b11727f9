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
The synthetic camera's public names at their old address.

The synthetic camera lives in the camera layer now: its picture in
`py_vision.capture.synthetic_picture`, the device in `py_vision.capture.synthetic_device`.
Import from there; this module keeps older imports working.
"""

from py_vision.capture.synthetic_device import (  # noqa: F401
    BUS_BYTES_PER_S, CONTROLS, FORMATS, is_synthetic_spec, MAX_FPS, MAX_SIZE,
    parse_synthetic_spec, SyntheticCamera, SyntheticDevices, UVC_RATES, yuyv_max_fps)
from py_vision.capture.synthetic_picture import (  # noqa: F401
    bgr_to_yuyv, JPEG_QUALITY, MIN_CODE_SIZE, read_frame_index, synthetic_frame,
    synthetic_jpeg, synthetic_yuyv, yuyv_to_bgr)
