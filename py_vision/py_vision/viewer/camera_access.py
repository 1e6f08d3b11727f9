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


"""What the viewer's HTTP side needs of the camera panel's ROS side, and how that fails."""

from typing import Any, Dict, Protocol


class CameraError(Exception):
    """A camera request that cannot be done: `status` is the HTTP status, the message why."""

    def __init__(self, status: int, message: str):
        super().__init__(message)
        self.status = status


class CameraAccess(Protocol):
    """What the camera panel needs from the side that reaches the camera (over ROS)."""

    def describe(self) -> Dict[str, Any]:
        """Return what the camera is and its controls, JSON-able (see docs/panel.md)."""

    def set_controls(self, values: Dict[str, Any]) -> Dict[str, Any]:
        """Apply name: value; return name: {applied, reason}; raise CameraError if none can."""

    def set_step_parameters(self, values: Dict[str, Any]) -> Dict[str, Any]:
        """Set the processing step's name: value like set_controls (404: no such node)."""
