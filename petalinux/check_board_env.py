#!/usr/bin/env python3
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
Check that this Python environment is what an image built with petalinux/ gives py_vision.

Usage: python petalinux/check_board_env.py  (in the board-version run's environment:
. scripts/board_env.sh; scripts/test.sh runs it before that run's tests)

It reads petalinux/image_python.txt. Every module the image has must import here, at the
image's version (a fourth number after a release of three is a PyPI build number:
opencv-python-headless 4.6.0.66 is OpenCV 4.6.0), and every module no board image has must
not: a test that passes here on a module the boards lack would say nothing about the boards.
The interpreter must be the image's Python 3.10. Prints one line when all is well; otherwise
every mismatch, and exits 1. Standard library only.
"""

import importlib
import importlib.metadata
import os
import re
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
TABLE = os.path.join(HERE, 'image_python.txt')
ABSENT = 'absent'
# The image's Python: openembedded-core langdale's python3_3.10.6.bb.
IMAGE_PYTHON = (3, 10)
VERSION = re.compile(r'\d+(\.\d+)*\Z')


class Row:
    """One line of image_python.txt."""

    __slots__ = ('name', 'version', 'package', 'pip', 'line')

    def __init__(self, name, version, package, pip, line):
        self.name = name        # what to import, e.g. 'vision_msgs.msg'
        self.version = version  # the image's version, or ABSENT
        self.package = package  # the rootfs package that brings it, '-' when absent
        self.pip = pip          # the requirements-board.txt distribution, 'humble' or '-'
        self.line = line

    @property
    def module(self):
        """Return the top-level module, the one py_vision imports."""
        return self.name.split('.')[0]

    @property
    def absent(self):
        """Return whether no board image has the module."""
        return self.version == ABSENT


def read_table(path=TABLE):
    """Return the rows of image_python.txt; ValueError for a line that is not one."""
    rows = []
    with open(path, encoding='utf-8') as stream:
        for number, text in enumerate(stream, start=1):
            words = text.split()
            if not words or words[0].startswith('#'):
                continue
            if len(words) != 4:
                raise ValueError('%s:%d: expected 4 columns (import, version, package, pip), '
                                 'got %r' % (path, number, text.rstrip('\n')))
            row = Row(*words, line=number)
            if not (row.absent or VERSION.match(row.version)):
                raise ValueError('%s:%d: version %r is neither dotted numbers nor %r'
                                 % (path, number, row.version, ABSENT))
            if row.absent != (row.package == '-'):
                raise ValueError('%s:%d: a module the image has names its package, an absent '
                                 "one has '-'" % (path, number))
            rows.append(row)
    if not rows:
        raise ValueError('%s lists no module' % path)
    return rows


def same_release(installed, image):
    """
    Return whether an installed version is the image's.

    Equal, or for a release of three numbers those three and a fourth: the build number of
    the opencv-python wheels (4.6.0.66 is OpenCV 4.6.0). PyYAML 6.0.4 is not 6.0.
    """
    if installed == image:
        return True
    parts = installed.split('.')
    return (len(image.split('.')) == 3 and len(parts) == 4
            and '.'.join(parts[:3]) == image and parts[3].isdigit())


def installed_version(row):
    """Return the version installed here of a row's module, from its distribution's metadata."""
    distribution = row.module if row.pip == 'humble' else row.pip
    try:
        return importlib.metadata.version(distribution)
    except importlib.metadata.PackageNotFoundError:
        return None


def problems(rows, import_module=importlib.import_module, version_of=installed_version,
             python=sys.version_info[:2]):
    """Return what differs from the image, one sentence each (empty when nothing does)."""
    found = []
    if tuple(python) != IMAGE_PYTHON:
        found.append('Python is %d.%d, the image has %d.%d'
                     % (tuple(python) + IMAGE_PYTHON))
    for row in rows:
        try:
            import_module(row.name)
        except Exception as error:  # noqa: B902 - ImportError, or a module broken on import
            if not row.absent:
                found.append('%s does not import (%s: %s); the image has it (%s %s)'
                             % (row.name, type(error).__name__, error, row.package,
                                row.version))
            continue
        if row.absent:
            found.append('%s imports, but no board image has it: remove %s from this '
                         'environment' % (row.name, row.pip if row.pip != '-' else 'it'))
            continue
        version = version_of(row)
        if version is None or not same_release(version, row.version):
            found.append('%s is %s here, the image has %s (%s)'
                         % (row.name, version or 'of unknown version', row.version,
                            row.package))
    return found


def main():
    """Check the environment; return the exit status."""
    try:
        rows = read_table()
    except (OSError, ValueError) as error:
        sys.stderr.write('[board env] cannot read the image table: %s\n' % error)
        return 2
    found = problems(rows)
    if found:
        sys.stderr.write('[board env] FAILED: this environment is not what an image built with '
                         'petalinux/ has (%s):\n' % os.path.relpath(TABLE))
        sys.stderr.write(''.join('  %s\n' % line for line in found))
        sys.stderr.write('[board env] set it up again with scripts/setup.sh --board '
                         '(requirements-board.txt)\n')
        return 1
    present = ['%s %s' % (row.module, row.version) for row in rows if not row.absent]
    absent = [row.module for row in rows if row.absent]
    sys.stdout.write('[board env] as on the image: Python %d.%d, %s; absent as on the boards: '
                     '%s\n' % (IMAGE_PYTHON + (', '.join(present), ', '.join(absent))))
    return 0


if __name__ == '__main__':
    sys.exit(main())
