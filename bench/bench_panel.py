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
The camera panel's API: how long a change takes through the viewer, against ROS directly.

Runs the installed usbcam_publisher (synthetic camera) and usbcam_subscriber (display:=web) on
a private ROS domain and times, alternately in the same run:

- POST /camera/controls (HTTP -> the viewer -> SetParameters -> the publisher) against the same
  SetParameters call made directly by an rclpy client (what `ros2 param set` does);
- after a change made elsewhere (that direct call) has been answered, until GET /camera shows
  it (through /parameter_events);
- GET /camera and GET /stats (the reference: a route that does not touch ROS).

Usage: .venv/bin/python bench/bench_panel.py [--rounds 200] [--fps 30]
"""

import argparse
import http.client
import json
import os
import shutil
import statistics
import tempfile
import threading
import time

from bench_common import save_results
import ros_harness


def request(port, method, path, body=None):
    connection = http.client.HTTPConnection('127.0.0.1', port, timeout=10)
    try:
        headers = {'Content-Type': 'application/json'} if body is not None else {}
        connection.request(method, path, body=body, headers=headers)
        response = connection.getresponse()
        return response.status, json.loads(response.read())
    finally:
        connection.close()


class DirectClient:
    """One SetParameters client of the publisher, kept for the run (as a script would)."""

    def __init__(self, peer, node_name):
        from rcl_interfaces.srv import SetParameters
        self._type = SetParameters
        self._client = peer.node.create_client(SetParameters, '/%s/set_parameters' % node_name)
        assert self._client.wait_for_service(timeout_sec=20), 'no set_parameters service'

    def set(self, name, value):  # noqa: A003
        """Set one integer parameter; return once the node has answered."""
        from param_client import parameter_value
        from rcl_interfaces.msg import Parameter
        done = threading.Event()
        future = self._client.call_async(self._type.Request(
            parameters=[Parameter(name=name, value=parameter_value(value))]))
        future.add_done_callback(lambda _: done.set())
        assert done.wait(10), 'no answer from set_parameters'
        return future.result().results[0]


def summary(samples):
    ordered = sorted(samples)
    return {'median_ms': round(statistics.median(ordered) * 1e3, 2),
            'p99_ms': round(ordered[max(0, int(len(ordered) * 0.99) - 1)] * 1e3, 2),
            'n': len(ordered)}


def main():
    parser = argparse.ArgumentParser(description=__doc__.split('\n\n')[0])
    parser.add_argument('--rounds', type=int, default=200)
    parser.add_argument('--fps', type=float, default=30.0)
    options = parser.parse_args()

    domain = ros_harness.DomainId()
    log_dir = tempfile.mkdtemp(prefix='py_vision_bench_panel_log_')
    env = ros_harness.installed_env()
    env.update(ROS_DOMAIN_ID=str(domain.value), ROS_AUTOMATIC_DISCOVERY_RANGE='LOCALHOST',
               PYTHONUNBUFFERED='1', RCUTILS_COLORIZED_OUTPUT='0', ROS_LOG_DIR=log_dir)
    nodes = [
        ros_harness.NodeProcess('usbcam_publisher', ros_harness.ros_args(
            {'video_device': 'synthetic', 'framerate': options.fps}), env),
        ros_harness.NodeProcess('usbcam_subscriber', ros_harness.ros_args(
            {'display': 'web', 'web_port': 0}), env),
    ]
    peer = None
    try:
        os.environ['ROS_AUTOMATIC_DISCOVERY_RANGE'] = 'LOCALHOST'  # the peer's discovery
        peer = ros_harness.RosPeer(domain.value, name='bench_peer')
        direct = DirectClient(peer, 'usbcam_publisher')
        port = int(nodes[1].wait_for_output(r'viewer at http://[^\s/]+:(\d+)/').group(1))
        ros_harness.wait_until(lambda: request(port, 'GET', '/camera')[1]['controls'], 30,
                               interval=0.2, what='the controls in GET /camera')
        times = {'post': [], 'direct': [], 'elsewhere_shown': [], 'get_camera': [],
                 'get_stats': []}
        for i in range(options.rounds):
            value = i % 50
            start = time.perf_counter()
            status, answer = request(port, 'POST', '/camera/controls',
                                     json.dumps({'brightness': value}).encode())
            times['post'].append(time.perf_counter() - start)
            assert answer['results']['brightness']['applied'], answer

            start = time.perf_counter()
            assert direct.set('contrast', 1 + i % 30).successful
            times['direct'].append(time.perf_counter() - start)
            start = time.perf_counter()
            ros_harness.wait_until(
                lambda: request(port, 'GET', '/camera')[1]['controls']['contrast']['value'] ==
                1 + i % 30, 10, interval=0.002, what='the change in GET /camera')
            times['elsewhere_shown'].append(time.perf_counter() - start)

            start = time.perf_counter()
            request(port, 'GET', '/camera')
            times['get_camera'].append(time.perf_counter() - start)
            start = time.perf_counter()
            request(port, 'GET', '/stats')
            times['get_stats'].append(time.perf_counter() - start)
    finally:
        if peer is not None:
            peer.close()
        for node in nodes:
            node.kill()
        domain.release()
        shutil.rmtree(log_dir, ignore_errors=True)

    rows = [('POST /camera/controls (brightness)', 'post'),
            ('SetParameters from rclpy directly (contrast)', 'direct'),
            ('then until GET /camera shows that change', 'elsewhere_shown'),
            ('GET /camera', 'get_camera'),
            ('GET /stats (no ROS)', 'get_stats')]
    result = {key: summary(times[key]) for _, key in rows}
    print('camera panel API, %d rounds, synthetic camera at %g fps\n' % (
        options.rounds, options.fps))
    print('%-46s %10s %10s' % ('', 'median ms', 'p99 ms'))
    for label, key in rows:
        print('%-46s %10.2f %10.2f' % (label, result[key]['median_ms'], result[key]['p99_ms']))
    ratio = result['post']['median_ms'] / result['direct']['median_ms']
    print('\nPOST through the viewer / direct SetParameters, medians: %.2f' % ratio)
    save_results('panel', dict(result, rounds=options.rounds, fps=options.fps,
                               post_to_direct_median_ratio=round(ratio, 3)))


if __name__ == '__main__':
    main()
