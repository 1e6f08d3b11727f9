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
The browser viewer and where a node shows its frames.

- `display`: the `display` parameter's choice: an OpenCV window, the browser viewer, nowhere
- `server`: the HTTP server (standard library only, no ROS): `WebViewer` and its routes
- `access`: who may ask what (the token, its cookie, the Host and Origin rules)
- `frames`: the newest frame, encoded to JPEG once and only when a client wants it
- `camera_access`: what the server needs of the camera panel's ROS side (a Protocol)
- `camera_panel`: that ROS side: the controls of the node publishing the shown topic
- ``page/``: the page (index.html, viewer.js, viewer.css), installed with the package

Importing this package imports none of them: `display` loads the server only for
``display:=web``.
"""
