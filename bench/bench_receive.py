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
Measure the CPU a received frame costs py_vision's receiving nodes, against bare rclpy.

  .venv/bin/python bench/bench_receive.py [--sizes 640x480,1280x720] [--rates 30]
      [--window S] [--rounds N] [--receivers bare,usbcam_subscriber,...]

Per size and rate, one bare rclpy publisher of prebuilt bgr8 frames (bench/bare_image_publisher.py,
reliable, on the profile usbcam_publisher makes for that size: shared memory for three frames)
runs in a process of its own, and each receiver in turn subscribes to it:

  bare                 bench/bare_image_subscriber.py on the profile usbcam_subscriber makes for
                       itself (py_vision.dds): the reference
  usbcam_subscriber    display:=none
  vision_step nothing  vision_step with a step that returns None (bench/nothing_step.py)
  vision_step circle   vision_step with its default step, which draws and returns the frame
  cv_bridge_test       the tutorial's node (the circle step under its own name)

A receiver's cost is its CPU (utime + stime of the whole process, /proc) over a window divided
by the frames it received in that window: the bare subscriber's own records, the nodes' frame
counts from their /diagnostics (the window runs from one report to a later one, the CPU read as
each arrives). The part of it spent in the kernel, minor page faults per frame (a frame's
memory given back to the system and faulted in again) and the resident memory at the window's
end go with it. Rounds alternate the
receivers (the order turns each round); the table gives medians over the rounds and, per node,
the median of its ratios to the bare subscriber of the same round. Writes
bench/results/receive-py<version>.json (the boards' Python 3.10 in the board-version
environment: `. scripts/board_env.sh && python bench/bench_receive.py`).
"""

import argparse
import os
import re
import statistics
import sys
import tempfile
import threading
import time

from bench_common import (BENCH, CLK_TCK, FIRST_FRAME_MARK, local_node_env, read_results,
                          save_results, start_helper)
import ros_harness

RECEIVERS = ('bare', 'usbcam_subscriber', 'vision_step nothing', 'vision_step circle',
             'cv_bridge_test')
START_S = 60.0
SETTLE_S = 2.0
# The status whose frame count each node reports on /diagnostics, and the key of the count.
COUNTS = {'usbcam_subscriber': ('stream', 'frames'), 'vision_step': ('processing', 'frames in'),
          'cv_bridge_test': ('processing', 'frames in')}


def process_stat(pid):
    """Return (utime + stime, stime in ticks, minor faults) of a process, or None if gone."""
    try:
        with open('/proc/%d/stat' % pid) as stream:
            fields = stream.read().rsplit(')', 1)[1].split()
    except OSError:
        return None
    return int(fields[11]) + int(fields[12]), int(fields[12]), int(fields[7])


def rss_mib(pid):
    """Return a process' VmRSS in MiB, or None."""
    try:
        with open('/proc/%d/status' % pid) as stream:
            found = re.search(r'^VmRSS:\s+(\d+) kB', stream.read(), re.M)
    except OSError:
        return None
    return round(int(found.group(1)) / 1024.0, 1) if found else None


class Reports:
    """A node's frame counts from /diagnostics, each with the node's CPU as it arrived."""

    def __init__(self, peer):
        from diagnostic_msgs.msg import DiagnosticArray
        from rclpy.qos import QoSProfile, ReliabilityPolicy
        self._lock = threading.Lock()
        self._watched = None  # (status name, key, pid)
        self.records = []     # (arrival, frames, (ticks, faults))
        peer.node.create_subscription(
            DiagnosticArray, '/diagnostics', self._received,
            QoSProfile(depth=100, reliability=ReliabilityPolicy.RELIABLE))

    def watch(self, name, pid):
        """Record from now on the counts of the node of that name (its process: pid)."""
        what, key = COUNTS[name]
        with self._lock:
            self._watched = ('%s: %s' % (name, what), key, pid)
            self.records = []

    def _received(self, msg):
        with self._lock:
            if self._watched is None:
                return
            name, key, pid = self._watched
            for status in msg.status:
                if status.name != name:
                    continue
                values = {kv.key: kv.value for kv in status.values}
                stat = process_stat(pid)
                if key in values and stat is not None:
                    self.records.append((time.monotonic(), int(values[key]), stat))

    def first_after(self, when, frames_at_least=0):
        """Return the first record that arrived after `when` with at least that many frames."""
        with self._lock:
            for record in self.records:
                if record[0] > when and record[1] >= frames_at_least:
                    return record
        return None


