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
The browser viewer under a flood of connections without the token: what a client with it gets.

An in-process WebViewer with a token on 127.0.0.1 (the installed package). A client holding the
token asks GET /stats one request after another; meanwhile connections from other loopback
addresses (127.0.0.2, ...), each sending one byte and then nothing, are reopened as soon as
the viewer drops them (the slow-request attack of issue 28), from a process of their own (so
that they do not take this one's interpreter lock). Measured in the same run: the client alone
(the reference), then under each flood. Only loopback addresses are used.

Usage: .venv/bin/python bench/bench_viewer_flood.py [--seconds 10]
"""

import argparse
import json
from pathlib import Path
import socket
import statistics
import subprocess
import sys
import threading
import time

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO / 'py_vision' / 'test'))

from bench_common import save_results  # noqa: E402
import ros_harness  # noqa: E402,I100 (puts the installed py_vision on sys.path)

sys.path.insert(0, str(ros_harness.SITE_PACKAGES))
from py_vision.viewer.server import WebViewer  # noqa: E402,I100

TOKEN = 'bench-token-0123456789'
ANSWER_TIMEOUT_S = 5.0


def ask(port):
    """GET /stats with the token; return (status or the error's name, seconds taken)."""
    start = time.perf_counter()
    try:
        with socket.create_connection(('127.0.0.1', port), timeout=ANSWER_TIMEOUT_S) as sock:
            sock.sendall(b'GET /stats HTTP/1.1\r\nHost: 127.0.0.1\r\nAuthorization: Bearer %s'
                         b'\r\n\r\n' % TOKEN.encode())
            data = b''
            while True:
                chunk = sock.recv(65536)
                if not chunk:
                    break
                data += chunk
        status = int(data.split(b' ', 2)[1]) if data else 'closed'
    except OSError as error:
        status = type(error).__name__
    return status, time.perf_counter() - start


def hold(port, source, stop, opened):
    """Keep one connection from source open with one byte sent; reopen it when dropped."""
    while time.monotonic() < stop:
        try:
            with socket.create_connection(('127.0.0.1', port), timeout=1.0,
                                          source_address=(source, 0)) as sock:
                opened.append(1)
                sock.sendall(b'G')
                while time.monotonic() < stop and sock.recv(1024):
                    pass
        except OSError:
            time.sleep(0.05)


def flood(port, sources, per_source, seconds):
    """Hold per_source connections from each source for seconds; print how many were opened."""
    stop = time.monotonic() + seconds
    opened = []
    threads = [threading.Thread(target=hold, args=(port, source, stop, opened), daemon=True)
               for source in sources for _ in range(per_source)]
    for thread in threads:
        thread.start()
    for thread in threads:
        thread.join()
    print(json.dumps({'opened': len(opened)}), flush=True)


def measure(port, seconds, sources, per_source):
    """Run the client for seconds under a flood from sources; return its numbers."""
    attackers = None
    if sources:
        attackers = subprocess.Popen(
            [sys.executable, __file__, '--flood', str(port), str(per_source),
             str(seconds + 2.0)] + sources, stdout=subprocess.PIPE, text=True)
        time.sleep(2.0)   # the flood holds its connections before the client starts
    statuses, times = [], []
    end = time.monotonic() + seconds
    while time.monotonic() < end:
        status, took = ask(port)
        statuses.append(status)
        if status == 200:
            times.append(took * 1e3)
        time.sleep(0.02)
    opened = 0
    if attackers is not None:
        opened = json.loads(attackers.communicate(timeout=30)[0])['opened']
    answered = statuses.count(200)
    return {'requests': len(statuses), 'answered': answered,
            'answered_fraction': round(answered / len(statuses), 3),
            'median_ms': round(statistics.median(times), 2) if times else None,
            'max_ms': round(max(times), 2) if times else None,
            'flood_connections_per_s': round(opened / (seconds + 2.0), 1),
            'other_answers': sorted({str(s) for s in statuses if s != 200})}


def main():
    if sys.argv[1:2] == ['--flood']:
        port, per_source, seconds = int(sys.argv[2]), int(sys.argv[3]), float(sys.argv[4])
        flood(port, sys.argv[5:], per_source, seconds)
        return
    parser = argparse.ArgumentParser(description=__doc__.split('\n\n')[0])
    parser.add_argument('--seconds', type=float, default=10.0)
    options = parser.parse_args()
    viewer = WebViewer(port=0, token=TOKEN)
    viewer.start()
    try:
        scenarios = [('the client alone (reference)', 'alone', [], 0),
                     ('24 connections from 127.0.0.2', 'one_address', ['127.0.0.2'], 24),
                     ('24 each from 127.0.0.2-5 (96)', 'four_addresses',
                      ['127.0.0.%d' % n for n in range(2, 6)], 24)]
        result = {}
        for _, key, sources, per_source in scenarios:
            result[key] = measure(viewer.port, options.seconds, sources, per_source)
    finally:
        viewer.close()
    print('GET /stats with the token, one after another for %g s, while connections without '
          'it send one byte and wait\n' % options.seconds)
    print('%-34s %9s %9s %10s %8s %11s' % (
        '', 'requests', 'answered', 'median ms', 'max ms', 'flood/s'))
    for label, key, _, _ in scenarios:
        row = result[key]
        print('%-34s %9d %9d %10s %8s %11s' % (label, row['requests'], row['answered'],
                                               row['median_ms'], row['max_ms'],
                                               row['flood_connections_per_s']))
    for key in ('one_address', 'four_addresses'):
        if result[key]['median_ms'] and result['alone']['median_ms']:
            result[key]['median_ratio_to_alone'] = round(
                result[key]['median_ms'] / result['alone']['median_ms'], 2)
            print('%s: median / alone = %.2f' % (key, result[key]['median_ratio_to_alone']))
    save_results('viewer_flood', dict(result, seconds=options.seconds))


if __name__ == '__main__':
    main()
