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
Copyright and license headers, checked without ament_copyright (which is not on PyPI).

ament_copyright accepts a file when it starts (after an optional shebang) with a
'Copyright <year> <holder>' line followed by the license's standard notice. This test applies
the same rule for the one license the package declares in package.xml, Apache-2.0.
"""

import xml.etree.ElementTree as ET

from lint_targets import APACHE_NOTICE, header_problem, PACKAGE_DIR, python_files
import pytest


def test_package_declares_the_checked_license():
    licenses = [e.text for e in ET.parse(PACKAGE_DIR / 'package.xml').getroot().iter('license')]
    assert licenses == ['Apache-2.0']


@pytest.mark.copyright
@pytest.mark.linter
def test_copyright():
    files = python_files()
    assert len(files) > 5, 'the copyright check found almost no files: the search is broken'
    problems = ['%s: %s' % (f, header_problem(f.read_text())) for f in files
                if header_problem(f.read_text())]
    assert not problems, 'Files without a proper header:\n' + '\n'.join(problems)


def test_checker_rejects_missing_or_altered_headers():
    good = '#!/usr/bin/env python3\n' + ''.join(
        '# %s\n' % line if line else '#\n'
        for line in ['Copyright 2026 someone', ''] + APACHE_NOTICE) + '\nimport os\n'
    good = good.replace('#     http', '# http')
    assert header_problem(good) is None
    assert header_problem('import os\n') is not None
    assert header_problem(good.replace('Copyright 2026', 'Copyleft 2026')) is not None
    assert header_problem(good.replace('Version 2.0', 'Version 3.0')) is not None
