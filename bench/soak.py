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
Soak test: run py_vision's publisher and subscriber for minutes and watch them grow.

  .venv/bin/python bench/soak.py [--minutes 10] [--fps 30] [--width 640 --height 480]
                                 [--sample-every 10]

Starts the installed ``usbcam_publisher`` (``video_device:=synthetic``) and
``usbcam_subscriber`` (``display:=none``), each through bench/pyv_nodes.py (the nodes
unchanged, plus one record per frame: the publisher's (time, frame index) of every captured
frame, the subscriber's (arrival, frame index, latency) of every image), as separate processes
on a domain id of their own, with localhost discovery and the Fast DDS profile the nodes ship.
Every few seconds it samples each process from /proc: resident memory, open file descriptors,
threads and CPU. At the end both get SIGINT and must exit with status 0; their records then
give frames published, received and lost (by the synthetic frames' index) and latency.

Verdict, after a warm-up that is left out (the first minute): resident memory, less what the
per-frame records themselves hold (their cost per record is measured in a child process of the
same Python), grows less than a tolerance (a line fitted through the samples), file descriptors
do not grow, no published frame is lost, and the frames received after the warm-up are fps x
duration. Writes bench/results/soak.json and soak.png (copied to docs/soak.png) and prints a
table.
"""

import argparse
from bisect import bisect_right
import json
import os
from pathlib import Path
import re
import shutil
import signal
import subprocess
import sys
import tempfile
import time

from bench_common import (BENCH, CLK_TCK, cpu_ticks, read_results, REPO, RESULTS,
                          start_helper)
from py_vision.stats import percentile
import ros_harness
from ros_harness import DomainId

LOG_FORMAT = '[{severity}] [{time}] [{name}]: {message}'
ROLES = ('publisher', 'subscriber')
# Only for the progress lines while it runs; the counts come from the records.
RECEIVED_LINE = re.compile(r'\[usbcam_subscriber\]: received (\d+) frames')

# What one record of pyv_nodes costs: the same tuples, appended to a list in a fresh process.
RECORD_COST = """
import sys, time
def rss():
    with open('/proc/self/status') as stream:
        for line in stream:
            if line.startswith('VmRSS:'):
                return int(line.split()[1]) * 1024
count, fields = int(sys.argv[1]), int(sys.argv[2])
records = []
before = rss()
for index in range(1000, 1000 + count):
    now = time.monotonic()
    records.append((now, index) if fields == 2 else (now, index, now - 0.001))
print((rss() - before) / count)
"""
RECORD_FIELDS = {'publisher': 2, 'subscriber': 3}


# ----------------------------------------------------------------------------- /proc

def proc_status(pid):
    """Return VmRSS and its parts (bytes) and the thread count of a process, or None if gone."""
    wanted = {'VmRSS': 'rss', 'RssAnon': 'rss_anon', 'RssFile': 'rss_file',
              'RssShmem': 'rss_shmem', 'Threads': 'threads'}
    values = {}
    try:
        with open('/proc/%d/status' % pid) as stream:
            for line in stream:
                key, _, rest = line.partition(':')
                if key in wanted:
                    number = int(rest.split()[0])
                    values[wanted[key]] = number * 1024 if key != 'Threads' else number
    except OSError:
        return None
    return values


def fd_count(pid):
    """Return the number of open file descriptors of a process, or None if it is gone."""
    try:
        return len(os.listdir('/proc/%d/fd' % pid))
    except OSError:
        return None


def sample(procs, started):
    """Return one row of measurements: time, load average and /proc numbers of each process."""
    row = {'t': round(time.monotonic() - started, 3), 'wall': time.time(),
           'loadavg': [round(v, 2) for v in os.getloadavg()]}
    for role, proc in procs.items():
        status = proc_status(proc.pid) or {}
        row[role] = dict(status, fds=fd_count(proc.pid), cpu_ticks=cpu_ticks(proc.pid))
        for key in ('rss', 'rss_anon', 'rss_file', 'rss_shmem', 'threads'):
            row[role].setdefault(key, None)
    return row


def add_cpu_percent(samples, roles):
    """Add the CPU% of each process over the interval since the previous sample."""
    for previous, row in zip([None] + samples[:-1], samples):
        for role in roles:
            row[role]['cpu_pct'] = cpu_between(previous, row, role)


def cpu_between(first, last, role):
    if first is None:
        return None
    a, b = first[role]['cpu_ticks'], last[role]['cpu_ticks']
    span = last['t'] - first['t']
    if a is None or b is None or span <= 0:
        return None
    return round(100.0 * (b - a) / CLK_TCK / span, 1)


# ----------------------------------------------------------------------------- analysis

def record_cost(python, role, count=200000):
    """Return the resident bytes one of pyv_nodes' per-frame records of a role holds."""
    done = subprocess.run([python, '-c', RECORD_COST, str(count), str(RECORD_FIELDS[role])],
                          capture_output=True, text=True, check=True, timeout=120)
    return float(done.stdout)


class Frames:
    """The publisher's and the subscriber's per-frame records, indexed for counting."""

    def __init__(self, published, received):
        self.published = sorted(published)  # (monotonic time, frame index)
        self.arrival, self.latency = {}, {}
        self.records = len(received)
        self.record_times = sorted(when for when, _, _ in received)
        self.undecoded = 0
        for when, index, latency in received:
            if index is None:
                self.undecoded += 1
            elif index not in self.arrival:
                self.arrival[index] = when
                self.latency[index] = latency
        self.duplicates = self.records - self.undecoded - len(self.arrival)
        self.arrivals = sorted(self.arrival.values())
        self.first_index = min(self.arrival) if self.arrival else None
        # A published frame is lost if it never arrived, counting from the first one that did
        # (frames before it went out before discovery had matched the subscriber).
        self.lost_times = [t for t, index in self.published
                           if self.first_index is not None and index >= self.first_index
                           and index not in self.arrival]
        self.published_times = [t for t, _ in self.published]

    def published_by(self, now):
        return bisect_right(self.published_times, now)

    def records_by(self, now):
        return bisect_right(self.record_times, now)

    def received_by(self, now):
        return bisect_right(self.arrivals, now)

    def lost_by(self, now):
        return bisect_right(self.lost_times, now)

    def latencies_between(self, first, last):
        """Return the sorted latencies (s) of the frames that arrived in (first, last]."""
        return sorted(self.latency[i] for i, t in self.arrival.items() if first < t <= last)


def add_frames(samples, started, frames, costs):
    """Add to each sample the frames so far and its RSS less what the records hold by then."""
    previous = None
    for row in samples:
        now = started + row['t']
        for role, count in (('publisher', frames.published_by(now)),
                            ('subscriber', frames.records_by(now))):
            proc = row[role]
            proc['records'] = count
            proc['rss_net'] = (None if proc['rss'] is None
                               else int(proc['rss'] - count * costs[role]))
        received = frames.received_by(now)
        lats = frames.latencies_between(started + previous['t'] if previous else 0.0, now)
        span = row['t'] - previous['t'] if previous else None
        row['frames'] = {
            'published': frames.published_by(now), 'received': received,
            'lost': frames.lost_by(now),
            'fps': (round((received - previous['frames']['received']) / span, 2)
                    if span else None),
            'p50_ms': round(percentile(lats, 0.5) * 1e3, 2) if lats else None,
            'p99_ms': round(percentile(lats, 0.99) * 1e3, 2) if lats else None}
        previous = row


def fit_line(points):
    """Least-squares slope and intercept of (x, y) points; slope 0 for fewer than 2 points."""
    if len(points) < 2:
        return 0.0, points[0][1] if points else 0.0
    n = len(points)
    mx = sum(x for x, _ in points) / n
    my = sum(y for _, y in points) / n
    sxx = sum((x - mx) ** 2 for x, _ in points)
    if sxx == 0:
        return 0.0, my
    slope = sum((x - mx) * (y - my) for x, y in points) / sxx
    return slope, my - slope * mx


def growth(samples, role, key, warmup):
    """Return the growth of one quantity after the warm-up: first, last, fitted, per minute."""
    points = [(row['t'], row[role].get(key)) for row in samples
              if row['t'] >= warmup and row[role].get(key) is not None]
    if not points:
        return None
    slope, _ = fit_line(points)
    span = points[-1][0] - points[0][0]
    values = [y for _, y in points]
    return {'first': points[0][1], 'last': points[-1][1], 'min': min(values),
            'max': max(values), 'change': points[-1][1] - points[0][1],
            'fitted_change': slope * span, 'per_min': slope * 60.0, 'span_s': span}


def frame_counts(frames, started, warmup, stop, fps):
    """
    Return the frames published, received and lost over the run and after the warm-up.

    The window after the warm-up ends when the publisher is stopped; a frame counts in it by
    its capture time (lost) or its arrival (received, against fps x duration).
    """
    first, last = started + warmup, stop
    span = last - first
    window = [index for t, index in frames.published if first <= t <= last]
    arrived = bisect_right(frames.arrivals, last) - bisect_right(frames.arrivals, first)
    lats = frames.latencies_between(first, last)
    out = {'published_total': len(frames.published), 'received_total': len(frames.arrival),
           'records_total': frames.records, 'duplicates': frames.duplicates,
           'undecoded': frames.undecoded, 'lost_total': len(frames.lost_times),
           'before_first_delivery': sum(1 for _, index in frames.published
                                        if frames.first_index is None
                                        or index < frames.first_index),
           'window_s': round(span, 3), 'expected_in_window': round(fps * span, 1),
           'published_in_window': len(window),
           'lost_in_window': sum(1 for index in window if index not in frames.arrival),
           'received_in_window': arrived,
           'missing_in_window': round(fps * span - arrived, 1),
           'received_fps_in_window': round(arrived / span, 3) if span > 0 else None,
           'p50_ms_in_window': round(percentile(lats, 0.5) * 1e3, 2) if lats else None,
           'p99_ms_in_window': round(percentile(lats, 0.99) * 1e3, 2) if lats else None}
    if window:
        # The synthetic camera skips an index when it falls a whole frame behind its schedule.
        out['source_skipped_in_window'] = max(window) - min(window) + 1 - len(window)
    return out


def verdict(report, rss_tolerance_mb, frame_tolerance):
    """Return a list of (check, passed, detail) for the README's targets."""
    checks = []
    for role in ROLES:
        rss = report['growth'][role]['rss']
        net = report['growth'][role]['rss_net']
        fds = report['growth'][role]['fds']
        if rss is None or fds is None:
            checks.append(('%s sampled' % role, False, 'no samples after the warm-up'))
            continue
        anon = report['growth'][role]['rss_anon']
        if net is None:
            checks.append(('%s RSS growth < %g MB' % (role, rss_tolerance_mb), False,
                           'no per-frame records to account for; fitted %+.2f MB in all' % (
                               rss['fitted_change'] / 2 ** 20)))
        else:
            fitted = net['fitted_change'] / 2 ** 20
            checks.append((
                '%s RSS growth < %g MB' % (role, rss_tolerance_mb), fitted < rss_tolerance_mb,
                'fitted %+.2f MB (%+.3f MB/min) less the records; in all fitted %+.2f MB, '
                'last - first %+.2f MB, anonymous memory fitted %+.2f MB' % (
                    fitted, net['per_min'] / 2 ** 20, rss['fitted_change'] / 2 ** 20,
                    rss['change'] / 2 ** 20,
                    anon['fitted_change'] / 2 ** 20 if anon else float('nan'))))
        checks.append(('%s fd growth = 0' % role, fds['change'] <= 0,
                       '%d -> %d (range %d..%d)' % (fds['first'], fds['last'], fds['min'],
                                                    fds['max'])))
    frames = report['frames']
    if 'error' in frames:
        checks.append(('frames counted', False, frames['error']))
    else:
        checks.append(('no frame lost (by frame index, whole run)', frames['lost_total'] == 0,
                       'lost %d of %d published after the first delivery, of which %d after '
                       'the warm-up' % (frames['lost_total'], frames['published_total']
                                        - frames['before_first_delivery'],
                                        frames['lost_in_window'])))
        checks.append(('received = fps x duration (+-%g)' % frame_tolerance,
                       abs(frames['missing_in_window']) <= frame_tolerance,
                       'expected %s, received %s in %s s after the warm-up' % (
                           frames['expected_in_window'], frames['received_in_window'],
                           frames['window_s'])))
    for role, status in report['exit_status'].items():
        checks.append(('%s exits with 0 on SIGINT' % role, status == 0, 'exit %s' % status))
    return checks


# ----------------------------------------------------------------------------- output

def mb(value):
    return '-' if value is None else '%.1f' % (value / 2 ** 20)


def opt(value, form='%s'):
    return '-' if value is None else form % value


def minute_rows(samples):
    """Return the samples closest to each whole minute (and the last one)."""
    rows, minute = [], 0
    for row in samples:
        if row['t'] >= minute * 60.0 - 1.0:
            rows.append(row)
            minute = int(row['t'] // 60.0) + 1
    if rows[-1] is not samples[-1]:
        rows.append(samples[-1])
    return rows


def table(samples, frames, started):
    """Return a Markdown table of one sample a minute; fps and latency since the row before."""
    head = ('| time | pub RSS MB | pub fds | pub threads | pub CPU% | sub RSS MB | sub fds | '
            'sub threads | sub CPU% | received | fps | lost | p50 ms | p99 ms | load avg |')
    lines = [head, '|' + '---:|' * head.count(' | ') + '---:|']
    rows = minute_rows(samples)
    for previous, row in zip([None] + rows[:-1], rows):
        cells = ['%d:%02d' % divmod(int(round(row['t'])), 60)]
        for role in ROLES:
            p = row[role]
            cells += [mb(p['rss']), opt(p['fds']), opt(p['threads']),
                      opt(cpu_between(previous, row, role))]
        received = fps = lost = p50 = p99 = None
        if frames is not None:
            now = started + row['t']
            since = started + previous['t'] if previous else 0.0
            received, lost = frames.received_by(now), frames.lost_by(now)
            if previous is not None:
                fps = (received - frames.received_by(since)) / (row['t'] - previous['t'])
            lats = frames.latencies_between(since, now)
            if lats:
                p50, p99 = percentile(lats, 0.5) * 1e3, percentile(lats, 0.99) * 1e3
        cells += [opt(received), opt(fps, '%.1f'), opt(lost), opt(p50, '%.1f'),
                  opt(p99, '%.1f'), '%.2f' % row['loadavg'][0]]
        lines.append('| ' + ' | '.join(cells) + ' |')
    return '\n'.join(lines)


def plot(samples, warmup, path, title):
    import matplotlib
    matplotlib.use('Agg')
    import matplotlib.pyplot as plt

    minutes = [row['t'] / 60.0 for row in samples]
    fig, (top, bottom) = plt.subplots(2, 1, figsize=(9, 6.5), sharex=True)
    for role, colour in (('publisher', '#4477aa'), ('subscriber', '#228833')):
        top.plot(minutes, [row[role]['rss'] / 2 ** 20 if row[role]['rss'] else None
                           for row in samples], color=colour, marker='.', label=role)
        if any(row[role].get('rss_net') for row in samples):
            top.plot(minutes, [row[role]['rss_net'] / 2 ** 20 if row[role].get('rss_net')
                               else None for row in samples], color=colour, linestyle='--',
                     label='%s less its per-frame records' % role)
        bottom.plot(minutes, [row[role]['fds'] for row in samples], color=colour,
                    marker='.', label=role)
    for axis in (top, bottom):
        axis.axvspan(0, warmup / 60.0, color='#dddddd', label='warm-up (not judged)')
        axis.grid(True, alpha=0.3)
    top.set_ylabel('resident memory, VmRSS (MB)')
    bottom.set_ylabel('open file descriptors')
    bottom.set_xlabel('minutes since start')
    top.legend(loc='lower right', fontsize=8)
    fig.suptitle(title, fontsize=10)
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)


# ----------------------------------------------------------------------------- main

def start(args, env, workdir):
    """Start the subscriber, then the publisher, through pyv_nodes; return both processes."""
    nodes = [sys.executable, str(BENCH / 'pyv_nodes.py')]
    sub = start_helper('subscriber', nodes + ['subscriber', '{out}', '--ros-args',
                                              '-p', 'display:=none', '-p', 'stats_period:=%r'
                                              % float(args.stats_period)], env, workdir)
    pub = start_helper('publisher', nodes + ['publisher', '{out}', '--ros-args',
                                             '-p', 'video_device:=synthetic',
                                             '-p', 'image_width:=%d' % args.width,
                                             '-p', 'image_height:=%d' % args.height,
                                             '-p', 'framerate:=%r' % float(args.fps)],
                       env, workdir)
    return {'publisher': pub, 'subscriber': sub}


def received_so_far(log):
    """Return the frame count of the subscriber's last statistics line, or '-'."""
    counts = RECEIVED_LINE.findall(log)
    return counts[-1] if counts else '-'


def run(args, env, workdir, log=print):
    """
    Run the soak.

    Return the samples, the start and stop (monotonic), exit statuses, both logs, both nodes'
    per-frame records (None if a node wrote none) and any error.
    """
    procs = start(args, env, workdir)
    started = time.monotonic()
    samples, error = [], None
    duration = args.minutes * 60.0
    try:
        step = 0
        while True:
            row = sample(procs, started)
            samples.append(row)
            gone = [role for role, proc in procs.items() if proc.proc.poll() is not None]
            if gone:
                error = '%s ended early (exit %s)' % (
                    ' and '.join(gone), [procs[r].proc.returncode for r in gone])
                break
            if step % max(1, int(round(60.0 / args.sample_every))) == 0:
                log('[%5.0fs] pub %s MB %s fds | sub %s MB %s fds | received %s | '
                    'load %.2f' % (row['t'], mb(row['publisher']['rss']),
                                   row['publisher']['fds'], mb(row['subscriber']['rss']),
                                   row['subscriber']['fds'],
                                   received_so_far(procs['subscriber'].output()),
                                   row['loadavg'][0]), flush=True)
            step += 1
            due = step * args.sample_every
            if due > duration + 1e-6:
                break
            time.sleep(max(0.0, started + due - time.monotonic()))
    except KeyboardInterrupt:
        error = 'interrupted'
    finally:
        stop = time.monotonic()
        procs['publisher'].end(timeout=15.0)
        # Frames still in flight when the publisher stopped arrive within milliseconds.
        time.sleep(0.5)
        procs['subscriber'].end(timeout=15.0)
        status = {role: procs[role].proc.returncode for role in ROLES}
    records = {role: read_results(procs[role]) for role in ROLES}
    logs = {role: procs[role].output() for role in ROLES}
    return samples, started, stop, status, logs, records, error


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split('\n\n')[0])
    parser.add_argument('--minutes', type=float, default=10.0, help='soak duration (10)')
    parser.add_argument('--fps', type=float, default=30.0, help='publisher frame rate (30)')
    parser.add_argument('--width', type=int, default=640, help='frame width (640)')
    parser.add_argument('--height', type=int, default=480, help='frame height (480)')
    parser.add_argument('--sample-every', type=float, default=10.0,
                        help='seconds between /proc samples (10)')
    parser.add_argument('--stats-period', type=float, default=10.0,
                        help="the subscriber's stats_period parameter, s (10)")
    parser.add_argument('--warmup', type=float, default=60.0,
                        help='seconds left out of the verdict (60)')
    parser.add_argument('--rss-tolerance-mb', type=float, default=1.0,
                        help='allowed fitted RSS growth after the warm-up, MB (1)')
    parser.add_argument('--frame-tolerance', type=float, default=2.0,
                        help='allowed |fps x duration - received| frames, for frames on the '
                             'edges of the window (2)')
    parser.add_argument('--out', default=str(RESULTS), help='results directory')
    parser.add_argument('--docs', default=str(REPO / 'docs'),
                        help='where the plot is copied to ("" for nowhere)')
    args = parser.parse_args(argv)
    if args.sample_every <= 0 or args.stats_period <= 0:
        parser.error('--sample-every and --stats-period must be > 0')
    if args.minutes * 60.0 < args.warmup + 2 * args.sample_every:
        parser.error('--minutes too short: the warm-up (%g s) leaves fewer than two samples'
                     % args.warmup)

    env = ros_harness.plain_env()
    env['ROS_AUTOMATIC_DISCOVERY_RANGE'] = 'LOCALHOST'
    env['RCUTILS_CONSOLE_OUTPUT_FORMAT'] = LOG_FORMAT
    env['RCUTILS_COLORIZED_OUTPUT'] = '0'
    env['PYTHONPATH'] = str(BENCH) + os.pathsep + env.get('PYTHONPATH', '')
    costs = {role: record_cost(sys.executable, role) for role in ROLES}
    out_dir = Path(args.out)
    out_dir.mkdir(parents=True, exist_ok=True)
    workdir = Path(tempfile.mkdtemp(prefix='pyv_soak_'))
    domain = DomainId()
    env['ROS_DOMAIN_ID'] = str(domain.value)

    def interrupted(signum, frame):
        raise KeyboardInterrupt

    signal.signal(signal.SIGTERM, interrupted)
    print('soak: %dx%d@%g for %g min on ROS_DOMAIN_ID %d, sampling every %g s' % (
        args.width, args.height, args.fps, args.minutes, domain.value, args.sample_every),
        flush=True)
    try:
        samples, started, stop, status, logs, records, error = run(args, env, workdir)
    finally:
        domain.release()
    shutil.rmtree(workdir, ignore_errors=True)

    add_cpu_percent(samples, ROLES)
    frames = None
    if records['publisher'] is None or records['subscriber'] is None:
        missing = [role for role in ROLES if records[role] is None]
        counts = {'error': 'no per-frame records from the %s' % ' and '.join(missing)}
    else:
        frames = Frames(records['publisher']['published'], records['subscriber']['received'])
        add_frames(samples, started, frames, costs)
        counts = frame_counts(frames, started, args.warmup, stop, args.fps)
    report = {
        'config': {'minutes': args.minutes, 'fps': args.fps, 'width': args.width,
                   'height': args.height, 'sample_every_s': args.sample_every,
                   'stats_period_s': args.stats_period, 'warmup_s': args.warmup,
                   'rss_tolerance_mb': args.rss_tolerance_mb,
                   'frame_tolerance': args.frame_tolerance},
        'machine': {'cpus': os.cpu_count(), 'loadavg_end': os.getloadavg()},
        'record_bytes': {role: round(cost, 1) for role, cost in costs.items()},
        'error': error, 'exit_status': status,
        'growth': {role: {key: growth(samples, role, key, args.warmup)
                          for key in ('rss', 'rss_net', 'rss_anon', 'rss_file', 'rss_shmem',
                                      'fds', 'threads')} for role in ROLES},
        'frames': counts, 'samples': samples,
    }
    checks = verdict(report, args.rss_tolerance_mb, args.frame_tolerance)
    report['verdict'] = [{'check': c, 'passed': ok, 'detail': d} for c, ok, d in checks]
    report['passed'] = error is None and all(ok for _, ok, _ in checks)
    if error is not None or not report['passed']:
        for role in ROLES:
            report['log_%s_tail' % role] = logs[role][-3000:]
    with open(out_dir / 'soak.json', 'w') as stream:
        json.dump(report, stream, indent=1)

    print()
    print(table(samples, frames, started))
    print()
    if frames is None:
        print('frames: %s' % counts['error'])
    else:
        print('frames: published %d, received %d (%d published before the first delivery: '
              'discovery), lost %d; after the warm-up expected %s (%g fps x %s s), received '
              '%d, p50 %s ms, p99 %s ms; per-frame records hold %.0f (publisher) and %.0f '
              '(subscriber) bytes each' % (
                  counts['published_total'], counts['received_total'],
                  counts['before_first_delivery'], counts['lost_total'],
                  counts['expected_in_window'], args.fps, counts['window_s'],
                  counts['received_in_window'], counts['p50_ms_in_window'],
                  counts['p99_ms_in_window'], costs['publisher'], costs['subscriber']))
    print()
    for check, ok, detail in checks:
        print('- %s %s: %s' % ('PASS' if ok else 'FAIL', check, detail))
    if error:
        print('- FAIL run: %s' % error)
    print('\nverdict: %s' % ('PASS' if report['passed'] else 'FAIL'))
    if samples:
        png = out_dir / 'soak.png'
        plot(samples, args.warmup, png,
             'py_vision soak: usbcam_publisher -> usbcam_subscriber, %dx%d@%g, %g min' % (
                 args.width, args.height, args.fps, args.minutes))
        if args.docs:
            shutil.copyfile(png, Path(args.docs) / 'soak.png')
        print('wrote %s and %s' % (out_dir / 'soak.json', png))
    return 0 if report['passed'] else 1


if __name__ == '__main__':
    sys.exit(main())
