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
The processing steps vision_step runs, and the API a step of your own follows (`api`).

`loader` turns a step's name into a step: `circle`, `hand_signs` and `faces` are the built-in
ones, here; `module.path:Class` names a user's own. docs/processing.md shows how to write one.
"""
