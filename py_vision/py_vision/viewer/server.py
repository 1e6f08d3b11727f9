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
The browser viewer's HTTP server: live images over HTTP, with the standard library only.

It serves the addresses in `ROUTES` and nothing else: the page (its three files, read once
from ``page/``), the MJPEG stream, a snapshot, a camera's H.264 for the page to decode itself
(`video`), the statistics as JSON, and the camera panel's API, which a `CameraAccess` given
to ``set_camera()`` answers (no ROS here). Who may ask what is `access`'s. Every client has
its own thread and always gets the newest frame (`frames`), so a slow client skips frames
instead of slowing the producer or the other clients. The number of video clients and of
connections is bounded; further ones get a short 503 answer.
"""

import collections
from dataclasses import dataclass
import errno
import html
from http.server import BaseHTTPRequestHandler, HTTPServer
from importlib import resources
import io
import ipaddress
import json
import logging
import math
import select
import socket
from socketserver import ThreadingMixIn
import sys
import threading
import time
from typing import Callable, Dict, Optional, Tuple

import numpy as np
from py_vision.throttled_log import ThrottledLog
from py_vision.viewer.access import Access, Refusal
from py_vision.viewer.camera_access import CameraAccess, CameraError
from py_vision.viewer.frames import FrameStore
from py_vision.viewer.video import frame, VideoStore

_BOUNDARY = 'py_vision_frame'
# A client that accepts no data for this long (it vanished or stalled) is dropped.
_SOCKET_TIMEOUT = 10.0
# A request's line and headers must have arrived this long after its connection opened (a
# browser sends them at once); only then is the token checked. The body, of a request that
# passed the check, must have arrived whole this long after the connection opened.
_HEAD_TIME = 2.0
_REQUEST_TIME = 10.0
# How often an idle stream thread checks that its client is still there.
_IDLE_CHECK = 1.0
# Short requests (the page, /stats, snapshots) beyond the video clients: enough for every
# tab's stats poll, small enough to bound the threads a misbehaving client can make us start.
_EXTRA_CONNECTIONS = 16
# Connections whose request has not arrived and passed the access check yet: at most this
# many from one address, and this many in all. They never take the places of the requests
# that passed it, so clients without the token cannot starve one with it.
_PENDING_PER_ADDRESS = 8
_PENDING = 32
# The largest request body taken (a POST of controls is a few hundred bytes).
MAX_BODY = 16384
# A snapshot asked for keeps a video stream decoded here this long (the next one is ready).
_SNAPSHOT_INTEREST = 10.0
# What the page may load and from where: its own files, nothing inline, nothing elsewhere.
_POLICY = ("default-src 'none'; img-src 'self'; connect-src 'self'; style-src 'self'; "
           "script-src 'self'; base-uri 'none'; form-action 'none'; frame-ancestors 'none'")
# The page's files (in page/, installed with the package) and the route of each.
_PAGE_FILES = {'/': ('index.html', 'text/html; charset=utf-8'),
               '/viewer.js': ('viewer.js', 'text/javascript; charset=utf-8'),
               '/viewer.css': ('viewer.css', 'text/css; charset=utf-8')}


class WebViewerError(Exception):
    """The viewer cannot serve (the address is in use or unusable); the message says why."""


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


def _text_problem(text: str) -> str:
    try:
        text.encode('utf-8')
    except UnicodeEncodeError:
        return '%s is not text (it holds a lone UTF-16 surrogate)' % ascii(text)[:40]
    return ''


def _controls_problem(values) -> str:
    """Return why a parsed POST body is not an object of control name: value ('' if it is)."""
    if not isinstance(values, dict) or not values:
        return 'the body must be a JSON object of control name: value, e.g. {"brightness": 10}'
    for name, value in values.items():
        problem = _text_problem(name)
        if not problem and isinstance(value, str):
            problem = _text_problem(value)
        elif not problem and not isinstance(value, (bool, int, float)):
            problem = 'the value of %s must be a number, a string, true or false' % name
        if problem:
            return problem
    return ''


def page_files(title: str) -> Dict[str, Tuple[str, bytes]]:
    """Return route: (content type, bytes) of the page's files, the title written in."""
    folder = resources.files('py_vision.viewer').joinpath('page')
    served = {}
    for route, (name, content_type) in _PAGE_FILES.items():
        text = folder.joinpath(name).read_text(encoding='utf-8')
        served[route] = (content_type, text.replace('{{title}}', html.escape(title)).encode())
    return served


