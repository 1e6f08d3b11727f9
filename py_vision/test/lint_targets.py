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

"""What the linter tests look at: this package, plus the repo's bench/ and petalinux/ tools."""

from pathlib import Path

PACKAGE_DIR = Path(__file__).resolve().parent.parent


def lint_targets():
    """Return the directories to lint (the repo extras only exist in a py_vision checkout)."""
    repo = PACKAGE_DIR.parent
    targets = [PACKAGE_DIR]
    targets += [repo / extra for extra in ('bench', 'petalinux') if (repo / extra).is_dir()]
    return targets


def python_files():
    """Every Python source file the linters check, excluding caches."""
    files = []
    for target in lint_targets():
        files += [p for p in sorted(target.rglob('*.py')) if '__pycache__' not in p.parts]
    return files
