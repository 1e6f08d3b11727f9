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


"""No Python string of 60 lines or more: a page, a script or a document is a file of its own."""

from lint_targets import long_strings, python_files
import pytest


@pytest.mark.linter
def test_no_python_string_of_60_lines_or_more():
    found = long_strings(python_files())
    assert not found, '\n'.join(found)
