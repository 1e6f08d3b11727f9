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
cv_bridge_test: the processing step of the second tutorial, ported to ROS 2.

Every image from usb_camera/image (or usb_camera/image/compressed with
``image_transport:=compressed``) is converted to an OpenCV bgr8 image with the bridge, gets
a red filled circle at (60, 60) with radius 30 when it is larger than 60x60, and goes out on
cv_bridge_image with the header it came with (and, while it has subscribers, as JPEG on
cv_bridge_image/compressed).

It is vision_step running the `circle` step (py_vision/steps/circle.py) under its own name and
topic, with the circle's `simulated_work_ms` and without `step` and `threads`: the same code,
the newest frame, the same statistics and /diagnostics. docs/processing.md explains it.
"""

from typing import Optional

from py_vision.node_main import main_for
from py_vision.steps.circle import Circle, work_note
from py_vision.vision_step import INPUT_SPECS, VisionStep


class CvBridgeTest(VisionStep):
    """The processing node (node_main.NodeProgram): a red circle on the newest frame."""

    NODE_NAME = 'cv_bridge_test'
    OUTPUT_TOPIC = 'cv_bridge_image'
    FIXED_STEP = 'circle'
    SUMMARY = ('Draws a red circle on every frame of usb_camera/image and publishes it on '
               'cv_bridge_image, always working on the newest frame.')
    NODE_PARAMETERS = INPUT_SPECS
    PARAMETERS = INPUT_SPECS + Circle.PARAMETERS

    def startup_line(self, note: Optional[str]) -> str:
        """Return the start-up line the tutorial's node has always logged."""
        return 'drawing on images from %s, publishing them on %s%s' % (
            self.subscription_.topic_name, self.publisher_.topic_name,
            work_note(self.step.simulated_work_s * 1e3))


main = main_for(CvBridgeTest)


if __name__ == '__main__':
    main()
