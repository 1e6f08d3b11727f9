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

"""What `usbcam_publisher --list-formats` prints, read back by the tests."""

import re

# A format's line: its FourCC as printed, its name, what the publisher gives of it.
FORMAT_LINE = re.compile(r'^(\S[^(]{0,7}?) \(([^()]*)\)(?:, (.*))?$')
# One size and its rates: "  1280x720: 10, 5 fps".
SIZE_LINE = re.compile(r'^  (\d+)x(\d+): ([\d., ]+) fps$')


def formats(output):
    """Return [(fourcc, description, {(width, height): [rates]})] in the listing's order."""
    found = []
    for line in output.splitlines():
        header = FORMAT_LINE.match(line)
        if header:
            found.append((header.group(1), header.group(2), {}))
            continue
        size = SIZE_LINE.match(line)
        if size and found:
            found[-1][2][(int(size.group(1)), int(size.group(2)))] = [
                float(rate) for rate in size.group(3).split(', ')]
    return found


def offered(output):
    """Return {fourcc: {(width, height): [rates]}} from a listing."""
    return {fourcc: sizes for fourcc, _, sizes in formats(output)}


def control_line(output, name):
    """Return the listing's line of the control named name (its parameter name), or None."""
    return next((line.strip() for line in output.splitlines()
                 if line.strip().startswith(name + ' (')), None)
