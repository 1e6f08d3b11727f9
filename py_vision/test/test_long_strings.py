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

import ast

from lint_targets import python_files
import pytest

MAX_LINES = 60


@pytest.mark.linter
def test_no_python_string_of_60_lines_or_more():
    long_strings = []
    for path in python_files():
        for node in ast.walk(ast.parse(path.read_text(encoding='utf-8'), str(path))):
            if isinstance(node, ast.Constant) and isinstance(node.value, (str, bytes)):
                lines = node.end_lineno - node.lineno + 1
                if lines >= MAX_LINES:
                    long_strings.append('%s:%d: a string of %d lines' % (
                        path, node.lineno, lines))
    assert not long_strings, '\n'.join(long_strings)
