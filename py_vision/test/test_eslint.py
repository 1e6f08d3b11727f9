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
The viewer page's script, linted with ESLint (Debian's `eslint` package, scripts/test.sh).

Without eslint the test is skipped with the reason on a developer's PC or in `colcon test`,
and fails when CI=true: CI must run it.
"""

import os
import shutil
import subprocess

from lint_targets import PACKAGE_DIR
import pytest

CONFIG = PACKAGE_DIR / 'test' / 'eslint.json'
SCRIPTS = sorted((PACKAGE_DIR / 'py_vision' / 'viewer' / 'page').glob('*.js'))
# Where Debian installs eslint's own modules: a Node.js from elsewhere (NodeSource) does not
# look there by itself.
DEBIAN_NODE_MODULES = '/usr/share/nodejs'


@pytest.mark.linter
def test_eslint():
    eslint = shutil.which('eslint')
    if eslint is None:
        missing = 'eslint is not installed (apt-get install eslint)'
        if os.environ.get('CI', '').lower() in ('1', 'true', 'yes'):
            pytest.fail('%s, and CI requires the JavaScript lint' % missing)
        pytest.skip('%s; CI runs this test' % missing)
    assert SCRIPTS, 'no script found in the viewer page folder'
    paths = os.pathsep.join(p for p in (DEBIAN_NODE_MODULES, os.environ.get('NODE_PATH'))
                            if p)
    # From the package's folder: ESLint 6 fails on a file outside its working directory.
    result = subprocess.run(
        [eslint, '--no-eslintrc', '--config', str(CONFIG.relative_to(PACKAGE_DIR)),
         '--max-warnings', '0'] + [str(path.relative_to(PACKAGE_DIR)) for path in SCRIPTS],
        stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, cwd=PACKAGE_DIR,
        env=dict(os.environ, NODE_PATH=paths), timeout=120)
    assert result.returncode == 0, 'ESLint found problems:\n' + result.stdout
