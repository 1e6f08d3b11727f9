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
The repository's tools beside the package (bench/, petalinux/, tests/): the package's linters.

The same checks as the package's own linter tests (py_vision/test/test_flake8.py, ...): flake8
and pep257 as ament runs them, the Apache-2.0 header, no Python string of 60 lines or more.
"""

from pathlib import Path
import subprocess
import sys

from ament_pep257.main import main as pep257_main
from lint_targets import header_problem, long_strings, python_files

REPO = Path(__file__).resolve().parents[1]
TOOLS = [REPO / 'bench', REPO / 'petalinux', REPO / 'tests']


def test_flake8():
    # In an interpreter of its own, as the package's test_flake8 does (flake8 forks a pool).
    result = subprocess.run(
        [sys.executable, '-m', 'ament_flake8.main'] + [str(p) for p in TOOLS],
        capture_output=True, text=True, timeout=300)
    assert result.returncode == 0, 'ament_flake8 found code style errors (status %d):\n%s%s' % (
        result.returncode, result.stdout, result.stderr)


def test_pep257():
    assert pep257_main(argv=[str(p) for p in TOOLS]) == 0, 'Found code style errors / warnings'


def test_copyright():
    files = python_files(TOOLS)
    assert len(files) > 5, 'the copyright check found almost no files: the search is broken'
    problems = ['%s: %s' % (f, header_problem(f.read_text())) for f in files
                if header_problem(f.read_text())]
    assert not problems, 'Files without a proper header:\n' + '\n'.join(problems)


def test_no_python_string_of_60_lines_or_more():
    found = long_strings(python_files(TOOLS))
    assert not found, '\n'.join(found)