class Connections:
    """
    The connections a viewer holds, each kind bounded.

    Pending ones (per address and in all), and those whose request passed the access check,
    video clients among them. A new connection is pending until its request has arrived and
    passed the check (`trust`). When the pending places are all taken, the address holding the
    most gives up its oldest, so that one address, or a few, flooding the viewer cannot keep
    out a client from another.
    """

    def __init__(self, max_clients: int):
        if not 1 <= int(max_clients):
            raise ValueError('max_clients must be at least 1, got %r' % max_clients)
        self.max_clients = int(max_clients)
        self._lock = threading.Lock()
        self._pending: Dict[socket.socket, str] = {}   # connection: address, oldest first
        self._trusted = set()
        self._streams = 0
        self._closing = False

    def add(self, connection: socket.socket, address: str) -> bool:
        """Count a new connection in as pending; False when it is refused."""
        evicted = None
        with self._lock:
            if self._closing:
                return False
            held = collections.Counter(self._pending.values())
            if held[address] >= _PENDING_PER_ADDRESS:
                return False
            if len(self._pending) >= _PENDING:
                greedy, most = held.most_common(1)[0]
                if most <= held[address] + 1:
                    return False
                evicted = next(c for c, a in self._pending.items() if a == greedy)
                del self._pending[evicted]
            self._pending[connection] = address
        if evicted is not None:
            _shut(evicted)  # its thread sees the end of its request and closes it
        return True

    def trust(self, connection: socket.socket) -> bool:
        """Count a connection whose request passed the access check; False when too many."""
        with self._lock:
            self._pending.pop(connection, None)
            if len(self._trusted) >= self.max_clients + _EXTRA_CONNECTIONS:
                return False
            self._trusted.add(connection)
            return True

    def remove(self, connection: socket.socket) -> None:
        """Count a connection out."""
        with self._lock:
            self._pending.pop(connection, None)
            self._trusted.discard(connection)

    def take_stream(self) -> bool:
        """Take a video client's place; False when all are taken."""
        with self._lock:
            if self._streams >= self.max_clients:
                return False
            self._streams += 1
            return True

    def release_stream(self) -> None:
        """Give a video client's place back."""
        with self._lock:
            self._streams -= 1

    @property
    def streams(self) -> int:
        """Return how many video clients are connected now."""
        with self._lock:
            return self._streams

    def close_all(self) -> None:
        """Refuse new connections and shut the open ones down."""
        with self._lock:
            self._closing = True
            connections = list(self._pending) + list(self._trusted)
        for connection in connections:
            _shut(connection)


def _shut(connection: socket.socket) -> None:
    try:
        connection.shutdown(socket.SHUT_RDWR)
    except OSError:
        pass


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
        if not self.viewer.connections.add(request, client_address[0]):
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
        self.viewer.connections.remove(request)
        super().shutdown_request(request)

    def handle_error(self, request, client_address):
        if isinstance(sys.exc_info()[1], OSError):
            return  # the client went away (reset, broken pipe) or was dropped for another
        self.viewer.log.warning('handler', 'viewer: a request from %s failed and was dropped'
                                % (client_address[0],))


