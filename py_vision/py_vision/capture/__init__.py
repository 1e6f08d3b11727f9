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
The camera layer: frame sources, the device's controls and the capture loop, without ROS.

- `source`: the interface every source has (`FrameSource`), `Frame`, `FrameFormat`, `Clock`;
- `controls`: a device's controls by V4L2 id (`ControlInfo`, one control described once), the
  automatic modes that hold others, and a batch of changes checked and ordered;
- `pixel_formats`: the pixel format table (FourCC, encoding, layout, conversions, bus cost);
- `devices`: what a `video_device` string names;
- `v4l2`: V4L2 devices: what they are and offer, their controls (ioctls);
- `v4l2_stream`: V4L2 cameras streamed by py_vision (mmap buffers);
- `video_file`: a video file played as a camera;
- `camera_model`: a camera described by a data file (the synthetic camera's and the test
  cameras'), and the USB bus's rule of the rates a camera offers;
- `synthetic_picture` and `synthetic_device`: the synthetic camera, its picture and the device;
- `camera`: `Camera`, a source opened and negotiated, with its controls by V4L2 id;
- `loop`: `CaptureLoop`, open / read / lose / reopen / close on a thread of its own.
"""

from py_vision.capture.camera import Camera, open_source, pixel_format_accepted
from py_vision.capture.controls import ControlInfo, Refusal
from py_vision.capture.loop import CaptureLoop, CaptureStats, LoopTiming
from py_vision.capture.source import (
    Frame, FrameFormat, FrameSize, FrameSource, SourceError, StreamFormat)
from py_vision.capture.synthetic_device import SyntheticDevices

__all__ = ['Camera', 'CaptureLoop', 'CaptureStats', 'ControlInfo', 'Frame', 'FrameFormat',
           'FrameSize', 'FrameSource', 'LoopTiming', 'open_source', 'pixel_format_accepted',
           'Refusal', 'SourceError', 'StreamFormat', 'SyntheticDevices']
