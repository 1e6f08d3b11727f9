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

import subprocess
import sys

from lint_targets import lint_targets
import pytest


@pytest.mark.flake8
@pytest.mark.linter
def test_flake8():
    # In an interpreter of its own: flake8 checks files in a pool of processes forked from
    # the one it runs in, and a fork of this test process (rclpy's, Fast DDS' and the
    # browser's threads) crashed in its garbage collector, again and again, until the timeout.
    result = subprocess.run(
        [sys.executable, '-m', 'ament_flake8.main'] + [str(p) for p in lint_targets()],
        capture_output=True, text=True, timeout=300)
    assert result.returncode == 0, 'ament_flake8 found code style errors (status %d):\n%s%s' % (
        result.returncode, result.stdout, result.stderr)
