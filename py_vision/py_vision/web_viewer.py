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
The browser viewer: live images over HTTP, with the standard library only (no ROS here).

Routes, and nothing else (no file is ever served from disk):

- ``GET /``             a self-contained page: the live video, the live stats, the camera panel
- ``GET /stream``       MJPEG (``multipart/x-mixed-replace``), always the newest frame
- ``GET /snapshot.jpg`` the newest frame as one JPEG (503 until the first frame arrives)
- ``GET /stats``        the stats given to ``set_stats()`` plus the viewer's own, as JSON
- ``GET /camera``       what the camera is and its controls, from the `CameraAccess` given to
  ``set_camera()`` (404 without one), as JSON
- ``POST /camera/controls`` a JSON object of control name: value, handed to the CameraAccess;
  the answer says per control whether it was applied and why not

Access: bound to a loopback address (127.0.0.0/8, ::1, localhost) and with no token given,
the viewer answers only requests whose Host names a loopback address (a web page cannot reach
it through a rebound DNS name). Anywhere else every request needs the token: ``?token=`` in
the URL once (the page then keeps it in an HttpOnly, SameSite=Strict cookie), or an
``Authorization: Bearer`` header. A POST must come from the page's own origin (its ``Origin``
equal to its ``Host``), or, authenticated by the header, carry no ``Origin``; its body must be
JSON (``Content-Type: application/json``) and small.

``submit()`` only stores a reference to the image and wakes the clients: a frame is encoded
to JPEG once, when the first client wants it, and never when nobody watches. Every client has
its own thread and always gets the newest frame, so a slow client skips frames instead of
slowing the producer or the other clients. The number of video clients is bounded; further
ones get a short 503 answer.
"""

import errno
import hmac
import html
from http.cookies import CookieError, SimpleCookie
from http.server import BaseHTTPRequestHandler, HTTPServer
import io
import ipaddress
import json
import logging
import math
import secrets
import select
import socket
from socketserver import ThreadingMixIn
import string
import threading
import time
from typing import Any, Dict, Optional, Protocol
from urllib.parse import parse_qs

import cv2
import numpy as np

_BOUNDARY = 'py_vision_frame'
# A client that accepts no data for this long (it vanished or stalled) is dropped.
_SOCKET_TIMEOUT = 10.0
# A request (line, headers and body) must have arrived whole this long after the connection:
# a client sending it a byte at a time cannot hold one of the few connections.
_REQUEST_TIME = 10.0
# How often an idle stream thread checks that its client is still there.
_IDLE_CHECK = 1.0
# Short requests (the page, /stats, snapshots) beyond the video clients: enough for every
# tab's stats poll, small enough to bound the threads a misbehaving client can make us start.
_EXTRA_CONNECTIONS = 16
_WILDCARD_HOSTS = ('', '0.0.0.0', '::')
# The largest request body taken (a POST of controls is a few hundred bytes).
MAX_BODY = 16384
# A token given to the viewer: long enough not to be guessed, and safe in a URL and a cookie.
TOKEN_RULE = 'at least 16 of A-Z a-z 0-9 - _ . ~'
_TOKEN_CHARACTERS = frozenset(string.ascii_letters + string.digits + '-_.~')


def good_token(token: str) -> bool:
    """Return True when token follows TOKEN_RULE."""
    return len(token) >= 16 and set(token) <= _TOKEN_CHARACTERS


class WebViewerError(Exception):
    """The viewer cannot serve (the address is in use or unusable); the message says why."""


class CameraError(Exception):
    """A camera request that cannot be done: `status` is the HTTP status, the message why."""

    def __init__(self, status: int, message: str):
        super().__init__(message)
        self.status = status


class CameraAccess(Protocol):
    """What the camera panel needs from the side that reaches the camera (over ROS)."""

    def describe(self) -> Dict[str, Any]:
        """Return what the camera is and its controls, JSON-able (see docs/panel.md)."""

    def set_controls(self, values: Dict[str, Any]) -> Dict[str, Any]:
        """Apply name: value; return name: {applied, reason}; raise CameraError if none can."""


def is_loopback(host: str) -> bool:
    """Return True when host (an address or name to bind) is this machine's loopback."""
    if host.lower() == 'localhost':
        return True
    try:
        return ipaddress.ip_address(host.strip('[]')).is_loopback
    except ValueError:
        return False


def _host_name(host_header: str) -> str:
    """Return the name part of a Host header ('[::1]:8080' -> '::1', 'a:80' -> 'a')."""
    if host_header.startswith('['):
        return host_header[1:].split(']', 1)[0]
    return host_header.rsplit(':', 1)[0] if host_header.count(':') == 1 else host_header


class _ThrottledLog:
    """One message per key and period at most, so a flood of events cannot flood the log."""

    def __init__(self, logger, period=5.0):
        self._logger = logger
        self._period = period
        self._last = {}
        self._lock = threading.Lock()

    def __call__(self, level, key, message):
        now = time.monotonic()
        with self._lock:
            if now - self._last.get(key, -math.inf) < self._period:
                return
            self._last[key] = now
        getattr(self._logger, level)(message)


