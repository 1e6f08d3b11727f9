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
The repository's own tests: its docs against the code, and the lint of its tools.

The package's tests (py_vision/test/) run where the package alone is, a colcon workspace; these
check what only a checkout has: README.md and docs/ against the package, and the tools beside
it (bench/, petalinux/, this folder). They import the installed package as the package's tests
do, with the package's test harness (py_vision/test/ros_harness.py).
"""

from pathlib import Path
import sys

import pytest

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO / 'py_vision' / 'test'))

import ros_harness  # noqa: E402  (from the package's test folder, put on the path above)

if not ros_harness.SITE_PACKAGES.is_dir():
    raise pytest.UsageError('%s is missing: build the package first (scripts/setup.sh)'
                            % ros_harness.SITE_PACKAGES)
ros_harness.import_installed_package()