class _RequestReader(io.RawIOBase):
    """The request side of one connection: every read ends by the request's deadline."""

    def __init__(self, connection: socket.socket, deadline: float):
        super().__init__()
        self._connection = connection
        self.deadline = deadline  # time.monotonic() by which the request must have arrived

    def readable(self) -> bool:
        return True

    def readinto(self, buffer) -> int:
        left = self.deadline - time.monotonic()
        if left <= 0:
            raise TimeoutError('the request did not arrive in time')
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
        self._opened = time.monotonic()
        self._reader = _RequestReader(self.connection, self._opened + _HEAD_TIME)
        self.rfile = io.BufferedReader(self._reader)

    def version_string(self):
        return 'py_vision'

    def _target(self):
        """Return (route, query): the target as the client sent it, split at '?'."""
        # http.server folds a leading '//' in self.path; exact matches only: '//stream',
        # '/stream/', '/../x', '/%2e%2e/' are all 404.
        target = self.requestline.split()[1]
        route, _, query = target.split('#', 1)[0].partition('?')
        return route, query

    def _dispatch(self):
        viewer = self.server.viewer
        route, query = self._target()
        served = ROUTES.get(route)
        how = viewer.access.authenticate(self.command, route, query, self.headers)
        if isinstance(how, Refusal):
            self._refuse(how)
            return
        refusal = viewer.access.site_refusal(served is not None and served.page, self.headers)
        if refusal is None and self.command == 'POST':
            refusal = viewer.access.change_refusal(how, self.headers)
        if refusal is not None:
            self._refuse(refusal)
            return
        if not viewer.connections.trust(self.connection):
            self._send(503, 'text/plain; charset=utf-8', b'Too many requests at once; retry.\n',
                       [('Retry-After', '1')])
            return
        self._reader.deadline = self._opened + _REQUEST_TIME  # for the body
        if served is None:
            self._send(404, 'text/plain; charset=utf-8', b'Not found.\n')
        elif self.command not in served.methods:
            self._fail(405, '%s takes %s' % (route, ', '.join(served.methods)),
                       [('Allow', ', '.join(served.methods))])
        else:
            served.serve(self, route)

    do_GET = do_HEAD = do_POST = _dispatch  # noqa: N815 (the names http.server looks for)

    # The routes' answers.

    def serve_page(self, route):
        content_type, body = self.server.viewer.page[route]
        self._send(200, content_type, body)

    def serve_stats(self, route):
        body = json.dumps(self.server.viewer.stats(), sort_keys=True).encode()
        self._send(200, 'application/json', body)

    def serve_snapshot(self, route):
        self.server.viewer.snapshot_asked = time.monotonic()
        jpeg = self.server.viewer.frames.latest_jpeg()[1]
        if jpeg is None:
            self._send(503, 'text/plain; charset=utf-8', b'No frame received yet.\n',
                       [('Retry-After', '1')])
        else:
            self._send(200, 'image/jpeg', jpeg)

    def serve_camera(self, route):
        try:
            self._send_json(200, self.server.viewer.camera_state())
        except CameraError as error:
            self._fail(error.status, str(error))

    def serve_controls(self, route):
        self._serve_set(self.server.viewer.set_controls, 'the controls')

    def serve_step(self, route):
        self._serve_set(self.server.viewer.set_step_parameters, 'the step parameters')

    def _serve_set(self, setter, what):
        viewer = self.server.viewer
        values = self._json_body()
        if values is None:
            return
        try:
            results = setter(values)
        except CameraError as error:
            self._fail(error.status, str(error))
            return
        except Exception as error:  # a defect: say so, and keep serving
            viewer.log.error('camera', 'viewer: setting %s failed: %s: %s' % (
                what, type(error).__name__, error))
            self._fail(500, 'setting %s failed: %s' % (what, type(error).__name__))
            return
        self._send_json(200, {'results': results})

    def serve_stream(self, route):
        viewer = self.server.viewer
        connections = viewer.connections
        if not connections.take_stream():
            viewer.log.warning('refused', 'viewer: refused a video client from %s, %d are '
                               'watching (the limit)' % (self.client_address[0],
                                                         connections.max_clients))
            self._send(503, 'text/plain; charset=utf-8',
                       b'Too many viewers are connected; close one and reload.\n',
                       [('Retry-After', '5')])
            return
        viewer.pixel_clients(+1)
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
                number = viewer.frames.wait_newer(sent, _IDLE_CHECK)
                if number is None:
                    return  # the viewer is closing
                if number == sent:
                    if self._client_gone():
                        return
                    continue
                sent, jpeg = viewer.frames.latest_jpeg()
                self.wfile.write(b'Content-Type: image/jpeg\r\nContent-Length: %d\r\n\r\n%s'
                                 b'\r\n--%s\r\n' % (len(jpeg), jpeg, _BOUNDARY.encode()))
        except (OSError, ValueError):
            pass  # the client went away (reset, broken pipe, timeout) or the viewer closed
        finally:
            viewer.pixel_clients(-1)
            connections.release_stream()

    def serve_video(self, route):
        viewer = self.server.viewer
        connections = viewer.connections
        if not viewer.video.number:
            self._fail(404, 'this viewer shows no H.264 stream')
            return
        if not connections.take_stream():
            self._fail(503, 'too many viewers are connected; close one and reload',
                       [('Retry-After', '5')])
            return
        try:
            self.close_connection = True
            # The body is the units, framed (video.frame), until the connection closes.
            self._headers(200, 'application/octet-stream',
                          [('X-Video-Codec', viewer.video.codec)])
            self.end_headers()
            if self.command == 'HEAD':
                return
            sent = 0
            while True:
                got = viewer.video.since(sent, _IDLE_CHECK)
                if got is None:
                    return  # the viewer is closing
                newest, units = got
                if not units and newest == sent and self._client_gone():
                    return
                sent = newest
                for unit, start in units:
                    self.wfile.write(frame(unit, start))
        except (OSError, ValueError):
            pass  # the client went away, or the viewer closed
        finally:
            connections.release_stream()

    # Reading and answering.

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
        except RecursionError:
            self._fail(400, 'the body is not a JSON object of control name: value: it nests '
                       'too deep')
            return None
        problem = _controls_problem(values)
        if problem:
            self._fail(400, problem)
            return None
        return values

    def _refuse(self, refusal: Refusal):
        if refusal.status < 400:  # the redirect that sets the cookie
            self._send(refusal.status, 'text/plain; charset=utf-8',
                       refusal.reason.encode() + b'\n', refusal.headers)
        else:
            self._fail(refusal.status, refusal.reason, refusal.headers)

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
        # No other page may frame this one (and trick its user into moving the controls), nor
        # show its video or snapshot in itself.
        self.send_header('X-Frame-Options', 'DENY')
        self.send_header('Content-Security-Policy', _POLICY)
        self.send_header('Cross-Origin-Resource-Policy', 'same-origin')
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

    def _client_gone(self):
        """Return True when the peer closed its end (readable with nothing to read)."""
        try:
            poller = select.poll()  # unlike select.select(), fine with descriptors > 1023
            poller.register(self.connection, select.POLLIN)
            return bool(poller.poll(0)) and not self.connection.recv(1, socket.MSG_PEEK)
        except (OSError, ValueError):
            return True


