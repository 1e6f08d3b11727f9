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
Who may ask the viewer what: the token, its cookie, and the Host and Origin rules.

Bound to a loopback address (127.0.0.0/8, ::1, localhost) and with no token given, the viewer
answers only requests whose Host names a loopback address (a web page cannot reach it through
a rebound DNS name). Anywhere else every request needs the token: ``?token=`` in the URL once
(the page then keeps it in an HttpOnly, SameSite=Strict cookie), or an ``Authorization:
Bearer`` header. A change must come from the page's own origin (its ``Origin`` equal to its
``Host``, by http or https), or, authenticated by the header, carry no ``Origin``. Nothing but
a navigation to the page may come from another site's page (``Sec-Fetch-Site``).
docs/panel.md explains the model and docs/security.md what it defends against.
"""

from dataclasses import dataclass
import hmac
import ipaddress
import secrets
from typing import Iterator, Mapping, Optional, Tuple, Union
from urllib.parse import parse_qs

from py_vision.web_token import good_token, TOKEN_RULE

# How a request is authenticated.
LOCAL, COOKIE, BEARER, QUERY = 'local', 'cookie', 'bearer', 'query'


@dataclass(frozen=True)
class Refusal:
    """What to answer instead of serving the request: a status, why, and extra headers."""

    status: int
    reason: str
    headers: Tuple[Tuple[str, str], ...] = ()


def is_loopback(host: str) -> bool:
    """Return True when host (an address or name to bind) is this machine's loopback."""
    if host.lower() == 'localhost':
        return True
    try:
        return ipaddress.ip_address(host.strip('[]')).is_loopback
    except ValueError:
        return False


def cookie_values(header: str, name: str) -> Iterator[str]:
    """
    Yield the values of the cookies called name in a Cookie header.

    Read leniently, as browsers write it: the other cookies, those of any other web
    application on the same host name, may hold anything (spaces, no '=', quotes).
    """
    for part in header.split(';'):
        key, equals, value = part.partition('=')
        if equals and key.strip() == name:
            value = value.strip()
            if len(value) >= 2 and value[0] == value[-1] == '"':
                value = value[1:-1]
            yield value


def host_name(host_header: str) -> str:
    """Return the name part of a Host header ('[::1]:8080' -> '::1', 'a:80' -> 'a')."""
    if host_header.startswith('['):
        return host_header[1:].split(']', 1)[0]
    return host_header.rsplit(':', 1)[0] if host_header.count(':') == 1 else host_header


class Access:
    """The access rules of one viewer: its token (if any) and its cookie."""

    def __init__(self, host: str, token: str = ''):
        """
        Make the rules for a viewer bound to host.

        token: what every request must carry (TOKEN_RULE; ValueError if not). Empty: none on
        a loopback host, and a random one on any other.
        """
        if token:
            if not good_token(token):
                raise ValueError('token must be %s' % TOKEN_RULE)
            self.token: Optional[str] = token
        else:
            self.token = None if is_loopback(host) else secrets.token_urlsafe(24)
        self.port = 0
        self.url = ''

    def bind(self, port: int, url: str) -> None:
        """Set the port the viewer is bound to and the URL it is opened at."""
        self.port, self.url = port, url

    @property
    def cookie_name(self) -> str:
        """Return the cookie the page keeps the token in (one per port: cookies ignore ports)."""
        return 'py_vision_token_%d' % self.port

    def check_token(self, given: str) -> bool:
        """Return True when given is the token (in constant time)."""
        return self.token is not None and hmac.compare_digest(
            given.encode('utf-8', 'replace'), self.token.encode())

    def authenticate(self, method: str, route: str, query: str,
                     headers: Mapping[str, str]) -> Union[str, Refusal]:
        """
        Return how the request is authenticated (LOCAL, COOKIE, BEARER, QUERY), or a Refusal.

        The page opened with its token is answered with the cookie and a redirect to the
        clean URL (a Refusal with status 303).
        """
        if self.token is None:
            host = headers.get('Host')
            if host is not None and not is_loopback(host_name(host)):
                return Refusal(403, 'this viewer answers only to localhost: open it as %s' % (
                    self.url))
            return LOCAL
        try:
            given = parse_qs(query).get('token', [None])[0]
        except ValueError:
            given = None
        if given is not None and method in ('GET', 'HEAD'):
            if not self.check_token(given):
                return Refusal(401, 'wrong token: open the URL the node logged at its start')
            if route != '/':
                return QUERY
            # The page keeps the token in a cookie no script can read or send to another site;
            # the redirect takes it out of the address bar and the history.
            return Refusal(303, 'See /', (
                ('Location', '/'), ('Set-Cookie', '%s=%s; HttpOnly; SameSite=Strict; Path=/' % (
                    self.cookie_name, self.token))))
        authorization = headers.get('Authorization', '')
        if authorization[:7].lower() == 'bearer ':
            if self.check_token(authorization[7:].strip()):
                return BEARER
        elif any(self.check_token(value) for value in cookie_values(
                headers.get('Cookie', ''), self.cookie_name)):
            return COOKIE
        return Refusal(401, 'this viewer needs its token: open the URL the node logged at its '
                       'start (http://...?token=...), or send "Authorization: Bearer <token>"',
                       (('WWW-Authenticate', 'Bearer realm="py_vision"'),))

    @staticmethod
    def change_refusal(how: str, headers: Mapping[str, str]) -> Optional[Refusal]:
        """Return why a change (a POST) authenticated as how is refused, or None."""
        # A cross-site page can make a browser send a POST with the cookie, never with the
        # header, and never with a forged Origin: the Origin must be the page's own. Behind a
        # proxy that speaks HTTPS to the browser and passes Host on, that is https://<Host>.
        origin = headers.get('Origin')
        host = headers.get('Host', '')
        own = ('http://' + host, 'https://' + host)
        if (origin is not None and origin not in own) or (origin is None and how == COOKIE):
            return Refusal(403, "a change must come from the viewer's own page (Origin %s, "
                           'expected %s)' % (origin or 'missing', ' or '.join(own)))
        return None

    @staticmethod
    def site_refusal(page: bool, headers: Mapping[str, str]) -> Optional[Refusal]:
        """
        Return why a request from another site's page is refused, or None.

        Browsers say where a request comes from (Sec-Fetch-Site); other clients send nothing.
        A link on another site may open a page (a navigation); nothing else of the viewer may
        be used by another site: its stream and snapshot shown in that site's page (which would
        also take the video clients' places), its API called from there.
        """
        site = headers.get('Sec-Fetch-Site')
        if site in (None, 'same-origin', 'none'):
            return None
        if page and headers.get('Sec-Fetch-Mode') == 'navigate' and headers.get(
                'Sec-Fetch-Dest') == 'document':
            return None
        return Refusal(403, 'another site (Sec-Fetch-Site: %s) cannot use this viewer: open it '
                       'at its own address' % site[:40])
