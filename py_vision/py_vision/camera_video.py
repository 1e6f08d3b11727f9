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
A camera's own H.264 or HEVC in the camera node: as it comes, and as images on demand.

Each frame is an access unit, published untouched on the video topic (transport.VideoPublisher)
while it has subscribers, with the frame's header (the kernel's capture time). The image topics
(raw, compressed) get pictures decoded from the units (video_decoder) only while one of them
has subscribers: the decoder starts at the next keyframe and each picture goes out with the
header of its own unit. Where this machine cannot decode, it is said once.
"""

from typing import Optional

from py_vision.annexb import CODECS, inspect
from py_vision.capture.pixel_formats import OPENCV_BGR, VIDEO_FORMATS
from py_vision.params import Parameters
from py_vision.transport import ImagePublisher, VideoPublisher
from py_vision.video_decoder import VideoDecoder

__all__ = ['CameraVideo']


class CameraVideo:
    """The video topic of a camera whose frames are access units, and its decoded images."""

    def __init__(self, parameters: Parameters, base_topic: str, qos, fourcc: str,
                 images: ImagePublisher, output: str = 'bgr8'):
        self.codec = VIDEO_FORMATS[fourcc]
        self.publisher = VideoPublisher(parameters, base_topic, qos, CODECS[self.codec])
        self._images = images
        # Decoders give BGR: converted as a BGR camera's frames are (output_encoding).
        self._output = output
        self._encoding = OPENCV_BGR.native_encoding if output == 'native' else output
        self._logger = parameters.node.get_logger()
        self._decoder: Optional[VideoDecoder] = None
        self._cannot_decode = False
        self._said_parameter_sets = False
        self.published = 0         # access units published
        self.decoded = 0           # pictures decoded for the image topics

    def publish(self, header, data) -> None:
        """Publish one access unit (the frame's bytes) and, when wanted, its picture."""
        unit = bytes(data)
        info = inspect(unit, self.codec)
        if info.keyframe and not info.parameter_sets and not self._said_parameter_sets:
            self._said_parameter_sets = True
            self._logger.warning(
                'the camera sends a keyframe without its parameter sets (SPS, PPS): a '
                'subscriber that joins after the stream started may not be able to decode it')
        if self.publisher.wants():
            self.publisher.publish(header, unit)
            self.published += 1
        images = self._images
        if self._cannot_decode or not (images.wants_raw() or images.wants_compressed()):
            self._stop_decoding()
            return
        if self._decoder is None:
            self._decoder = VideoDecoder(self.codec, self._decoded, self._failed)
            if self._decoder.failed:
                self._failed(self._decoder.failed)
        if self._decoder is not None:
            self._decoder.decode(unit, header)

    def _decoded(self, picture, header):
        """Publish a decoded picture with its own unit's header (on the decoder's thread)."""
        self.decoded += 1
        self._images.publish(header, lambda: OPENCV_BGR.convert(picture, self._output), None,
                             self._encoding, lambda: picture)

    def _failed(self, reason):
        # On the decoder's thread, or the capture thread's: the next unit stops the decoder.
        self._cannot_decode = True
        self._logger.error(
            "cannot decode the camera's %s here, so %s and its compressed topic stay empty: "
            "%s (the camera's own stream is on %s)" % (
                self.publisher.format.upper(), self._images.raw.topic_name, reason,
                self.publisher.name))

    def _stop_decoding(self):
        # The next decoder starts at a keyframe again: nothing is decoded without its
        # references after a pause.
        if self._decoder is not None:
            self._decoder.close(timeout=0)
            self._decoder = None

    def close(self) -> None:
        """Stop decoding."""
        decoder, self._decoder = self._decoder, None
        if decoder is not None:
            decoder.close()