def receiver_command(receiver, size, python):
    """Return the command of a receiver; '{out}' is the bare subscriber's results file."""
    if receiver == 'bare':
        return [python, str(BENCH / 'bare_image_subscriber.py'), '{out}', 'reliable',
                '--py-vision-profile']
    # As a launch file starts them: every node told the camera's size (pipeline.launch.py's
    # params.yaml), which sizes the shared memory of the nodes that publish what they receive.
    params = {'image_width': size[0], 'image_height': size[1]}
    if receiver == 'usbcam_subscriber':
        params.update(display='none', stats_period=5.0)
        executable = 'usbcam_subscriber'
    elif receiver == 'cv_bridge_test':
        executable = 'cv_bridge_test'
    else:
        executable = 'vision_step'
        params['step'] = 'nothing_step:Nothing' if receiver.endswith('nothing') else 'circle'
    return [str(ros_harness.EXECUTABLES / executable)] + ros_harness.ros_args(params)


def measure(receiver, size, window, env, workdir, reports, log=print):
    """Run one receiver against the running publisher; return its figures (or an 'error')."""
    node = receiver.split()[0]
    result = {'receiver': receiver}
    proc = start_helper(receiver.replace(' ', '_'), receiver_command(receiver, size,
                                                                     sys.executable),
                        env, workdir)
    try:
        if node == 'bare':
            ros_harness.wait_until(lambda: FIRST_FRAME_MARK in proc.output()
                                   or proc.proc.poll() is not None, START_S, 0.1, 'a frame')
            if proc.proc.poll() is not None:
                raise AssertionError('it ended')
            time.sleep(SETTLE_S)
            start = (time.monotonic(), None, process_stat(proc.pid))
            time.sleep(window)
            end = (time.monotonic(), None, process_stat(proc.pid))
        else:
            reports.watch(node, proc.pid)
            begun = time.monotonic()
            ros_harness.wait_until(lambda: reports.first_after(begun, 1)
                                   or proc.proc.poll() is not None, START_S, 0.1,
                                   'frames counted on /diagnostics')
            if proc.proc.poll() is not None:
                raise AssertionError('it ended')
            settled = time.monotonic() + SETTLE_S
            start = ros_harness.wait_until(lambda: reports.first_after(settled), 10, 0.05,
                                           'a report')
            end = ros_harness.wait_until(lambda: reports.first_after(start[0] + window),
                                         10 + window, 0.05, 'a report')
        result['rss_mib'] = rss_mib(proc.pid)
    except AssertionError as error:
        result['error'] = '%s: %s' % (receiver, error)
    finally:
        status = proc.end(timeout=15.0)
    if 'error' not in result and not status:
        result['error'] = '%s did not stop on SIGINT' % receiver
    if 'error' in result or proc.proc.returncode:
        result.setdefault('error', '%s ended with status %s' % (receiver, proc.proc.returncode))
        log('  %s\n%s' % (result['error'], proc.output()[-2000:]))
        return result
    seconds = end[0] - start[0]
    if node == 'bare':
        received = read_results(proc)['received']
        frames = sum(1 for record in received if start[0] <= record[0] < end[0])
    else:
        frames = end[1] - start[1]
    ticks, system, faults = (b - a for a, b in zip(start[2], end[2]))
    result.update(frames=frames, seconds=round(seconds, 3),
                  fps=round(frames / seconds, 2),
                  cpu_percent=round(100.0 * ticks / CLK_TCK / seconds, 2),
                  cpu_ms_per_frame=round(1000.0 * ticks / CLK_TCK / frames, 3) if frames
                  else None,
                  system_ms_per_frame=round(1000.0 * system / CLK_TCK / frames, 3) if frames
                  else None,
                  faults_per_frame=round(faults / frames, 1) if frames else None)
    return result


def run_size(size, fps, receivers, rounds, window, base_env, log=print):
    """Run every receiver `rounds` times against one publisher of size at fps; return runs."""
    domain = ros_harness.DomainId()
    env = dict(base_env, ROS_DOMAIN_ID=str(domain.value))
    workdir = tempfile.mkdtemp(prefix='pyv_receive_')
    peer = ros_harness.RosPeer(domain.value, name='bench_receive')
    reports = Reports(peer)
    publisher = start_helper('publisher', [
        sys.executable, str(BENCH / 'bare_image_publisher.py'), '{out}', str(size[0]),
        str(size[1]), repr(float(fps)), 'reliable', '--py-vision-profile'], env, workdir)
    runs = []
    try:
        for number in range(rounds):
            # The order turns each round, so that no receiver always follows the same one.
            turn = number % len(receivers)
            for receiver in receivers[turn:] + receivers[:turn]:
                result = measure(receiver, size, window, env, workdir, reports, log)
                result.update(round=number, size='%dx%d' % size, target_fps=fps)
                runs.append(result)
                log('[%dx%d@%g round %d] %-20s %s' % (
                    size[0], size[1], fps, number + 1, receiver, result.get('error') or
                    '%.3f ms a frame, %.1f fps, %.0f faults a frame, %s MiB' % (
                        result['cpu_ms_per_frame'] or 0, result['fps'],
                        result['faults_per_frame'] or 0, result['rss_mib'])))
    finally:
        publisher.end(timeout=15.0)
        peer.close()
        domain.release()
    return runs