def _json_safe(value):
    """Return value with numpy scalars made plain and non-finite floats made null."""
    if isinstance(value, dict):
        return {str(k): _json_safe(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_json_safe(v) for v in value]
    if isinstance(value, np.generic):
        value = value.item()
    if isinstance(value, float) and not math.isfinite(value):
        return None
    if value is None or isinstance(value, (bool, int, float, str)):
        return value
    return str(value)


class _Server(ThreadingMixIn, HTTPServer):
    """A threading HTTP server that counts, caps and can close its connections."""

    daemon_threads = True
    allow_reuse_address = True
    request_queue_size = 64  # a burst of connections waits in the kernel, not in SYN retries

    def __init__(self, viewer, address, family):
        self.viewer = viewer
        self.address_family = family
        super().__init__(address, _Handler)

    def server_bind(self):
        # HTTPServer.server_bind() resolves the host's FQDN, which can stall for seconds on a
        # board without DNS; the name is not needed.
        super(HTTPServer, self).server_bind()
        self.server_name, self.server_port = self.server_address[:2]

    def process_request(self, request, client_address):
        if not self.viewer._open_connection(request):
            try:
                request.setblocking(False)
                request.send(b'HTTP/1.1 503 Service Unavailable\r\nContent-Length: 0\r\n'
                             b'Connection: close\r\n\r\n')
            except OSError:
                pass
            super().shutdown_request(request)
            return
        super().process_request(request, client_address)

    def shutdown_request(self, request):
        self.viewer._close_connection(request)
        super().shutdown_request(request)

    def handle_error(self, request, client_address):
        self.viewer._log_handler_error(client_address)


class _RequestReader(io.RawIOBase):
    """The request side of one connection: every read ends by the request's deadline."""

    def __init__(self, connection: socket.socket, deadline: float):
        super().__init__()
        self._connection = connection
        self._deadline = deadline

    def readable(self) -> bool:
        return True

    def readinto(self, buffer) -> int:
        left = self._deadline - time.monotonic()
        if left <= 0:
            raise TimeoutError('the request did not arrive within %g s' % _REQUEST_TIME)
        # The socket's own timeout stays what the answer is written with.
        self._connection.settimeout(min(left, _SOCKET_TIMEOUT))
        try:
            return self._connection.recv_into(buffer)
        finally:
            self._connection.settimeout(_SOCKET_TIMEOUT)


class _Handler(BaseHTTPRequestHandler):
    """Serves the routes of one connection, then closes it."""

    protocol_version = 'HTTP/1.1'
    timeout = _SOCKET_TIMEOUT

    def setup(self):
        super().setup()
        # http.server reads the request line, the headers and the body through rfile: a
        # timeout there ends the connection quietly (handle_one_request).
        self.rfile = io.BufferedReader(
            _RequestReader(self.connection, time.monotonic() + _REQUEST_TIME))

    def version_string(self):
        return 'py_vision'

    def _route(self):
        """Return (route, query): the target as the client sent it, split at '?'."""
        # http.server folds a leading '//' in self.path; exact matches only: '//stream',
        # '/stream/', '/../x', '/%2e%2e/' are all 404.
        target = self.requestline.split()[1]
        route, _, query = target.split('#', 1)[0].partition('?')
        return route, query

    def _authenticate(self, route, query):
        """
        Return how the request is authenticated ('local', 'cookie', 'bearer', 'query').

        None when it is not: the refusal has been sent (or, for the page opened with its
        token, the cookie and the redirect to the clean URL).
        """
        viewer = self.server.viewer
        if viewer.token is None:
            host = self.headers.get('Host')
            if host is not None and not is_loopback(_host_name(host)):
                self._fail(403, 'this viewer answers only to localhost: open it as %s' % (
                    viewer.url))
                return None
            return 'local'
        try:
            given = parse_qs(query).get('token', [None])[0]
        except ValueError:
            given = None
        if given is not None and self.command in ('GET', 'HEAD'):
            if not viewer.check_token(given):
                self._fail(401, 'wrong token: open the URL the node logged at its start')
                return None
            if route != '/':
                return 'query'
            # The page keeps the token in a cookie no script can read or send to another site;
            # the redirect takes it out of the address bar and the history.
            self._send(303, 'text/plain; charset=utf-8', b'See /\n', [
                ('Location', '/'), ('Set-Cookie', '%s=%s; HttpOnly; SameSite=Strict; Path=/' % (
                    viewer.cookie_name, viewer.token))])
            return None
        authorization = self.headers.get('Authorization', '')
        if authorization[:7].lower() == 'bearer ':
            if viewer.check_token(authorization[7:].strip()):
                return 'bearer'
        else:
            try:
                morsel = SimpleCookie(self.headers.get('Cookie', '')).get(viewer.cookie_name)
            except CookieError:
                morsel = None
            if morsel is not None and viewer.check_token(morsel.value):
                return 'cookie'
        self._fail(401, 'this viewer needs its token: open the URL the node logged at its '
                   'start (http://...?token=...), or send "Authorization: Bearer <token>"',
                   [('WWW-Authenticate', 'Bearer realm="py_vision"')])
        return None

    def do_GET(self):  # noqa: N802 (the name http.server looks for)
        viewer = self.server.viewer
        route, query = self._route()
        if self._authenticate(route, query) is None:
            return
        if route == '/':
            self._send(200, 'text/html; charset=utf-8', viewer._page)
        elif route == '/stats':
            body = json.dumps(viewer.stats(), sort_keys=True).encode()
            self._send(200, 'application/json', body)
        elif route == '/snapshot.jpg':
            jpeg = viewer._latest_jpeg()[1]
            if jpeg is None:
                self._send(503, 'text/plain; charset=utf-8', b'No frame received yet.\n',
                           [('Retry-After', '1')])
            else:
                self._send(200, 'image/jpeg', jpeg)
        elif route == '/stream':
            self._stream()
        elif route == '/camera':
            try:
                self._send_json(200, viewer.camera_state())
            except CameraError as error:
                self._fail(error.status, str(error))
        else:
            self._send(404, 'text/plain; charset=utf-8', b'Not found.\n')

    do_HEAD = do_GET  # noqa: N815 (same answers, _send() leaves the body out)

    def do_POST(self):  # noqa: N802 (the name http.server looks for)
        viewer = self.server.viewer
        route, query = self._route()
        how = self._authenticate(route, query)
        if how is None:
            return
        # A cross-site page can make a browser send a POST with the cookie, never with the
        # header, and never with a forged Origin: the Origin must be the page's own.
        origin = self.headers.get('Origin')
        own = 'http://%s' % self.headers.get('Host', '')
        if (origin is not None and origin != own) or (origin is None and how == 'cookie'):
            self._fail(403, "a change must come from the viewer's own page (Origin %s, "
                       'expected %s)' % (origin or 'missing', own))
            return
        if route != '/camera/controls':
            self._fail(405, 'only /camera/controls takes a POST', [('Allow', 'GET, HEAD')])
            return
        values = self._json_body()
        if values is None:
            return
        try:
            results = viewer.set_controls(values)
        except CameraError as error:
            self._fail(error.status, str(error))
            return
        except Exception as error:  # a defect: say so, and keep serving
            viewer._throttled('error', 'camera', 'viewer: setting controls failed: %s: %s' % (
                type(error).__name__, error))
            self._fail(500, 'setting the controls failed: %s' % type(error).__name__)
            return
        self._send_json(200, {'results': results})

    def _json_body(self):
        """Return the request's JSON object, or None when a refusal has been sent."""
        if 'chunked' in self.headers.get('Transfer-Encoding', '').lower():
            self._fail(411, 'send the body with a Content-Length')
            return None
        try:
            length = int(self.headers.get('Content-Length', ''))
        except ValueError:
            self._fail(411, 'send the body with a Content-Length')
            return None
        if length > MAX_BODY or length < 0:
            self._fail(413, 'the body is %d bytes; at most %d are taken' % (length, MAX_BODY))
            return None
        content_type = self.headers.get('Content-Type', '').split(';')[0].strip().lower()
        if content_type != 'application/json':
            self._fail(415, 'the body must be JSON (Content-Type: application/json), got %s' % (
                content_type or 'no Content-Type'))
            return None
        body = self.rfile.read(length)
        try:
            values = json.loads(body.decode('utf-8'))
        except (UnicodeDecodeError, ValueError) as error:
            self._fail(400, 'the body is not JSON: %s' % error)
            return None
        if not isinstance(values, dict) or not values:
            self._fail(400, 'the body must be a JSON object of control name: value, '
                       'e.g. {"brightness": 10}')
            return None
        return values

    def _send_json(self, code, value, extra=()):
        self._send(code, 'application/json', json.dumps(_json_safe(value)).encode(), extra)

    def _fail(self, code, reason, extra=()):
        """Refuse the request: JSON {"error": reason} with the status."""
        self._send_json(code, {'error': reason}, extra)

    def send_error(self, code, message=None, explain=None):
        # Replaces http.server's HTML error page (bad request line, unsupported method...).
        text = '%d %s\n' % (code, message or self.responses.get(code, ('Error',))[0])
        self._send(code, 'text/plain; charset=utf-8', text.encode())

    def log_message(self, format, *args):  # noqa: A002 (http.server's signature)
        pass  # one log line per request would bury the node's own log

    def _headers(self, code, content_type, extra=()):
        self.send_response(code)
        self.send_header('Content-Type', content_type)
        self.send_header('Cache-Control', 'no-store')
        self.send_header('X-Content-Type-Options', 'nosniff')
        # No other page may frame this one (and trick its user into moving the controls).
        self.send_header('X-Frame-Options', 'DENY')
        self.send_header('Connection', 'close')
        for name, value in extra:
            self.send_header(name, value)

    def _send(self, code, content_type, body, extra=()):
        self.close_connection = True
        self._headers(code, content_type, extra)
        self.send_header('Content-Length', str(len(body)))
        self.end_headers()
        if self.command != 'HEAD':
            self.wfile.write(body)

    def _stream(self):
        viewer = self.server.viewer
        if not viewer._take_stream_slot():
            viewer._throttled('warning', 'refused',
                              'viewer: refused a video client from %s, %d are watching '
                              '(the limit)' % (self.client_address[0], viewer.max_clients))
            self._send(503, 'text/plain; charset=utf-8',
                       b'Too many viewers are connected; close one and reload.\n',
                       [('Retry-After', '5')])
            return
        try:
            self.close_connection = True
            self._headers(200, 'multipart/x-mixed-replace; boundary=' + _BOUNDARY,
                          [('Pragma', 'no-cache')])
            self.end_headers()
            if self.command == 'HEAD':
                return
            # Each part is followed at once by the next boundary, which is what makes a browser
            # show it now rather than when the next frame comes.
            self.wfile.write(b'--%s\r\n' % _BOUNDARY.encode())
            sent = 0
            while True:
                number = viewer._wait_newer(sent, _IDLE_CHECK)
                if number is None:
                    return  # the viewer is closing
                if number == sent:
                    if self._client_gone():
                        return
                    continue
                sent, jpeg = viewer._latest_jpeg()
                self.wfile.write(b'Content-Type: image/jpeg\r\nContent-Length: %d\r\n\r\n%s'
                                 b'\r\n--%s\r\n' % (len(jpeg), jpeg, _BOUNDARY.encode()))
        except (OSError, ValueError):
            pass  # the client went away (reset, broken pipe, timeout) or the viewer closed
        finally:
            viewer._release_stream_slot()

    def _client_gone(self):
        """Return True when the peer closed its end (readable with nothing to read)."""
        try:
            poller = select.poll()  # unlike select.select(), fine with descriptors > 1023
            poller.register(self.connection, select.POLLIN)
            return bool(poller.poll(0)) and not self.connection.recv(1, socket.MSG_PEEK)
        except (OSError, ValueError):
            return True


class WebViewer:
    """Serve the newest submitted image to any number of browsers (up to max_clients)."""

    def __init__(self, host='127.0.0.1', port=8080, *, max_clients=8, jpeg_quality=80,
                 title='py_vision', logger=None, token=''):
        """
        Make a viewer for host:port; nothing is bound before start().

        token: what every request must carry (TOKEN_RULE; ValueError if not). Empty: none
        on a loopback host, and a random one (see `url`) on any other.
        """
        if not 1 <= int(max_clients):
            raise ValueError('max_clients must be at least 1, got %r' % max_clients)
        if not 0 <= int(jpeg_quality) <= 100:
            raise ValueError('jpeg_quality must be within 0..100, got %r' % jpeg_quality)
        self.host = host
        self.max_clients = int(max_clients)
        self._requested_port = int(port)
        self._jpeg_params = [cv2.IMWRITE_JPEG_QUALITY, int(jpeg_quality)]
        self._logger = logger if logger is not None else logging.getLogger(__name__)
        self._throttled = _ThrottledLog(self._logger)
        self._page = _page(title)
        if token:
            if not good_token(token):
                raise ValueError('token must be %s' % TOKEN_RULE)
            self.token = token
        else:
            self.token = None if is_loopback(host) else secrets.token_urlsafe(24)
        self._camera: Optional[CameraAccess] = None

        self._frame_lock = threading.Condition()
        self._frame = None
        self._frame_number = 0
        self._closing = False

        self._encode_lock = threading.Lock()
        self._jpeg = None
        self._jpeg_number = 0
        self._encoded = 0

        self._lock = threading.Lock()  # guards what follows
        self._stats = {}
        self._connections = set()
        self._streams = 0

        self._server = None
        self._thread = None

    def start(self):
        """Bind and serve in daemon threads; raise WebViewerError if the address is unusable."""
        if self._server is not None:
            return
        family = socket.AF_INET6 if ':' in self.host else socket.AF_INET
        try:
            self._server = _Server(self, (self.host, self._requested_port), family)
        except (OSError, OverflowError) as error:
            reason = getattr(error, 'strerror', None) or str(error)
            advice = 'choose another web_port'
            if isinstance(error, socket.gaierror) or (
                    getattr(error, 'errno', None) == errno.EADDRNOTAVAIL):
                advice = 'web_host must be an address or name of this machine'
            raise WebViewerError('cannot serve the browser viewer on %s:%d: %s; %s' % (
                self.host, self._requested_port, reason, advice)) from None
        self._thread = threading.Thread(target=self._server.serve_forever, args=(0.1,),
                                        name='web_viewer', daemon=True)
        self._thread.start()

    @property
    def port(self):
        """Return the port really bound (the requested one, or the ephemeral one for port 0)."""
        return self._server.server_address[1] if self._server else self._requested_port

    @property
    def url(self):
        """
        Return the address to open in a browser, with the token when one is needed.

        The host name when bound to all interfaces.
        """
        host = socket.gethostname() if self.host in _WILDCARD_HOSTS else self.host
        if ':' in host:
            host = '[%s]' % host
        url = 'http://%s:%d/' % (host, self.port)
        return url + ('?token=' + self.token if self.token else '')

    @property
    def cookie_name(self):
        """Return the cookie the page keeps the token in (one per port: cookies ignore ports)."""
        return 'py_vision_token_%d' % self.port

    def check_token(self, given):
        """Return True when given is the token (in constant time)."""
        return self.token is not None and hmac.compare_digest(
            given.encode('utf-8', 'replace'), self.token.encode())

    def set_camera(self, camera: Optional[CameraAccess]):
        """Serve /camera and /camera/controls from camera (None: 404, no panel on the page)."""
        self._camera = camera

    def camera_state(self):
        """Return GET /camera's answer: the camera's, with the size and rate of what is shown."""
        camera = self._camera
        if camera is None:
            raise CameraError(404, 'this viewer has no camera panel')
        state = dict(camera.describe())
        with self._lock:
            stats = dict(self._stats)
        shown = {'topic': stats.get('topic'), 'fps': stats.get('fps')}
        if stats.get('width') and stats.get('height'):
            shown['size'] = '%dx%d' % (stats['width'], stats['height'])
        state['shown'] = shown
        return _json_safe(state)

    def set_controls(self, values):
        """Apply POST /camera/controls; return name: {applied, reason}."""
        camera = self._camera
        if camera is None:
            raise CameraError(404, 'this viewer has no camera panel')
        return camera.set_controls(values)

    def submit(self, image):
        """
        Make image (uint8 BGR HxWx3 or mono HxW) the newest frame; it must not change later.

        Costs O(1) whatever the clients do: no copy, no encoding, no waiting on sockets.
        """
        if not isinstance(image, np.ndarray):
            raise ValueError('the viewer shows numpy images, got %s' % type(image).__name__)
        if image.dtype != np.uint8 or not (
                image.ndim == 2 or (image.ndim == 3 and image.shape[2] in (1, 3))):
            raise ValueError('the viewer shows uint8 BGR (HxWx3) or mono (HxW) images, got %s %s'
                             % (image.dtype, image.shape))
        with self._frame_lock:
            self._frame = image
            self._frame_number += 1
            self._frame_lock.notify_all()

    def submit_jpeg(self, jpeg):
        """Make an already encoded JPEG (bytes) the newest frame; it is served as it is."""
        if not isinstance(jpeg, bytes) or jpeg[:2] != b'\xff\xd8':
            raise ValueError('submit_jpeg takes the bytes of a JPEG image')
        with self._frame_lock:
            self._frame = jpeg
            self._frame_number += 1
            self._frame_lock.notify_all()

    def set_stats(self, stats):
        """Set the JSON-able dict /stats and the page show (fps, latency, size, topic...)."""
        with self._lock:
            self._stats = dict(stats)

    def stats(self):
        """Return the stats last set plus the viewer's own counters, ready for JSON."""
        with self._lock:
            result = dict(self._stats)
            result['clients'] = self._streams
        result['encoded_frames'] = self._encoded
        result['viewer_frames'] = self._frame_number
        return _json_safe(result)

    @property
    def client_count(self):
        """How many video clients (/stream) are connected now."""
        with self._lock:
            return self._streams

    @property
    def encoded_frames(self):
        """How many frames were JPEG-encoded so far (at most one per submitted frame)."""
        return self._encoded

    def close(self):
        """Stop serving, drop every client and release the port; safe to call twice."""
        with self._frame_lock:
            self._closing = True
            self._frame_lock.notify_all()
        server, self._server = self._server, None
        if server is None:
            return
        server.shutdown()
        server.server_close()
        with self._lock:
            connections = list(self._connections)
        for connection in connections:
            try:
                connection.shutdown(socket.SHUT_RDWR)
            except OSError:
                pass
        self._thread.join(1.0)

    # What the request handlers use.

    def _open_connection(self, connection):
        with self._lock:
            if self._closing or len(self._connections) >= self.max_clients + _EXTRA_CONNECTIONS:
                return False
            self._connections.add(connection)
            return True

    def _close_connection(self, connection):
        with self._lock:
            self._connections.discard(connection)

    def _take_stream_slot(self):
        with self._lock:
            if self._streams >= self.max_clients:
                return False
            self._streams += 1
            return True

    def _release_stream_slot(self):
        with self._lock:
            self._streams -= 1

    def _wait_newer(self, number, timeout):
        """Wait for a frame newer than number; return the newest number (None when closing)."""
        with self._frame_lock:
            self._frame_lock.wait_for(
                lambda: self._closing or self._frame_number != number, timeout)
            return None if self._closing else self._frame_number

    def _latest_jpeg(self):
        """Return (number, JPEG bytes) of the newest frame, encoding it if nobody did yet."""
        with self._encode_lock:
            with self._frame_lock:
                number, frame = self._frame_number, self._frame
            if frame is None:
                return 0, None
            if number != self._jpeg_number and isinstance(frame, bytes):
                self._jpeg, self._jpeg_number = frame, number
            elif number != self._jpeg_number:
                ok, buffer = cv2.imencode('.jpg', frame, self._jpeg_params)
                if not ok:
                    raise ValueError('JPEG encoding failed for a %s frame' % (frame.shape,))
                self._jpeg, self._jpeg_number = buffer.tobytes(), number
                self._encoded += 1
            return self._jpeg_number, self._jpeg

    def _log_handler_error(self, client_address):
        self._throttled('warning', 'handler',
                        'viewer: a request from %s failed and was dropped' % (client_address[0],))


def _page(title):
    """Return the viewer page: one HTML document with inline CSS and JS, nothing external."""
    return _PAGE.replace('{{title}}', html.escape(title)).encode()


_PAGE = """<!DOCTYPE html>
<html lang="en">
<head>
<meta charset="utf-8">
<meta name="viewport" content="width=device-width, initial-scale=1">
<meta http-equiv="Content-Security-Policy" content="default-src 'none'; img-src 'self';
 connect-src 'self'; style-src 'unsafe-inline'; script-src 'unsafe-inline'">
<title>{{title}}</title>
<style>
  :root { color-scheme: dark; --fg: #e8eaed; --dim: #9aa0a6; --card: #202124;
          --line: #3c4043; --ok: #81c995; --bad: #f28b82; }
  * { box-sizing: border-box; }
  body { margin: 0; background: #121212; color: var(--fg);
         font: 14px/1.4 system-ui, -apple-system, "Segoe UI", Roboto, sans-serif; }
  header { display: flex; align-items: center; gap: 12px; padding: 10px 18px;
           border-bottom: 1px solid var(--line); }
  h1 { font-size: 17px; font-weight: 600; margin: 0; }
  #status { margin-left: auto; font-size: 13px; color: var(--dim); }
  #status::before { content: ""; display: inline-block; width: 9px; height: 9px;
                    border-radius: 50%; margin-right: 6px; background: var(--dim); }
  #status.live::before { background: var(--ok); }
  #status.down::before { background: var(--bad); }
  main { display: flex; flex-wrap: wrap; gap: 18px; padding: 18px; align-items: flex-start; }
  .video { position: relative; flex: 0 1 auto; min-width: 320px; min-height: 240px;
           background: #000; border: 1px solid var(--line); border-radius: 8px;
           overflow: hidden; }
  /* Natural size when it fits (no blur), scaled down with its aspect ratio when not. */
  #video { display: block; max-width: 100%; max-height: calc(100vh - 100px); width: auto;
           height: auto; margin: 0 auto; }
  #overlay { position: absolute; inset: 0; display: flex; align-items: center;
             justify-content: center; padding: 20px; text-align: center; color: var(--dim);
             background: rgba(0, 0, 0, .6); }
  #overlay[hidden] { display: none; }
  aside { flex: 0 0 290px; background: var(--card); border: 1px solid var(--line);
          border-radius: 8px; padding: 14px 16px; }
  dl { display: grid; grid-template-columns: auto 1fr; gap: 7px 14px; margin: 0; }
  dt { color: var(--dim); }
  dd { margin: 0; text-align: right; font-variant-numeric: tabular-nums;
       overflow-wrap: anywhere; }
  .links { margin-top: 14px; font-size: 12px; color: var(--dim); }
  a { color: #8ab4f8; }
  .column { display: flex; flex-direction: column; gap: 18px; flex: 0 1 auto; min-width: 320px; }
  #stats { flex: none; }
  #stats dl { grid-template-columns: auto 1fr auto 1fr; }
  #panel { flex: 0 0 300px; }
  h2 { font-size: 14px; font-weight: 600; margin: 0 0 10px; }
  h3 { font-size: 12px; font-weight: 600; color: var(--dim); text-transform: uppercase;
       letter-spacing: .05em; margin: 14px 0 8px; }
  #panel-message { color: var(--dim); margin: 0 0 10px; }
  #panel-message:empty { display: none; }
  .control { display: grid; grid-template-columns: 1fr auto; gap: 2px 10px; margin: 0 0 10px; }
  .control label { overflow-wrap: break-word; }
  .control .value { color: var(--dim); font-variant-numeric: tabular-nums; text-align: right; }
  .control input[type=checkbox] { margin: 0 0 0 8px; vertical-align: middle; }
  .control input[type=range], .control select, .control input[type=text] {
    grid-column: 1 / 3; width: 100%; }
  .control.unset input[type=range] { opacity: .45; }
  .control .note { grid-column: 1 / 3; color: var(--bad); font-size: 12px; }
  .control .note:empty { display: none; }
  .control .why { grid-column: 1 / 3; color: var(--dim); font-size: 12px; }
  .control .why:empty { display: none; }
  .control.inactive label { color: var(--dim); }
  select, input[type=text] { background: #303134; color: var(--fg); border: 1px solid var(--line);
                             border-radius: 4px; padding: 2px 4px; font: inherit; }
  button { background: #303134; color: var(--fg); border: 1px solid var(--line);
           border-radius: 6px; padding: 6px 12px; font: inherit; cursor: pointer; }
</style>
</head>
<body>
<header>
  <h1>{{title}}</h1>
  <span id="status">connecting</span>
</header>
<main>
  <div class="column">
    <div class="video">
      <img id="video" src="/stream" alt="live video">
      <div id="overlay" hidden></div>
    </div>
    <aside id="stats">
      <h2>stream</h2>
      <dl>
        <dt>topic</dt><dd id="stat-topic">-</dd>
        <dt>fps</dt><dd id="stat-fps">-</dd>
        <dt>latency p50</dt><dd id="stat-latency">-</dd>
        <dt>latency p99</dt><dd id="stat-latency-p99">-</dd>
        <dt>resolution</dt><dd id="stat-resolution">-</dd>
        <dt>encoding</dt><dd id="stat-encoding">-</dd>
        <dt>frames</dt><dd id="stat-frames">-</dd>
        <dt class="proc" hidden>frames in</dt><dd class="proc" id="stat-in" hidden>-</dd>
        <dt class="proc" hidden>processed</dt><dd class="proc" id="stat-processed" hidden>-</dd>
        <dt class="proc" hidden>skipped</dt><dd class="proc" id="stat-skipped" hidden>-</dd>
        <dt class="proc" hidden>processing p50</dt>
        <dd class="proc" id="stat-processing" hidden>-</dd>
        <dt class="proc" hidden>processing p99</dt>
        <dd class="proc" id="stat-processing-p99" hidden>-</dd>
        <dt class="proc" hidden>output age p50</dt><dd class="proc" id="stat-age" hidden>-</dd>
        <dt class="proc" hidden>output age p99</dt><dd class="proc" id="stat-age-p99" hidden>-</dd>
        <dt>viewers</dt><dd id="stat-clients">-</dd>
      </dl>
      <div class="links"><button id="snapshot" type="button">snapshot</button>
        <a href="/stats">stats JSON</a> &middot;
        <a href="/camera">camera JSON</a></div>
    </aside>
  </div>
  <aside id="panel" hidden>
    <h2>camera</h2>
    <p id="panel-message"></p>
    <dl>
      <dt>node</dt><dd id="cam-node">-</dd>
      <dt>device</dt><dd id="cam-device">-</dd>
      <dt>format</dt><dd id="cam-format">-</dd>
      <dt>size</dt><dd id="cam-size">-</dd>
      <dt>rate</dt><dd id="cam-rate">-</dd>
      <dt>status</dt><dd id="cam-status">-</dd>
    </dl>
    <div id="controls"></div>
  </aside>
</main>
<script>
"use strict";
(function () {
  const video = document.getElementById("video");
  const overlay = document.getElementById("overlay");
  const status = document.getElementById("status");
  let retry = null;

  function show(id, text) { document.getElementById(id).textContent = text; }
  function num(value, digits, unit) {
    return (typeof value === "number") ? value.toFixed(digits) + (unit || "") : "-";
  }
  function setStatus(text, cls) { status.textContent = text; status.className = cls; }

  function connectVideo() {
    retry = null;
    video.src = "/stream?t=" + Date.now();
  }
  function message(text) { overlay.textContent = text; overlay.hidden = !text; }
  video.addEventListener("error", function () {
    message("video unavailable (too many viewers, or the node stopped); retrying");
    if (!retry && !document.hidden) { retry = setTimeout(connectVideo, 3000); }
  });
  // A hidden tab stops its stream, so background tabs cost the robot nothing.
  document.addEventListener("visibilitychange", function () {
    if (document.hidden) { video.removeAttribute("src"); } else { connectVideo(); }
  });

  // One request at a time, one per second: the page never floods the server.
  async function poll() {
    try {
      const response = await fetch("/stats", { cache: "no-store" });
      if (!response.ok) { throw new Error(response.status); }
      const s = await response.json();
      show("stat-topic", s.topic || "-");
      show("stat-fps", num(s.fps, 1));
      show("stat-latency", num(s.latency_ms_p50, 1, " ms"));
      show("stat-latency-p99", num(s.latency_ms_p99, 1, " ms"));
      show("stat-resolution", (s.width && s.height) ? s.width + " \\u00d7 " + s.height : "-");
      show("stat-encoding", s.encoding || "-");
      show("stat-frames", (typeof s.frames === "number") ? String(s.frames) : "-");
      show("stat-clients", String(s.clients));
      // A processing node (cv_bridge_test) also reports what it skipped and how long it took.
      const processing = typeof s.frames_in === "number";
      document.querySelectorAll(".proc").forEach(function (e) { e.hidden = !processing; });
      if (processing) {
        show("stat-in", String(s.frames_in));
        show("stat-processed", String(s.processed));
        show("stat-skipped", String(s.skipped));
        show("stat-processing", num(s.processing_ms_p50, 1, " ms"));
        show("stat-processing-p99", num(s.processing_ms_p99, 1, " ms"));
        show("stat-age", num(s.age_ms_p50, 1, " ms"));
        show("stat-age-p99", num(s.age_ms_p99, 1, " ms"));
      }
      if (s.viewer_frames > 0) {
        setStatus("live", "live");
        if (!retry) { message(""); }
      } else {
        setStatus("waiting for frames", "");
        message("waiting for the first frame");
      }
    } catch (e) {
      setStatus("disconnected", "down");
    }
    setTimeout(poll, 1000);
  }
  poll();

  // The camera panel: what the camera is and its controls, from GET /camera once a second
  // (a change made elsewhere shows within a second); a change is sent at once, and while a
  // slider moves at most one request per control is on its way.
  const panel = document.getElementById("panel");
  const controlsBox = document.getElementById("controls");
  let layout = null;
  const widgets = {};
  const busy = {};
  const queued = {};

  function describeValue(c, value) {
    if (value === null || value === undefined) { return "camera\u2019s own value"; }
    if (c.menu) {
      const entry = c.menu.find(function (m) { return m.value === value; });
      return entry ? entry.label : String(value);
    }
    if (typeof value === "boolean") { return value ? "on" : "off"; }
    return String(value);
  }

  function makeControl(name, c) {
    const box = document.createElement("div");
    box.className = "control";
    box.id = "control-" + name;
    const label = document.createElement("label");
    label.textContent = name.replace(/_/g, " ");
    label.title = c.description || "";
    const value = document.createElement("span");
    value.className = "value";
    const note = document.createElement("span");
    note.className = "note";
    const why = document.createElement("span");
    why.className = "why";
    let input;
    if (c.menu) {
      // The menu shows the chosen entry itself: its label is not repeated beside the name.
      value.hidden = true;
      input = document.createElement("select");
      const own = document.createElement("option");
      own.value = "";
      own.textContent = "camera\u2019s own value";
      own.disabled = true;
      input.appendChild(own);
      c.menu.forEach(function (m) {
        const option = document.createElement("option");
        option.value = String(m.value);
        option.textContent = m.label;
        input.appendChild(option);
      });
    } else if (c.type === "bool") {
      input = document.createElement("input");
      input.type = "checkbox";
    } else if (typeof c.min === "number" && typeof c.max === "number") {
      input = document.createElement("input");
      input.type = "range";
      input.min = c.min;
      input.max = c.max;
      input.step = c.step > 0 ? c.step : (c.type === "integer" ? 1 : "any");
    } else {
      input = document.createElement("input");
      input.type = "text";
    }
    input.name = name;
    input.disabled = c.read_only;
    label.htmlFor = input.id = "input-" + name;
    input.addEventListener("pointerdown", function () { busy[name] = true; });
    input.addEventListener(input.type === "range" ? "input" : "change", function () {
      let v;
      if (input.type === "checkbox") { v = input.checked; }
      else if (c.type === "integer") { v = parseInt(input.value, 10); }
      else if (c.type === "double") { v = parseFloat(input.value); }
      else { v = input.value; }
      value.textContent = describeValue(c, v);
      send(name, v);
    });
    ["change", "pointerup", "pointercancel"].forEach(function (event) {
      input.addEventListener(event, function () { busy[name] = false; });
    });
    if (input.type === "checkbox") {
      value.appendChild(document.createTextNode(""));
      const right = document.createElement("span");
      right.className = "value";
      right.append(value, input);
      box.append(label, right, why, note);
    } else {
      box.append(label, value, input, why, note);
    }
    widgets[name] = { box: box, input: input, value: value, note: note, why: why, spec: c };
    return box;
  }

  function showValue(name, c) {
    const w = widgets[name];
    w.spec = c;
    w.box.classList.toggle("unset", c.value === null);
    w.box.classList.toggle("inactive", Boolean(c.inactive));
    w.why.textContent = c.inactive ? "inactive " + c.inactive : "";
    w.value.textContent = describeValue(c, c.value);
    if (busy[name] || name in queued) { return; }
    if (w.input.type === "checkbox") {
      w.input.indeterminate = c.value === null;
      w.input.checked = c.value === true;
    } else if (w.input.tagName === "SELECT") {
      w.input.value = c.value === null ? "" : String(c.value);
    } else if (c.value !== null) {
      w.input.value = String(c.value);
    } else if (w.input.type === "range") {
      w.input.value = String((Number(c.min) + Number(c.max)) / 2);
    }
  }

  function renderCamera(cam) {
    panel.hidden = false;
    show("panel-message", cam.message || "");
    const info = cam.camera || {};
    const shown = cam.shown || {};
    show("cam-node", cam.publisher || "-");
    show("cam-device", info.device || "-");
    show("cam-format", info.pixel_format || "-");
    show("cam-size", info.size || shown.size || "-");
    const rates = [];
    if (typeof shown.fps === "number") { rates.push(shown.fps.toFixed(1) + " fps shown"); }
    if (typeof info.fps === "number") { rates.push(info.fps.toFixed(1) + " fps at the camera"); }
    show("cam-rate", rates.join(", ") || "-");
    show("cam-status", info.status || "-");
    // A control under a second name (usb_cam's) is shown once, under the camera's name.
    const all = cam.controls || {};
    const controls = {};
    Object.keys(all).forEach(function (n) {
      if (!(all[n].alias_of && all[n].alias_of in all)) { controls[n] = all[n]; }
    });
    const key = JSON.stringify(Object.keys(controls).map(function (n) {
      const c = controls[n];
      return [n, c.type, c.min, c.max, c.step, c.menu, c.read_only, c.group];
    }));
    if (key !== layout) {
      layout = key;
      controlsBox.textContent = "";
      Object.keys(widgets).forEach(function (n) { delete widgets[n]; });
      let group = null;
      Object.keys(controls).forEach(function (n) {
        if (controls[n].group !== group) {
          group = controls[n].group;
          const h = document.createElement("h3");
          h.textContent = group === "stream" ? "stream settings" : "controls";
          controlsBox.appendChild(h);
        }
        controlsBox.appendChild(makeControl(n, controls[n]));
      });
    }
    Object.keys(controls).forEach(function (n) { showValue(n, controls[n]); });
  }

  async function send(name, v) {
    queued[name] = v;
    if (busy[name + "/sending"]) { return; }
    busy[name + "/sending"] = true;
    const w = widgets[name];
    while (name in queued) {
      const body = {};
      body[name] = queued[name];
      delete queued[name];
      try {
        const response = await fetch("/camera/controls", {
          method: "POST", cache: "no-store", body: JSON.stringify(body),
          headers: { "Content-Type": "application/json" } });
        const answer = await response.json();
        const result = response.ok ? answer.results[name] : { applied: false,
                                                               reason: answer.error };
        if (w) { w.note.textContent = result.applied ? "" : "refused: " + result.reason; }
      } catch (e) {
        if (w) { w.note.textContent = "not sent: the viewer does not answer"; }
      }
    }
    busy[name + "/sending"] = false;
  }

  async function pollCamera() {
    try {
      const response = await fetch("/camera", { cache: "no-store" });
      if (response.status === 404) {  // no camera panel (yet): ask again now and then
        panel.hidden = true;
        setTimeout(pollCamera, 5000);
        return;
      }
      if (response.ok) { renderCamera(await response.json()); }
    } catch (e) {
      // the node stopped: the status line says so; keep trying
    }
    setTimeout(pollCamera, 1000);
  }
  pollCamera();

  document.getElementById("snapshot").addEventListener("click", function () {
    const link = document.createElement("a");
    link.href = "/snapshot.jpg";
    link.download = "snapshot-" + new Date().toISOString().replace(/[:.]/g, "-") + ".jpg";
    document.body.appendChild(link);
    link.click();
    link.remove();
  });
})();
</script>
</body>
</html>
"""
