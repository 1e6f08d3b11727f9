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

"""A property test's failure, as the suite reports it, says how to replay it (conftest.py)."""

import ast
import re

from hypothesis import given, reproduce_failure, settings, strategies as st
import pytest


def failing_property(drawn):
    """Return a property test that fails on large floats, recording what it was given."""
    @settings(database=None)
    @given(st.floats(allow_nan=False, allow_infinity=False))
    def below_a_million(value):
        drawn.append(value)
        assert abs(value) < 1e6
    return below_a_million


def test_a_failing_property_prints_the_line_that_replays_it(capsys):
    drawn = []
    with pytest.raises(AssertionError) as failure:
        failing_property(drawn)()
    # Hypothesis adds what pytest shows below the traceback as the exception's notes (Python
    # 3.11's add_note; its own attribute of the same name on 3.10).
    printed = capsys.readouterr().out + '\n'.join(getattr(failure.value, '__notes__', ()))
    line = re.search(r'@reproduce_failure\((.*)\)', printed)
    assert line, 'no @reproduce_failure line in what the failure printed:\n' + printed
    version, blob = ast.literal_eval('(%s)' % line.group(1))

    replayed = []
    with pytest.raises(AssertionError):
        reproduce_failure(version, blob)(failing_property(replayed))()
    # The very example the failure reported (its last run), and only that one.
    assert replayed == [drawn[-1]]
    assert abs(drawn[-1]) >= 1e6
