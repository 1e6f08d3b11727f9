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
What the package's linter tests look at, and the checks they share with the repository's.

The package's tests lint the package alone: in a workspace it is all there is. The repository's
own tools (bench/, petalinux/, tests/) are linted by the repository's tests
(tests/test_lint.py), which use the same checks.
"""

import ast
from pathlib import Path
import re

PACKAGE_DIR = Path(__file__).resolve().parent.parent

APACHE_NOTICE = [
    'Licensed under the Apache License, Version 2.0 (the "License");',
    'you may not use this file except in compliance with the License.',
    'You may obtain a copy of the License at',
    '',
    'http://www.apache.org/licenses/LICENSE-2.0',
    '',
    'Unless required by applicable law or agreed to in writing, software',
    'distributed under the License is distributed on an "AS IS" BASIS,',
    'WITHOUT WARRANTIES OR CONDITIONS OF ANY KIND, either express or implied.',
    'See the License for the specific language governing permissions and',
    'limitations under the License.',
]
COPYRIGHT_LINE = re.compile(r'^Copyright (19|20)\d\d(-(19|20)\d\d)? \S.*$')
# A Python string this long is a page, a script or a document: a file of its own.
MAX_STRING_LINES = 60


def lint_targets():
    """Return the directories the package's linter tests check: the package's own."""
    return [PACKAGE_DIR]


def python_files(targets=None):
    """Every Python source file under targets (default: lint_targets()), excluding caches."""
    files = []
    for target in lint_targets() if targets is None else targets:
        files += [p for p in sorted(target.rglob('*.py')) if '__pycache__' not in p.parts]
    return files


def header_problem(text):
    """Return why a file's header is not acceptable, or None when it is."""
    lines = text.splitlines()
    if lines and lines[0].startswith('#!'):
        lines = lines[1:]
    comment = []
    for line in lines:
        if not line.startswith('#'):
            break
        comment.append(line[1:].strip())
    if not comment or not COPYRIGHT_LINE.match(comment[0]):
        return 'does not start with a "# Copyright <year> <holder>" line'
    if comment[1:2] != [''] or comment[2:2 + len(APACHE_NOTICE)] != APACHE_NOTICE:
        return 'the Apache-2.0 notice does not follow the copyright line'
    return None


def long_strings(paths):
    """Return '<file>:<line>: a string of N lines' for every string of MAX_STRING_LINES or more."""
    found = []
    for path in paths:
        for node in ast.walk(ast.parse(path.read_text(encoding='utf-8'), str(path))):
            if isinstance(node, ast.Constant) and isinstance(node.value, (str, bytes)):
                lines = node.end_lineno - node.lineno + 1
                if lines >= MAX_STRING_LINES:
                    found.append('%s:%d: a string of %d lines' % (path, node.lineno, lines))
    return found
