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

"""The tables in docs/ say what the code's tables say."""

from pathlib import Path
import re

from py_vision.capture.pixel_formats import FORMATS
from py_vision.control_names import USB_CAM_PIXEL_FORMATS

DOCS = Path(__file__).resolve().parents[1] / 'docs'


def test_the_pixel_format_table_in_transport_md_is_the_codes():
    text = (DOCS / 'transport.md').read_text()
    rows = re.findall(r'^\| `(\w+)` \| [^|]+ \| ([^|]+) \| ([^|]+) \| ([^|]+) \|$', text,
                      re.MULTILINE)
    documented = {fourcc: ([n.strip('` ') for n in names.split(',')], encoding.strip(),
                           bus.strip()) for fourcc, names, encoding, bus in rows}
    expected = {}
    for pixel_format in FORMATS.values():
        names = [pixel_format.fourcc.lower()] + [
            name for name, fourcc in USB_CAM_PIXEL_FORMATS.items()
            if fourcc == pixel_format.fourcc]
        encoding = '`%s`' % pixel_format.encoding if pixel_format.encoding else \
            '(none: `%s`)' % pixel_format.native_encoding
        bus = '%g' % pixel_format.bus_bytes if pixel_format.bus_bytes else 'compressed'
        expected[pixel_format.fourcc] = (names, encoding, bus)
    assert documented == expected
