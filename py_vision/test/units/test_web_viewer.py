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
The browser viewer over real HTTP connections, in-process (no ROS).

Requests go out through raw sockets so the target reaches the server exactly as written
(no client-side path normalisation), which is what a hostile client would do.
"""

import json
import re
import socket
import struct

import cv2
import numpy as np
from py_vision.capture.synthetic_picture import read_frame_index, synthetic_frame
from py_vision.viewer.access import is_loopback
from py_vision.viewer.camera_access import CameraError
from py_vision.viewer.server import WebViewer, WebViewerError
import pytest
from ros_harness import wait_until

W, H = 640, 480


@pytest.fixture
def make_viewer():
    """Start WebViewers on ephemeral ports; all are closed at the end of the test."""
    viewers = []

    def make(**kwargs):
        viewer = WebViewer(port=0, **kwargs)
        viewer.start()
        viewers.append(viewer)
        return viewer
    yield make
    for viewer in viewers:
        viewer.close()


def connect(viewer, timeout=5.0):
    return socket.create_connection(('127.0.0.1', viewer.port), timeout=timeout)


def parse_head(data):
    head, _, body = data.partition(b'\r\n\r\n')
    lines = [line for line in head.decode('latin-1').split('\r\n') if line]
    status = int(lines[0].split()[1])
    headers = {k.strip().lower(): v.strip() for k, v in (line.split(':', 1) for line in lines[1:])}
    return status, headers, body


def request(viewer, target, method='GET'):
    """Send one request with the target exactly as given; return (status, headers, body)."""
    with connect(viewer) as sock:
        sock.sendall(('%s %s HTTP/1.1\r\nHost: localhost\r\n\r\n' % (method, target)).encode())
        chunks = []
        while True:  # the server closes every connection after its answer
            chunk = sock.recv(65536)
            if not chunk:
                break
            chunks.append(chunk)
    status, headers, body = parse_head(b''.join(chunks))
    if method != 'HEAD':
        assert int(headers['content-length']) == len(body)
    return status, headers, body


class StreamClient:
    """A /stream client that parses the multipart answer part by part."""

    def __init__(self, viewer, target='/stream', rcvbuf=None):
        self.sock = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
        if rcvbuf:
            self.sock.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, rcvbuf)
        self.sock.settimeout(5.0)
        self.sock.connect(('127.0.0.1', viewer.port))
        self.sock.sendall(b'GET %s HTTP/1.1\r\nHost: localhost\r\n\r\n' % target.encode())
        self.file = None
        self.received = 0

    def read_head(self):
        self.file = self.sock.makefile('rb')
        lines = []
        while True:
            line = self.file.readline()
            if line in (b'\r\n', b''):
                break
            lines.append(line)
        status, headers, _ = parse_head(b''.join(lines))
        self.status, self.headers = status, headers
        match = re.search(r'boundary=(\S+)', headers.get('content-type', ''))
        self.boundary = match.group(1).encode() if match else None
        return status

    def next_part(self):
        """Return the next JPEG part as bytes."""
        line = self.file.readline()
        while line == b'\r\n':
            line = self.file.readline()
        assert line.rstrip(b'\r\n') == b'--' + self.boundary, line
        headers = {}
        while True:
            line = self.file.readline().rstrip(b'\r\n')
            if not line:
                break
            key, value = line.decode().split(':', 1)
            headers[key.strip().lower()] = value.strip()
        assert headers['content-type'] == 'image/jpeg'
        jpeg = self.file.read(int(headers['content-length']))
        self.received += len(jpeg)
        return jpeg

    def close(self, reset=False):
        if reset:  # vanish abruptly: RST instead of an orderly FIN
            self.sock.setsockopt(socket.SOL_SOCKET, socket.SO_LINGER, struct.pack('ii', 1, 0))
        if self.file is not None:
            self.file.close()
        self.sock.close()


def decode(jpeg):
    image = cv2.imdecode(np.frombuffer(jpeg, np.uint8), cv2.IMREAD_UNCHANGED)
    assert image is not None, 'not a valid JPEG'
    return image


def test_stream_sends_every_new_frame_as_a_jpeg_of_the_right_size(make_viewer):
    viewer = make_viewer()
    client = StreamClient(viewer)
    assert client.read_head() == 200
    assert client.headers['content-type'].startswith('multipart/x-mixed-replace')
    assert client.headers['cache-control'] == 'no-store'
    previous = None
    for index in range(1, 8):
        viewer.submit(synthetic_frame(index, W, H))
        image = decode(client.next_part())
        assert image.shape == (H, W, 3)
        assert read_frame_index(image) == index
        if previous is not None:
            assert np.abs(image.astype(int) - previous).mean() > 1.0
        previous = image.astype(int)
    mono = cv2.cvtColor(synthetic_frame(8, 320, 240), cv2.COLOR_BGR2GRAY)
    viewer.submit(mono)
    image = decode(client.next_part())
    assert image.shape == (240, 320)
    assert read_frame_index(image) == 8
    client.close()


def test_snapshot_is_503_until_the_first_frame_then_the_newest_jpeg(make_viewer):
    viewer = make_viewer()
    status, headers, body = request(viewer, '/snapshot.jpg')
    assert status == 503
    assert headers['retry-after'] == '1'
    assert b'no frame' in body.lower()
    for index in (3, 4):
        viewer.submit(synthetic_frame(index, W, H))
    status, headers, body = request(viewer, '/snapshot.jpg')
    assert status == 200
    assert headers['content-type'] == 'image/jpeg'
    image = decode(body)
    assert image.shape == (H, W, 3)
    assert read_frame_index(image) == 4


def test_stats_are_json_with_the_viewer_counters(make_viewer):
    viewer = make_viewer()
    viewer.set_stats({'fps': 14.5, 'latency_ms_p50': np.float64(3.25),
                      'latency_ms_p99': float('nan'), 'width': np.int64(W), 'height': H,
                      'encoding': 'bgr8', 'topic': '/usb_camera/image', 'frames': 7})
    client = StreamClient(viewer)
    client.read_head()
    viewer.submit(synthetic_frame(1, W, H))
    client.next_part()
    status, headers, body = request(viewer, '/stats?t=123')
    assert status == 200
    assert headers['content-type'] == 'application/json'
    stats = json.loads(body)  # strict JSON: NaN would not parse in a browser
    assert stats['fps'] == 14.5
    assert stats['latency_ms_p50'] == 3.25
    assert stats['latency_ms_p99'] is None
    assert (stats['width'], stats['height'], stats['encoding']) == (W, H, 'bgr8')
    assert stats['topic'] == '/usb_camera/image'
    assert stats['clients'] == 1 and stats['mjpeg_clients'] == 1
    assert stats['encoded_frames'] == 1
    client.close()


def test_page_is_self_contained_with_the_video_and_stats_elements(make_viewer):
    viewer = make_viewer(title='cam <1> & "x"')
    status, headers, body = request(viewer, '/')
    assert status == 200
    assert headers['content-type'] == 'text/html; charset=utf-8'
    page = body.decode()
    # The script chooses what the video shows (MJPEG in the img, or H.264 the page decodes
    # itself on the canvas) once it knows what the node receives.
    assert re.search(r'<img id="video" alt=', page) and '<canvas id="canvas"' in page
    script = request(viewer, '/viewer.js')[2].decode()
    assert '"/stream?t="' in script and 'fetch("/video"' in script
    for element in ('stat-fps', 'stat-latency', 'stat-resolution', 'stat-encoding',
                    'stat-topic', 'stat-clients'):
        assert 'id="%s"' % element in page
    assert 'cam &lt;1&gt; &amp; &quot;x&quot;' in page and 'cam <1>' not in page
    # Its script and style are the viewer's own files; nothing runs inline.
    policy = headers['content-security-policy']
    assert "script-src 'self'" in policy and 'unsafe-inline' not in policy
    assert re.search(r'<script src="/viewer.js">', page) and '<style' not in page
    for route, content_type, words in (('/viewer.js', 'text/javascript', 'function poll'),
                                       ('/viewer.css', 'text/css', '#video')):
        status, headers, body = request(viewer, route)
        assert status == 200, route
        assert headers['content-type'].startswith(content_type)
        assert words in body.decode()
        page += body.decode()
    # Nothing from elsewhere: the page has to work on a board with no internet.
    assert not re.search(r'(src|href)="(?!/)', page)
    assert 'http://' not in page and 'https://' not in page


@pytest.mark.parametrize('target', [
    '/index.html', '/favicon.ico', '/web_viewer.py', '/../etc/passwd', '/stream/..',
    '/%2e%2e/%2e%2e/etc/passwd', '/%2E%2E/', '/..%2fetc%2fpasswd', '//stream', '/stream/',
    '/./stats', '/STATS', '/stats/', '/snapshot.jpg/', '/%73tats', '/stream%00',
    'http://localhost/stats', '*', '/py_vision/', '/test/',
])
def test_every_other_path_is_404(make_viewer, target):
    viewer = make_viewer()
    viewer.submit(synthetic_frame(1, W, H))
    status, headers, body = request(viewer, target)
    assert status == 404, target
    assert body == b'Not found.\n'
    assert headers['content-type'].startswith('text/plain')


def test_head_and_unsupported_methods(make_viewer):
    viewer = make_viewer()
    status, headers, body = request(viewer, '/stats', 'HEAD')
    assert status == 200 and body == b'' and int(headers['content-length']) > 0
    status, headers, body = request(viewer, '/stats', 'POST')
    assert status == 405 and headers['allow'] == 'GET, HEAD'
    assert b'clients' not in body
    status, _, body = request(viewer, '/stats', 'PUT')
    assert status == 501
    assert b'clients' not in body


def test_clients_beyond_the_limit_are_refused_and_a_freed_slot_is_reused(make_viewer):
    viewer = make_viewer(max_clients=2)
    clients = [StreamClient(viewer) for _ in range(2)]
    viewer.submit(synthetic_frame(1, W, H))
    for client in clients:
        assert client.read_head() == 200
        client.next_part()
    assert viewer.client_count == 2
    status, headers, body = request(viewer, '/stream')
    assert status == 503
    assert b'too many viewers' in body.lower()
    assert int(headers['retry-after']) > 0
    # The page and the stats still work for everyone watching.
    assert request(viewer, '/')[0] == 200
    assert json.loads(request(viewer, '/stats')[2])['clients'] == 2
    clients[0].close()
    wait_until(lambda: viewer.client_count == 1, 5.0, what='the slot to be freed')
    again = StreamClient(viewer)
    assert again.read_head() == 200
    # A new client gets the current frame at once, then every newer one.
    assert read_frame_index(decode(again.next_part())) == 1
    viewer.submit(synthetic_frame(2, W, H))
    assert read_frame_index(decode(again.next_part())) == 2
    assert read_frame_index(decode(clients[1].next_part())) == 2
    again.close()
    clients[1].close()


@pytest.mark.parametrize('frames_keep_coming', [True, False])
def test_a_client_vanishing_mid_stream_frees_its_slot(make_viewer, frames_keep_coming):
    viewer = make_viewer(max_clients=1)
    client = StreamClient(viewer)
    client.read_head()
    viewer.submit(synthetic_frame(1, W, H))
    client.next_part()
    viewer.submit(synthetic_frame(2, W, H))
    client.file.read(100)  # stop in the middle of a part
    client.close(reset=True)
    index = [2]

    def slot_free():
        if frames_keep_coming:
            index[0] += 1
            viewer.submit(synthetic_frame(index[0], W, H))
        return viewer.client_count == 0
    wait_until(slot_free, 5.0, interval=0.05, what='the vanished client to be dropped')
    survivor = StreamClient(viewer)
    assert survivor.read_head() == 200
    assert read_frame_index(decode(survivor.next_part())) == index[0]
    viewer.submit(synthetic_frame(100, W, H))
    assert read_frame_index(decode(survivor.next_part())) == 100
    survivor.close()


def test_each_frame_is_encoded_once_for_all_clients_and_never_without_clients(make_viewer):
    viewer = make_viewer(max_clients=4)
    for index in range(1, 31):
        viewer.submit(synthetic_frame(index, W, H))
    assert viewer.encoded_frames == 0
    clients = [StreamClient(viewer) for _ in range(4)]
    for client in clients:
        client.read_head()
    parts = [client.next_part() for client in clients]  # all get frame 30, encoded once
    assert len(set(parts)) == 1
    assert viewer.encoded_frames == 1
    for index in range(31, 36):
        viewer.submit(synthetic_frame(index, W, H))
        parts = [client.next_part() for client in clients]
        assert len(set(parts)) == 1
        assert read_frame_index(decode(parts[0])) == index
        assert request(viewer, '/snapshot.jpg')[2] == parts[0]
    assert viewer.encoded_frames == 6
    for client in clients:
        client.close()


def test_a_client_that_never_reads_slows_neither_submit_nor_other_clients(make_viewer):
    viewer = make_viewer(max_clients=2)
    slow = StreamClient(viewer, rcvbuf=4096)  # sends its request, then never reads
    wait_until(lambda: viewer.client_count == 1, 5.0, what='the slow client')
    fast = StreamClient(viewer)
    fast.read_head()
    rng = np.random.default_rng(1)
    # Noise barely compresses: ~0.8 MB a frame fills the slow client's buffers within a few.
    frames = [rng.integers(0, 256, (960, 1280, 3), np.uint8) for _ in range(4)]
    for index in range(30):
        viewer.submit(frames[index % 4])
        jpeg = fast.next_part()
        assert request(viewer, '/snapshot.jpg')[2] == jpeg, 'the fast client lags behind'
    assert viewer.encoded_frames == 30
    assert viewer.client_count == 2
    slow.sock.setblocking(False)
    waiting = 0
    try:
        while True:
            chunk = slow.sock.recv(1 << 20)
            if not chunk:
                break
            waiting += len(chunk)
    except BlockingIOError:
        pass
    assert waiting < fast.received / 2, 'the slow client was not held back'
    slow.close()
    fast.close()


def test_idle_connections_are_bounded(make_viewer):
    viewer = make_viewer(max_clients=1)
    idle = []
    try:
        # Connections that never send a request: slowloris. Beyond the cap they are turned
        # away at once, so they cannot pile up server threads.
        for _ in range(40):
            idle.append(connect(viewer))
        refused = 0
        for sock in idle[-10:]:
            try:
                sock.settimeout(2.0)
                answer = sock.recv(4096)
            except socket.timeout:
                continue
            except ConnectionResetError:
                answer = b''
            assert answer == b'' or answer.startswith(b'HTTP/1.1 503')
            refused += 1
        assert refused == 10
    finally:
        for sock in idle:
            sock.close()
    wait_until(lambda: _stats_ok(viewer), 5.0, interval=0.1, what='service after the flood')


def _stats_ok(viewer):
    try:
        return request(viewer, '/stats')[0] == 200
    except OSError:
        return False


def test_close_drops_clients_and_releases_the_port(make_viewer):
    viewer = make_viewer()
    port = viewer.port
    assert viewer.url == 'http://127.0.0.1:%d/' % port
    client = StreamClient(viewer)
    client.read_head()
    viewer.submit(synthetic_frame(1, W, H))
    client.next_part()
    viewer.close()
    # The stream ends (EOF or reset), it does not hang.
    try:
        assert b'Content-Type' not in client.file.read()
    except ConnectionResetError:
        pass
    client.close()
    again = WebViewer(port=port)
    again.start()
    try:
        assert again.port == port
        assert request(again, '/stats')[0] == 200
    finally:
        again.close()


def test_a_port_in_use_is_a_clear_error(make_viewer):
    viewer = make_viewer()
    second = WebViewer(port=viewer.port)
    with pytest.raises(WebViewerError) as error:
        second.start()
    message = str(error.value)
    assert '127.0.0.1:%d' % viewer.port in message
    assert 'web_port' in message


@pytest.mark.parametrize('image', [
    np.zeros((4, 4), np.uint16), np.zeros((4, 4, 3), np.float32), np.zeros((4, 4, 4), np.uint8),
    np.zeros(4, np.uint8), [[0, 1], [2, 3]],
])
def test_submit_refuses_what_it_cannot_show(make_viewer, image):
    viewer = make_viewer()
    with pytest.raises(ValueError, match='uint8|numpy'):
        viewer.submit(image)


@pytest.mark.parametrize('host, loopback', [
    ('127.0.0.1', True), ('127.8.9.10', True), ('::1', True), ('[::1]', True),
    ('localhost', True), ('LOCALHOST', True), ('0.0.0.0', False), ('::', False),
    ('', False), ('192.168.1.20', False), ('board.local', False), ('10.0.0.1', False)])
def test_loopback_is_judged_by_the_bound_address(host, loopback):
    assert is_loopback(host) is loopback
    assert (WebViewer(host, 0).token is None) is loopback


class FakeCamera:
    """A CameraAccess that answers from a dict (the ROS side is test_camera_panel.py's)."""

    def __init__(self, fail=None):
        self.received = []
        self.fail = fail

    def describe(self):
        return {'publisher': '/cam', 'controls': {'gain': {'value': 3}}}

    def set_controls(self, values):
        self.received.append(values)
        if self.fail:
            raise self.fail
        return {name: {'applied': True, 'reason': ''} for name in values}


def post_json(viewer, body, headers=''):
    with connect(viewer) as sock:
        sock.sendall(b'POST /camera/controls HTTP/1.1\r\nHost: localhost\r\n'
                     b'Content-Type: application/json\r\nContent-Length: %d\r\n%s\r\n%s' % (
                         len(body), headers.encode(), body))
        data = b''.join(iter(lambda: sock.recv(65536), b''))
    status, _, answer = parse_head(data)
    return status, json.loads(answer)


def test_camera_routes_serve_the_camera_given_and_404_without(make_viewer):
    viewer = make_viewer()
    status, headers, body = request(viewer, '/camera')
    assert status == 404 and 'no camera panel' in json.loads(body)['error']
    assert post_json(viewer, b'{"gain": 1}')[0] == 404

    camera = FakeCamera()
    viewer.set_stats({'width': 640, 'height': 480, 'fps': 9.5, 'topic': '/t'})
    viewer.set_camera(camera)
    status, headers, body = request(viewer, '/camera')
    assert status == 200 and headers['content-type'] == 'application/json'
    state = json.loads(body)
    assert state['controls'] == {'gain': {'value': 3}}
    assert state['shown'] == {'size': '640x480', 'fps': 9.5, 'topic': '/t'}
    assert post_json(viewer, b'{"gain": 1}') == (200, {'results': {
        'gain': {'applied': True, 'reason': ''}}})
    assert camera.received == [{'gain': 1}]
    # Nothing reaches the camera from a page of another origin.
    assert post_json(viewer, b'{"gain": 2}', 'Origin: http://evil.example\r\n')[0] == 403
    assert post_json(viewer, b'{"gain": 2}', 'Origin: http://localhost\r\n')[0] == 200
    assert camera.received == [{'gain': 1}, {'gain': 2}]
    assert request(viewer, '/')[1]['x-frame-options'] == 'DENY'


def test_a_failing_camera_side_is_a_500_and_the_viewer_keeps_serving(make_viewer):
    viewer = make_viewer()
    viewer.set_camera(FakeCamera(fail=KeyError('boom')))
    status, answer = post_json(viewer, b'{"gain": 1}')
    assert status == 500 and 'KeyError' in answer['error']
    viewer.set_camera(FakeCamera(fail=CameraError(504, '/cam did not answer within 3 s')))
    assert post_json(viewer, b'{"gain": 1}') == (504, {'error': '/cam did not answer within 3 s'})
    assert request(viewer, '/stats')[0] == 200


def test_a_token_given_is_required_on_loopback_too(make_viewer):
    viewer = make_viewer(token='a-token-of-16-chars')
    assert viewer.url.endswith('/?token=a-token-of-16-chars')
    assert request(viewer, '/stats')[0] == 401
    status, headers, _ = request(viewer, '/?token=a-token-of-16-chars')
    assert status == 303 and headers['location'] == '/'
    assert headers['set-cookie'].startswith('py_vision_token_%d=' % viewer.port)


def test_a_client_that_sends_its_request_slowly_is_dropped_and_its_slot_freed(
        make_viewer, monkeypatch):
    # A client that keeps a connection by sending its request a byte at a time (within the
    # socket timeout each) would hold one of its address's few connections for ever: the
    # request's line and headers must arrive within the viewer's head time.
    import time
    from py_vision.viewer import server
    monkeypatch.setattr(server, '_HEAD_TIME', 1.0)
    monkeypatch.setattr(server, '_PENDING_PER_ADDRESS', 1)   # one connection per address
    viewer = make_viewer(max_clients=1)
    slow = connect(viewer, timeout=0.2)
    slow.sendall(b'GET / HTTP/1.1\r\n')
    dropped = False
    give_up = time.monotonic() + 8.0   # eight times the request time
    while not dropped and time.monotonic() < give_up:
        try:
            slow.sendall(b'X')
            dropped = slow.recv(1) == b''
        except socket.timeout:
            continue   # still open: the viewer is waiting for the rest
        except OSError:
            dropped = True   # reset by the viewer
    slow.close()
    assert dropped, 'a request trickling in for 8 s still holds its connection'
    # The address's one connection is free again.
    wait_until(lambda: request(viewer, '/stats')[0] == 200, 5, interval=0.1,
               what='the connection the slow client held to be free')


@pytest.mark.parametrize('token', ['short', 'sixteen chars ok', 'a' * 15 + '/', 'é' * 20])
def test_a_token_that_is_guessable_or_unsafe_in_a_url_is_refused(token):
    with pytest.raises(ValueError, match='at least 16 of A-Z a-z 0-9'):
        WebViewer(host='0.0.0.0', port=0, token=token)
    assert WebViewer(host='0.0.0.0', port=0, token='Abc-_.~0123456789').token == \
        'Abc-_.~0123456789'


# What a neighbour on the network, or another web page in the user's browser, may send
# (issue 28).

TOKEN = 'a-token-of-16-chars'


def ask(viewer, target, headers=(), method='GET', body=b'', source='127.0.0.1', timeout=5.0):
    """Send one request from the address source; return (status, headers, body)."""
    with socket.create_connection(('127.0.0.1', viewer.port), timeout=timeout,
                                  source_address=(source, 0)) as sock:
        head = '%s %s HTTP/1.1\r\nHost: 127.0.0.1:%d\r\n' % (method, target, viewer.port)
        head += ''.join('%s: %s\r\n' % item for item in headers)
        if body:
            head += 'Content-Length: %d\r\n' % len(body)
        sock.sendall(head.encode('utf-8', 'surrogateescape') + b'\r\n' + body)
        data = b''
        while True:
            chunk = sock.recv(65536)
            if not chunk:
                break
            data += chunk
            if method != 'HEAD' and b'\r\n\r\n' in data and 'multipart' in data.decode(
                    'latin-1').partition('\r\n\r\n')[0].lower():
                break  # a stream: the head is enough
    return parse_head(data)


def test_a_malformed_cookie_of_another_app_does_not_hide_the_token(make_viewer):
    # Another web application on the same host name sets its own cookies; a browser sends
    # them all in one header. Some are not what Python's SimpleCookie accepts.
    viewer = make_viewer(token=TOKEN)
    ours = '%s=%s' % (viewer.cookie_name, TOKEN)
    for cookie in ('theme=dark blue; ' + ours, 'junk; ' + ours, ours + '; a="b; c=d',
                   'x=1;;' + ours, ours):
        status, _, body = ask(viewer, '/stats', [('Cookie', cookie)])
        assert status == 200, (cookie, body)
    for cookie in ('theme=dark blue', '%s=%s' % (viewer.cookie_name, 'x' * 19),
                   'py_vision_token_1=' + TOKEN):
        assert ask(viewer, '/stats', [('Cookie', cookie)])[0] == 401, cookie


@pytest.mark.parametrize('route', ['/stream', '/snapshot.jpg'])
def test_another_site_cannot_embed_the_video(make_viewer, route):
    # On loopback any page the user opens could put <img src="http://127.0.0.1:8080/stream">
    # in its own page (and use up the video slots); browsers say where a request comes from.
    viewer = make_viewer()
    viewer.submit(synthetic_frame(1, W, H))
    for site in ('cross-site', 'same-site'):
        status, headers, body = ask(viewer, route, [('Sec-Fetch-Site', site)])
        assert status == 403, site
        assert 'another site' in json.loads(body)['error']
    assert viewer.client_count == 0
    for site in ('same-origin', 'none', None):
        status, headers, _ = ask(viewer, route, [('Sec-Fetch-Site', site)] if site else [])
        assert status == 200, site
        assert headers['cross-origin-resource-policy'] == 'same-origin'


@pytest.mark.parametrize('body', [
    b'[' * 1100, b'{"a": ' * 1100, b'{"gain": ' + b'[' * 100000 + b'}',
    b'{"\\ud800": 1}', b'{"gain": "\\udfff"}'])
def test_any_json_is_answered_with_a_4xx(make_viewer, body):
    viewer = make_viewer()
    camera = FakeCamera()
    viewer.set_camera(camera)
    if len(body) > 16384:
        body = body[:16000]
    status, _, answer = ask(viewer, '/camera/controls', [
        ('Content-Type', 'application/json')], 'POST', body)
    assert 400 <= status < 500, (body[:30], status)
    assert 'error' in json.loads(answer)
    assert camera.received == [], 'a value no control can take reached the camera side'
    assert ask(viewer, '/stats')[0] == 200


def test_a_change_through_an_https_proxy_is_from_the_page_itself(make_viewer):
    # Behind a reverse proxy that speaks HTTPS to the browser (and passes the Host on), the
    # page's Origin is https://<Host>.
    viewer = make_viewer(token=TOKEN)
    viewer.set_camera(FakeCamera())
    cookie = ('Cookie', '%s=%s' % (viewer.cookie_name, TOKEN))
    own = 'https://127.0.0.1:%d' % viewer.port
    json_type = ('Content-Type', 'application/json')
    status, _, _ = ask(viewer, '/camera/controls', [cookie, json_type, ('Origin', own)],
                       'POST', b'{"gain": 1}')
    assert status == 200
    for origin in ('https://evil.example', 'https://127.0.0.1:%d.evil' % viewer.port,
                   'ftp://127.0.0.1:%d' % viewer.port, 'null'):
        status, _, _ = ask(viewer, '/camera/controls', [cookie, json_type, ('Origin', origin)],
                           'POST', b'{"gain": 1}')
        assert status == 403, origin


def test_web_host_0_is_every_interface(make_viewer):
    # '0' is 0.0.0.0 to the socket layer: the URL names this machine, not host '0'.
    viewer = make_viewer(host='0', token=TOKEN)
    assert viewer.url == 'http://%s:%d/?token=%s' % (socket.gethostname(), viewer.port, TOKEN)


class Flood:
    """
    Connections from one address that each send a byte and then nothing.

    Each is reopened as soon as the viewer drops it: someone without the token trying to hold
    the viewer's connections.
    """

    def __init__(self, viewer, source, connections, seconds):
        import threading
        import time
        self._viewer, self._source = viewer, source
        self._stop = time.monotonic() + seconds
        self.opened = 0
        self._threads = [threading.Thread(target=self._hold, daemon=True)
                         for _ in range(connections)]
        for thread in self._threads:
            thread.start()

    def _hold(self):
        import time
        while time.monotonic() < self._stop:
            try:
                with socket.create_connection(('127.0.0.1', self._viewer.port), timeout=1.0,
                                              source_address=(self._source, 0)) as sock:
                    self.opened += 1
                    sock.sendall(b'G')
                    while time.monotonic() < self._stop and sock.recv(1024):
                        pass
            except OSError:
                time.sleep(0.05)

    def join(self):
        for thread in self._threads:
            thread.join()


def test_connections_without_the_token_cannot_starve_a_client_with_it(make_viewer):
    # Measured in bench/bench_viewer_flood.py; here: every request of the client holding the
    # token is answered while the flood goes on.
    import time
    viewer = make_viewer(token=TOKEN)
    floods = [Flood(viewer, '127.0.0.%d' % n, 24, 12.0) for n in (2, 3, 4)]
    try:
        wait_until(lambda: sum(f.opened for f in floods) >= 72, 10, interval=0.05,
                   what='the flood to open its connections')
        answers = []
        for _ in range(20):
            try:
                answers.append(ask(viewer, '/stats', [('Authorization', 'Bearer ' + TOKEN)],
                                   timeout=5.0)[0])
            except OSError as error:
                answers.append(type(error).__name__)
            time.sleep(0.1)
        assert answers == [200] * 20, answers
    finally:
        for flood in floods:
            flood.join()


def test_a_viewer_that_warns_then_errs_on_an_rclpy_logger_keeps_answering(make_viewer):
    # rclpy's loggers refuse a call site whose severity changes between calls: the viewer's
    # warning (a refused video client) and its error (a failing camera side) must both log.
    from rclpy.logging import get_logger
    viewer = make_viewer(max_clients=1, logger=get_logger('test_viewer'))
    viewer.set_camera(FakeCamera(fail=KeyError('boom')))
    watching = StreamClient(viewer)
    assert watching.read_head() == 200
    assert request(viewer, '/stream')[0] == 503   # a warning
    status, answer = post_json(viewer, b'{"gain": 1}')   # an error
    assert status == 500 and 'KeyError' in answer['error']
    status, answer = post_json(viewer, b'{"gain": 1}')
    assert status == 500
    watching.close()
