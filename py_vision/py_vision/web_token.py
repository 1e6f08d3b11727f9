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
The browser viewer's token rule, shared by the viewer and the `web_token` parameter.

A module of its own so that the parameters (params.py) can check a token without importing
the HTTP server, and the server without importing ROS.
"""

import string

# Long enough not to be guessed, and safe in a URL and a cookie as it is.
TOKEN_RULE = 'at least 16 of A-Z a-z 0-9 - _ . ~'
_TOKEN_CHARACTERS = frozenset(string.ascii_letters + string.digits + '-_.~')


def good_token(token: str) -> bool:
    """Return True when token follows TOKEN_RULE."""
    return len(token) >= 16 and set(token) <= _TOKEN_CHARACTERS