@dataclass(frozen=True)
class Route:
    """
    One address the viewer serves: the methods it takes, and what answers them.

    page: a page that a link on another site may open (a navigation); nothing else of the
    viewer may be used by another site's page (Sec-Fetch-Site).
    """

    methods: Tuple[str, ...]
    serve: Callable[[_Handler, str], None]
    what: str
    page: bool = False


_READ = ('GET', 'HEAD')
# Every address the viewer answers; anything else is 404 (no file is served from disk).
ROUTES: Dict[str, Route] = {
    '/': Route(_READ, _Handler.serve_page, 'the page: the live video, the stats, the panel',
               page=True),
    '/viewer.js': Route(_READ, _Handler.serve_page, "the page's script"),
    '/viewer.css': Route(_READ, _Handler.serve_page, "the page's style"),
    '/stream': Route(_READ, _Handler.serve_stream,
                     'MJPEG (multipart/x-mixed-replace), always the newest frame'),
    '/video': Route(_READ, _Handler.serve_video,
                    "a camera's H.264 access units for the page to decode (WebCodecs), from "
                    'the newest keyframe on (404 without one)'),
    '/snapshot.jpg': Route(_READ, _Handler.serve_snapshot,
                           'the newest frame as one JPEG (503 until the first frame)'),
    '/stats': Route(_READ, _Handler.serve_stats,
                    "the stats given to set_stats() and the viewer's own, as JSON"),
    '/camera': Route(_READ, _Handler.serve_camera,
                     'what the camera is and its controls, as JSON (404 without a camera)'),
    '/camera/controls': Route(('POST',), _Handler.serve_controls,
                              'a JSON object of control name: value to set; per-control '
                              'answer'),
    '/camera/step': Route(('POST',), _Handler.serve_step,
                          "a JSON object of the processing step's parameter name: value to "
                          'set; per-parameter answer (404 without a processing node)'),
}