def summarise(runs, receivers):
    """Return one row per (size, rate, receiver): medians, and the ratio to the bare one."""
    rows = []
    for key in sorted({(r['size'], r['target_fps']) for r in runs},
                      key=lambda k: (int(k[0].split('x')[0]), k[1])):
        here = [r for r in runs if (r['size'], r['target_fps']) == key and 'error' not in r]
        bare = {r['round']: r['cpu_ms_per_frame'] for r in here if r['receiver'] == 'bare'}
        for receiver in receivers:
            mine = [r for r in here if r['receiver'] == receiver]
            if not mine:
                continue
            ratios = [r['cpu_ms_per_frame'] / bare[r['round']] for r in mine
                      if bare.get(r['round']) and r['cpu_ms_per_frame']]
            rows.append({
                'size': key[0], 'target_fps': key[1], 'receiver': receiver,
                'rounds': len(mine),
                'cpu_ms_per_frame': median([r['cpu_ms_per_frame'] for r in mine]),
                'system_ms_per_frame': median([r['system_ms_per_frame'] for r in mine]),
                'ratio_to_bare': round(statistics.median(ratios), 3) if ratios else None,
                'ratios': [round(ratio, 3) for ratio in ratios],
                'fps': median([r['fps'] for r in mine]),
                'faults_per_frame': median([r['faults_per_frame'] for r in mine]),
                'rss_mib': median([r['rss_mib'] for r in mine]),
            })
    return rows


def median(values):
    values = [value for value in values if value is not None]
    return round(statistics.median(values), 3) if values else None


def fmt(value, digits=2):
    return '-' if value is None else '%.*f' % (digits, value)


def table(rows):
    lines = ['| size | fps | receiver | CPU ms a frame | of which kernel | ratio to bare | '
             'faults a frame | received fps | RSS MiB | rounds |',
             '|---|---:|---|---:|---:|---:|---:|---:|---:|---:|']
    for row in rows:
        lines.append('| %s | %g | %s | %s | %s | %s | %s | %s | %s | %d |' % (
            row['size'], row['target_fps'], row['receiver'], fmt(row['cpu_ms_per_frame']),
            fmt(row['system_ms_per_frame']), fmt(row['ratio_to_bare']),
            fmt(row['faults_per_frame'], 0), fmt(row['fps'], 1), fmt(row['rss_mib'], 1),
            row['rounds']))
    return '\n'.join(lines)


def parse_sizes(text):
    try:
        return [tuple(int(part) for part in size.split('x')) for size in text.split(',')]
    except ValueError:
        raise argparse.ArgumentTypeError('sizes are WIDTHxHEIGHT, comma-separated') from None


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split('\n\n')[0])
    parser.add_argument('--sizes', type=parse_sizes, default=parse_sizes('640x480,1280x720'),
                        help='frame sizes (640x480,1280x720)')
    parser.add_argument('--rates', default='30', help='frame rates, comma-separated (30)')
    parser.add_argument('--window', type=float, default=15.0,
                        help='measurement window per receiver, s (15)')
    parser.add_argument('--rounds', type=int, default=3, help='rounds; medians (3)')
    parser.add_argument('--receivers', default=','.join(RECEIVERS),
                        help='comma-separated, of: %s' % ', '.join(RECEIVERS))
    parser.add_argument('--label', default='', help='a word added to the results file name')
    args = parser.parse_args(argv)
    receivers = [name.strip() for name in args.receivers.split(',') if name.strip()]
    unknown = [name for name in receivers if name not in RECEIVERS]
    if unknown:
        parser.error('unknown receivers: %s' % ', '.join(unknown))
    env = local_node_env()
    env['PYTHONPATH'] = str(BENCH) + os.pathsep + env.get('PYTHONPATH', '')
    runs = []
    started = time.monotonic()
    for size in args.sizes:
        for fps in (float(rate) for rate in args.rates.split(',')):
            runs += run_size(size, fps, receivers, args.rounds, args.window, env)
    rows = summarise(runs, receivers)
    load = ' '.join('%.2f' % value for value in os.getloadavg())
    print('\n%d s, load average %s' % (time.monotonic() - started, load))
    print(table(rows))
    name = 'receive-py%d.%d' % sys.version_info[:2]
    save_results(name + ('-' + args.label if args.label else ''), {
        'window_s': args.window, 'rounds': args.rounds, 'rows': rows, 'runs': runs,
        'loadavg_end': os.getloadavg()})
    return 0 if rows else 1


if __name__ == '__main__':
    sys.exit(main())
