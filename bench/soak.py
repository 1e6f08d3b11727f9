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
Soak test: run the installed publisher and subscriber for minutes and watch them grow.

  .venv/bin/python bench/soak.py [--minutes 10] [--fps 30] [--width 640 --height 480]
                                 [--sample-every 10]

Starts ``usbcam_publisher`` (``video_device:=synthetic``) and ``usbcam_subscriber``
(``display:=none``) as separate processes on a domain id of their own, with localhost discovery
and the Fast DDS profile the nodes ship. Every few seconds it samples each process from /proc:
resident memory, open file descriptors, threads and CPU. The subscriber's statistics lines give
frames received, rate, latency and lost frames (by the synthetic frames' index). At the end both
get SIGINT and must exit with status 0.

Verdict, after a warm-up that is left out (the first minute): resident memory grows less than a
tolerance (a line fitted through the samples), file descriptors do not grow, no frame is lost,
both by the subscriber's count and by comparing received frames with fps x duration.
Writes bench/results/soak.json and soak.png (copied to docs/soak.png) and prints a table.
"""

import argparse
import json
import os
from pathlib import Path
import re
import shutil
import signal
import sys
import tempfile
import time

from bench_pipeline import (CLK_TCK, cpu_ticks, DomainId, INSTALL, installed_env, Proc, REPO,
                            RESULTS, wait_for)

EXECUTABLES = INSTALL / 'py_vision' / 'lib' / 'py_vision'
LOG_FORMAT = '[{severity}] [{time}] [{name}]: {message}'

STATS_LINE = re.compile(
    r'\[(?P<stamp>\d+\.\d+)\] \[usbcam_subscriber\]: received (?P<frames>\d+) frames '
    r'\((?P<fps>[\d.]+) fps\), latency p50 (?P<p50>[\d.]+) ms p99 (?P<p99>[\d.]+) ms, '
    r'lost (?P<lost>\d+), (?P<size>\d+x\d+) (?P<encoding>\S+) on (?P<topic>\S+?)'
    r'(?:, gap of (?P<gap>[\d.]+) s)?$', re.MULTILINE)
IDLE_LINE = re.compile(
    r'\[(?P<stamp>\d+\.\d+)\] \[usbcam_subscriber\]: no frames on \S+ in the last \S+ s '
    r'\((?P<frames>\d+) received in total\)', re.MULTILINE)
PUBLISHED_LINE = re.compile(r'camera released after (\d+) frames')


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

def parse_stats(text):
    """Return the subscriber's statistics lines, in order, as dicts (cumulative frames, lost)."""
    lines = []
    for match in STATS_LINE.finditer(text):
        lines.append({'stamp': float(match['stamp']), 'frames': int(match['frames']),
                      'fps': float(match['fps']), 'p50_ms': float(match['p50']),
                      'p99_ms': float(match['p99']), 'lost': int(match['lost']),
                      'size': match['size'], 'encoding': match['encoding'],
                      'gap_s': float(match['gap']) if match['gap'] else None})
    for match in IDLE_LINE.finditer(text):
        lines.append({'stamp': float(match['stamp']), 'frames': int(match['frames']),
                      'fps': 0.0, 'idle': True})
    lines.sort(key=lambda line: line['stamp'])
    return lines


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
    points = [(row['t'], row[role][key]) for row in samples
              if row['t'] >= warmup and row[role][key] is not None]
    if not points:
        return None
    slope, _ = fit_line(points)
    span = points[-1][0] - points[0][0]
    values = [y for _, y in points]
    return {'first': points[0][1], 'last': points[-1][1], 'min': min(values),
            'max': max(values), 'change': points[-1][1] - points[0][1],
            'fitted_change': slope * span, 'per_min': slope * 60.0, 'span_s': span}


def frame_counts(stats, samples, warmup, fps, published, stop_wall):
    """
    Return the frames expected, received and lost after the warm-up and over the run.

    The window for fps x duration runs from the first statistics line after the warm-up to the
    last one before the publisher was stopped.
    """
    started_wall = samples[0]['wall'] - samples[0]['t']
    active = [s for s in stats if not s.get('idle')]
    after = [s for s in active
             if s['stamp'] - started_wall >= warmup and s['stamp'] < stop_wall]
    out = {'published_total': published,
           'received_total': stats[-1]['frames'] if stats else None,
           'lost_by_subscriber': active[-1]['lost'] if active else None}
    if published is not None and out['received_total'] is not None:
        out['published_minus_received'] = published - out['received_total']
        out['before_first_delivery'] = (out['published_minus_received']
                                        - (out['lost_by_subscriber'] or 0))
    if len(after) >= 2:
        first, last = after[0], after[-1]
        span = last['stamp'] - first['stamp']
        expected = fps * span
        received = last['frames'] - first['frames']
        out.update(window_s=round(span, 3), expected_in_window=round(expected, 1),
                   received_in_window=received,
                   missing_in_window=round(expected - received, 1),
                   lost_by_subscriber_in_window=last['lost'] - first['lost'],
                   received_fps_in_window=round(received / span, 3) if span > 0 else None)
    return out


def verdict(report, rss_tolerance_mb, frame_tolerance):
    """Return a list of (check, passed, detail) for the README's targets."""
    checks = []
    for role in ('publisher', 'subscriber'):
        rss = report['growth'][role]['rss']
        fds = report['growth'][role]['fds']
        if rss is None or fds is None:
            checks.append(('%s sampled' % role, False, 'no samples after the warm-up'))
            continue
        fitted = rss['fitted_change'] / 2 ** 20
        anon = report['growth'][role]['rss_anon']
        checks.append(('%s RSS growth < %g MB' % (role, rss_tolerance_mb),
                       fitted < rss_tolerance_mb,
                       'fitted %+.2f MB (%+.3f MB/min); last - first %+.2f MB; '
                       'anonymous memory fitted %+.2f MB' % (
                           fitted, rss['per_min'] / 2 ** 20, rss['change'] / 2 ** 20,
                           anon['fitted_change'] / 2 ** 20 if anon else float('nan'))))
        checks.append(('%s fd growth = 0' % role, fds['change'] <= 0,
                       '%d -> %d (range %d..%d)' % (fds['first'], fds['last'], fds['min'],
                                                    fds['max'])))
    frames = report['frames']
    lost = frames.get('lost_by_subscriber')
    checks.append(('no frame lost (subscriber count, whole run)', lost == 0,
                   'lost %s, of which %s after the warm-up' % (
                       lost, frames.get('lost_by_subscriber_in_window'))))
    missing = frames.get('missing_in_window')
    checks.append(('received = fps x duration (+-%g)' % frame_tolerance,
                   missing is not None and abs(missing) <= frame_tolerance,
                   'expected %s, received %s in %s s after the warm-up' % (
                       frames.get('expected_in_window'), frames.get('received_in_window'),
                       frames.get('window_s'))))
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


def table(samples, stats):
    head = ('| time | pub RSS MB | pub fds | pub threads | pub CPU% | sub RSS MB | sub fds | '
            'sub threads | sub CPU% | received | fps | lost | p50 ms | p99 ms | load avg |')
    lines = [head, '|' + '---:|' * head.count(' | ') + '---:|']
    rows = minute_rows(samples)
    for previous, row in zip([None] + rows[:-1], rows):
        seen = [s for s in stats if s['stamp'] <= row['wall'] and not s.get('idle')]
        last = seen[-1] if seen else {}
        cells = ['%d:%02d' % divmod(int(round(row['t'])), 60)]
        for role in ('publisher', 'subscriber'):
            p = row[role]
            cells += [mb(p['rss']), opt(p['fds']), opt(p['threads']),
                      opt(cpu_between(previous, row, role))]
        cells += [opt(last.get('frames')), opt(last.get('fps'), '%.1f'), opt(last.get('lost')),
                  opt(last.get('p50_ms'), '%.1f'), opt(last.get('p99_ms'), '%.1f'),
                  '%.2f' % row['loadavg'][0]]
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
    """Start the subscriber, then the publisher; return both Procs."""
    sub = Proc('subscriber', [str(EXECUTABLES / 'usbcam_subscriber'), '--ros-args',
                              '-p', 'display:=none',
                              '-p', 'stats_period:=%r' % float(args.stats_period)],
               env, workdir)
    pub = Proc('publisher', [str(EXECUTABLES / 'usbcam_publisher'), '--ros-args',
                             '-p', 'video_device:=synthetic',
                             '-p', 'image_width:=%d' % args.width,
                             '-p', 'image_height:=%d' % args.height,
                             '-p', 'framerate:=%r' % float(args.fps)],
               env, workdir)
    return {'publisher': pub, 'subscriber': sub}


def run(args, env, workdir, log=print):
    """Run the soak; return samples, exit statuses, both logs, stop time and any error."""
    procs = start(args, env, workdir)
    started = time.monotonic()
    samples, error, stop_wall = [], None, None
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
                stats = parse_stats(procs['subscriber'].output())
                last = stats[-1] if stats else {}
                log('[%5.0fs] pub %s MB %s fds | sub %s MB %s fds | received %s, lost %s | '
                    'load %.2f' % (row['t'], mb(row['publisher']['rss']),
                                   row['publisher']['fds'], mb(row['subscriber']['rss']),
                                   row['subscriber']['fds'], last.get('frames', '-'),
                                   last.get('lost', '-'), row['loadavg'][0]), flush=True)
            step += 1
            due = step * args.sample_every
            if due > duration + 1e-6:
                break
            time.sleep(max(0.0, started + due - time.monotonic()))
    except KeyboardInterrupt:
        error = 'interrupted'
    finally:
        stop_wall = time.time()
        status = {'publisher': procs['publisher'].stop()}
        # One more statistics line after the publisher stopped gives the total received.
        sub = procs['subscriber']
        wait_for(lambda: any(s['stamp'] > stop_wall for s in parse_stats(sub.output()))
                 or sub.proc.poll() is not None, args.stats_period + 5.0, interval=0.2)
        status['subscriber'] = sub.stop()
    return samples, status, procs['publisher'].output(), sub.output(), stop_wall, error


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
                        help='allowed |expected - received| frames, for the boundaries of '
                             'the statistics lines (2)')
    parser.add_argument('--out', default=str(RESULTS), help='results directory')
    parser.add_argument('--docs', default=str(REPO / 'docs'),
                        help='where the plot is copied to ("" for nowhere)')
    args = parser.parse_args(argv)
    if args.sample_every <= 0 or args.stats_period <= 0:
        parser.error('--sample-every and --stats-period must be > 0')
    if args.minutes * 60.0 < args.warmup + 2 * max(args.sample_every, args.stats_period):
        parser.error('--minutes too short: the warm-up (%g s) leaves fewer than two samples'
                     % args.warmup)
    for name in ('usbcam_publisher', 'usbcam_subscriber'):
        if not (EXECUTABLES / name).is_file():
            sys.exit('%s is missing: build first with scripts/setup.sh' % (EXECUTABLES / name))

    env = installed_env()
    env['ROS_AUTOMATIC_DISCOVERY_RANGE'] = 'LOCALHOST'
    env['RCUTILS_CONSOLE_OUTPUT_FORMAT'] = LOG_FORMAT
    env['RCUTILS_COLORIZED_OUTPUT'] = '0'
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
        samples, status, pub_log, sub_log, stop_wall, error = run(args, env, workdir)
    finally:
        domain.release()
    shutil.rmtree(workdir, ignore_errors=True)

    roles = ('publisher', 'subscriber')
    add_cpu_percent(samples, roles)
    stats = parse_stats(sub_log)
    published = PUBLISHED_LINE.search(pub_log)
    report = {
        'config': {'minutes': args.minutes, 'fps': args.fps, 'width': args.width,
                   'height': args.height, 'sample_every_s': args.sample_every,
                   'stats_period_s': args.stats_period, 'warmup_s': args.warmup,
                   'rss_tolerance_mb': args.rss_tolerance_mb,
                   'frame_tolerance': args.frame_tolerance},
        'machine': {'cpus': os.cpu_count(), 'loadavg_end': os.getloadavg()},
        'error': error, 'exit_status': status,
        'growth': {role: {key: growth(samples, role, key, args.warmup)
                          for key in ('rss', 'rss_anon', 'rss_file', 'rss_shmem', 'fds',
                                      'threads')} for role in roles},
        'frames': frame_counts(stats, samples, args.warmup, args.fps,
                               int(published.group(1)) if published else None, stop_wall),
        'samples': samples, 'stats': stats,
    }
    checks = verdict(report, args.rss_tolerance_mb, args.frame_tolerance)
    report['verdict'] = [{'check': c, 'passed': ok, 'detail': d} for c, ok, d in checks]
    report['passed'] = error is None and all(ok for _, ok, _ in checks)
    if error is not None or not report['passed']:
        report['log_publisher_tail'] = pub_log[-3000:]
        report['log_subscriber_tail'] = sub_log[-3000:]
    with open(out_dir / 'soak.json', 'w') as stream:
        json.dump(report, stream, indent=1)

    print()
    print(table(samples, stats))
    frames = report['frames']
    print()
    print('frames: published %s, received %s (%s before the first delivery: discovery), '
          'lost %s; after the warm-up expected %s (%g fps x %s s), received %s' % (
              frames.get('published_total'), frames.get('received_total'),
              frames.get('before_first_delivery'), frames.get('lost_by_subscriber'),
              frames.get('expected_in_window'), args.fps, frames.get('window_s'),
              frames.get('received_in_window')))
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