class WebViewer:
    """Serve the newest submitted image to any number of browsers (up to max_clients)."""

    def __init__(self, host='127.0.0.1', port=8080, *, max_clients=8, jpeg_quality=80,
                 title='py_vision', logger=None, token=''):
        """
        Make a viewer for host:port; nothing is bound before start().

        token: what every request must carry (TOKEN_RULE; ValueError if not). Empty: none
        on a loopback host, and a random one (see `url`) on any other.
        """
        self.host = host
        self._requested_port = int(port)
        self.connections = Connections(max_clients)
        self.frames = FrameStore(jpeg_quality)
        self.video = VideoStore()
        self.snapshot_asked = -math.inf     # time.monotonic() of the last /snapshot.jpg
        self._pixel_clients = 0
        self.video_decoder_missing = None          # why H.264 is not decoded here (None: it is)
        self.access = Access(host, token)
        self.log = ThrottledLog(logger if logger is not None else logging.getLogger(__name__))
        self.page = page_files(title)
        self._camera: Optional[CameraAccess] = None
        self._stats_lock = threading.Lock()
        self._stats = {}
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
        self.access.bind(self.port, self.url)
        self._thread = threading.Thread(target=self._server.serve_forever, args=(0.1,),
                                        name='web_viewer', daemon=True)
        self._thread.start()

    @property
    def max_clients(self):
        """Return how many video clients may watch at once."""
        return self.connections.max_clients

    @property
    def token(self):
        """Return the token every request must carry (None: a loopback viewer needs none)."""
        return self.access.token

    @property
    def port(self):
        """Return the port really bound (the requested one, or the ephemeral one for port 0)."""
        return self._server.server_address[1] if self._server else self._requested_port

    @property
    def url(self):
        """
        Return the address to open in a browser, with the token when one is needed.

        The host name when bound to all interfaces (0.0.0.0, ::, or what the socket layer takes
        for them, such as 0).
        """
        bound = self._server.server_address[0] if self._server else self.host
        try:
            everywhere = bound == '' or ipaddress.ip_address(bound).is_unspecified
        except ValueError:
            everywhere = False
        host = socket.gethostname() if everywhere else self.host
        if ':' in host:
            host = '[%s]' % host
        url = 'http://%s:%d/' % (host, self.port)
        return url + ('?token=' + self.token if self.token else '')

    @property
    def cookie_name(self):
        """Return the cookie the page keeps the token in (one per port: cookies ignore ports)."""
        return self.access.cookie_name

    def set_camera(self, camera: Optional[CameraAccess]):
        """Serve /camera, /camera/controls and /camera/step from camera (None: 404, no panel)."""
        self._camera = camera

    def camera_state(self):
        """Return GET /camera's answer: the camera's, with the size and rate of what is shown."""
        camera = self._camera
        if camera is None:
            raise CameraError(404, 'this viewer has no camera panel')
        state = dict(camera.describe())
        with self._stats_lock:
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

    def set_step_parameters(self, values):
        """Apply POST /camera/step; return name: {applied, reason}."""
        camera = self._camera
        if camera is None:
            raise CameraError(404, 'this viewer has no camera panel')
        return camera.set_step_parameters(values)

    def submit(self, image):
        """
        Make image (uint8 BGR HxWx3 or mono HxW) the newest frame; it must not change later.

        Costs O(1) whatever the clients do: no copy, no encoding, no waiting on sockets.
        """
        self.frames.submit(image)

    def submit_jpeg(self, jpeg):
        """Make an already encoded JPEG (bytes) the newest frame; it is served as it is."""
        self.frames.submit_jpeg(jpeg)

    def submit_video(self, unit: bytes, start: bool, codec: str = ''):
        """
        Add a camera's H.264 access unit for the page's own decoder (GET /video).

        start: a decoder can start at it (a keyframe with its SPS and PPS); codec: the codec
        string of its SPS ('avc1.42c01e') when it has one.
        """
        self.video.submit(unit, start, codec)

    def pixel_clients(self, change: int) -> None:
        """Count an MJPEG client in (+1) or out (-1)."""
        with self._stats_lock:
            self._pixel_clients += change

    @property
    def wants_pixels(self) -> bool:
        """
        Return True when someone needs decoded frames: an MJPEG client, a recent snapshot.

        A page that decodes H.264 itself needs none.
        """
        with self._stats_lock:
            clients = self._pixel_clients
        return clients > 0 or time.monotonic() - self.snapshot_asked < _SNAPSHOT_INTEREST

    def set_stats(self, stats):
        """Set the JSON-able dict /stats and the page show (fps, latency, size, topic...)."""
        with self._stats_lock:
            self._stats = dict(stats)

    def stats(self):
        """Return the stats last set plus the viewer's own counters, ready for JSON."""
        with self._stats_lock:
            result = dict(self._stats)
        result['clients'] = self.connections.streams
        with self._stats_lock:   # the MJPEG clients, for which the node encodes (and decodes)
            result['mjpeg_clients'] = self._pixel_clients
        result['encoded_frames'] = self.frames.encoded
        result['viewer_frames'] = self.frames.number + self.video.number
        if self.video.number:   # a video's units came: its codec, '' until a keyframe's
            result['video_codec'] = self.video.codec
            result['video_decoder_missing'] = self.video_decoder_missing
        return _json_safe(result)

    @property
    def client_count(self):
        """How many video clients (/stream) are connected now."""
        return self.connections.streams

    @property
    def encoded_frames(self):
        """How many frames were JPEG-encoded so far (at most one per submitted frame)."""
        return self.frames.encoded

    def close(self):
        """Stop serving, drop every client and release the port; safe to call twice."""
        self.frames.close()
        self.video.close()
        server, self._server = self._server, None
        if server is None:
            return
        server.shutdown()
        server.server_close()
        self.connections.close_all()
        self._thread.join(1.0)
