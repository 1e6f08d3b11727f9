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
A processing step that does nothing: vision_step's receiving and handing over, alone.

`vision_step --ros-args -p step:=nothing_step:Nothing` (bench/ on PYTHONPATH) converts each
frame to bgr8 and hands it to this step, which returns None: nothing is published.
"""


class Nothing:
    """process() returns None: no image goes out."""

    def process(self, image, header):
        """Return None for every frame."""
        return None
