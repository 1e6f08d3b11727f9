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
Measure what reaches the subscriber: py_vision's nodes against a bare rclpy reference.

One command, every case in separate processes, one after the other:

  .venv/bin/python bench/bench_pipeline.py [--quick] [--duration S] [--repeat N] [--cases ...]

Cases (``--cases`` takes group names or substrings of case names):
  ref-default   bare rclpy publisher -> bare subscriber, Fast DDS defaults (no XML profile)
  ref-tuned     the same with FASTRTPS_DEFAULT_PROFILES_FILE = py_vision's installed profile,
                its shared memory sized for three frames as py_vision's publisher sizes it
  pyv-pyv       usbcam_publisher (synthetic source) -> usbcam_subscriber (display:=none)
  pyv-bare      usbcam_publisher (synthetic source) -> bare subscriber
  pyv-bare-throttled  the same, the publisher with a throughput controller (see THROTTLE)
  netns         ref-default, ref-tuned, pyv-pyv and pyv-bare between two network namespaces
                joined by a veth pair (root only), and pyv-bare-throttled: the publisher with
                the packaged profile plus a throughput controller (THROTTLE), a default
                subscriber; the subscriber namespace's UDP receive-buffer drops are counted
each at 640x480, 1280x720 and 1920x1080, at 30 fps and a high rate, with a best-effort and a
reliable subscriber.

Per case: start the subscriber, then the publisher; wait for the first frame (discovery is not
measured), settle for a second, then measure a fixed window. Frames are counted by frame index:
every frame the publisher published in the window is delivered or lost. Latency is capture (or
publish) stamp to subscriber callback. CPU% is utime+stime from /proc over the window.
Writes bench/results/pipeline.json and pipeline.png and prints a Markdown table. Processes,
environments, domains and the two hosts are the tests' harness (ros_harness, bench_common).
"""

import argparse
import functools
import json
import os
from pathlib import Path
import re
import shutil
import signal
import statistics
import subprocess
import sys
import tempfile
import time

from bench_common import (BENCH, CLK_TCK, cpu_ticks, FIRST_FRAME_MARK, machine_ticks,
                          read_results, RESULTS, start_helper)
from py_vision.stats import percentile
import ros_harness
from ros_harness import DomainId

PROFILE = ros_harness.SHARE / 'config' / 'fastdds_image_profile.xml'

SIZES = ((640, 480), (1280, 720), (1920, 1080))
HIGH_RATE = {(640, 480): 200.0, (1280, 720): 60.0, (1920, 1080): 60.0}
RELIABILITIES = ('best_effort', 'reliable')
NETNS_FPS = 15.0
# The two "hosts" (network namespaces joined by a veth pair, each process with a /dev/shm of
# its own, so that shared memory cannot carry frames between them).
HOSTS = ('publisher', 'subscriber')


def check_profile(env):
    """Return Fast DDS' complaints about the installed profile (it names unknown elements)."""
    probe = ('import rclpy; rclpy.init(); node = rclpy.create_node("profile_check"); '
             'node.destroy_node(); rclpy.shutdown()')
    env = dict(env, FASTRTPS_DEFAULT_PROFILES_FILE=str(PROFILE), ROS_DOMAIN_ID='0',
               ROS_AUTOMATIC_DISCOVERY_RANGE='LOCALHOST')
    done = subprocess.run([sys.executable, '-c', probe], env=env, capture_output=True,
                          text=True, timeout=60)
    lines = (done.stdout + done.stderr).splitlines()
    problems = [line for line in lines if 'XMLPARSER' in line or 'Error' in line]
    if done.returncode != 0 and not problems:
        problems = lines[-5:]
    return problems


def receive_buffer_errors(hosts):
    """UDP datagrams the subscriber's host dropped for a full socket buffer, so far."""
    out = hosts.read(HOSTS[1], ['cat', '/proc/net/snmp'])
    rows = [line.split() for line in out.splitlines() if line.startswith('Udp:')]
    if len(rows) < 2:
        return None
    return int(dict(zip(rows[0][1:], rows[1][1:])).get('RcvbufErrors', 0))


def veth_tx_bytes(hosts):
    """Bytes the publisher's veth end has sent so far."""
    out = hosts.read(HOSTS[0], ['cat', '/sys/class/net/%s/statistics/tx_bytes'
                                % hosts.device[HOSTS[0]]])
    return int(out) if out.strip().isdigit() else None


# ----------------------------------------------------------------------------- cases

def make_case(group, pub, sub, transport, reliability, size, fps, netns=False):
    width, height = size
    return {
        'name': '%s %dx%d@%g %s' % (group, width, height, fps, reliability),
        'group': group, 'publisher': pub, 'subscriber': sub, 'transport': transport,
        'reliability': reliability, 'width': width, 'height': height, 'fps': fps,
        'netns': netns,
    }


def all_cases(quick):
    sizes = SIZES[:1] if quick else SIZES
    cases = []
    for rel in RELIABILITIES:
        for fps in (30.0, HIGH_RATE[SIZES[0]]):
            cases.append(make_case('ref-default', 'bare', 'bare', 'default', rel, SIZES[0], fps))
    for group, pub, sub, transport in (('ref-tuned', 'bare', 'bare', 'tuned'),
                                       ('pyv-pyv', 'pyv', 'pyv', 'packaged'),
                                       ('pyv-bare', 'pyv', 'bare', 'packaged')):
        for size in sizes:
            for fps in (30.0, HIGH_RATE[size]):
                for rel in RELIABILITIES:
                    cases.append(make_case(group, pub, sub, transport, rel, size, fps))
    # The throttled publisher on one host: what pacing costs where there is no network.
    for rel in RELIABILITIES:
        cases.append(make_case('pyv-bare-throttled', 'pyv', 'bare', 'throttled', rel, SIZES[0],
                               30.0))
    # pyv-bare across hosts: py_vision's publisher and a subscriber with Fast DDS' defaults,
    # e.g. rqt_image_view or the user's own node on a PC.
    for group, pub, sub, transport in (('netns ref-default', 'bare', 'bare', 'default'),
                                       ('netns ref-tuned', 'bare', 'bare', 'tuned'),
                                       ('netns pyv-pyv', 'pyv', 'pyv', 'packaged'),
                                       ('netns pyv-bare', 'pyv', 'bare', 'packaged'),
                                       ('netns pyv-bare-throttled', 'pyv', 'bare',
                                        'throttled')):
        for rel in RELIABILITIES:
            cases.append(make_case(group, pub, sub, transport, rel, SIZES[0], NETNS_FPS,
                                   netns=True))
    return cases


def select_cases(cases, wanted):
    if not wanted:
        return cases
    chosen = []
    for case in cases:
        for want in wanted:
            if case['group'] == want or case['group'].startswith(want + ' ') \
                    or want in case['name']:
                chosen.append(case)
                break
    return chosen


def commands(case, python):
    """Return (publisher cmd, subscriber cmd) for a case; '{out}' is the results file."""
    w, h, fps, rel = case['width'], case['height'], case['fps'], case['reliability']
    if case['publisher'] == 'bare':
        pub = [python, str(BENCH / 'bare_image_publisher.py'), '{out}', str(w), str(h),
               repr(fps), rel]
    else:
        pub = [python, str(BENCH / 'pyv_nodes.py'), 'publisher', '{out}', '--ros-args',
               '-p', 'video_device:=synthetic', '-p', 'image_width:=%d' % w,
               '-p', 'image_height:=%d' % h, '-p', 'framerate:=%r' % fps,
               '-p', 'reliability:=%s' % rel]
    if case['subscriber'] == 'bare':
        sub = [python, str(BENCH / 'bare_image_subscriber.py'), '{out}', rel]
    else:
        # usbcam_subscriber chooses its reliability from the publishers it sees.
        sub = [python, str(BENCH / 'pyv_nodes.py'), 'subscriber', '{out}', '--ros-args',
               '-p', 'display:=none', '-p', 'stats_period:=5.0']
    return pub, sub


# The publisher-side remedy tried for the default subscriber's losses across hosts: Fast DDS
# 2.x's throughput controller (XML in 2.6 and 2.14; named flow controllers only from 3.0) on
# an asynchronous writer. It paces every transport of the writer, shared memory included.
THROTTLE = (65536, 1)  # bytes per period, period in ms
THROTTLED_WRITER = (
    '  <data_writer profile_name="py_vision_throttled" is_default_profile="true">\n'
    '    <qos><publishMode><kind>ASYNCHRONOUS</kind></publishMode></qos>\n'
    '    <throughputController>\n'
    '      <bytesPerPeriod>%d</bytesPerPeriod>\n'
    '      <periodMillisecs>%d</periodMillisecs>\n'
    '    </throughputController>\n'
    '  </data_writer>\n'
    '</profiles>')


def sized_profile(case):
    """Return the installed profile's text with shared memory for three of the case's frames."""
    # As py_vision's publisher sizes its own (py_vision/dds.py); the file holds VGA's.
    return re.sub(r'<segment_size>\d+</segment_size>', '<segment_size>%d</segment_size>' % (
        3 * case['width'] * case['height'] * 3), PROFILE.read_text())


def publisher_env(env, case, workdir):
    """Return the publisher's environment: the subscriber's, or the throttled profile's."""
    if case['transport'] != 'throttled':
        return env
    profile = workdir / 'throttled.xml'
    profile.write_text(sized_profile(case).replace('</profiles>', THROTTLED_WRITER % THROTTLE))
    # rmw_fastrtps makes every writer synchronous unless told otherwise.
    return dict(env, FASTRTPS_DEFAULT_PROFILES_FILE=str(profile),
                RMW_FASTRTPS_PUBLICATION_MODE='ASYNCHRONOUS')


def case_env(base, case, domain, workdir):
    env = dict(base)
    env['ROS_DOMAIN_ID'] = str(domain)
    if case['netns']:
        # Discovery by multicast on the veth subnet: what two hosts on one LAN do by default.
        env['ROS_AUTOMATIC_DISCOVERY_RANGE'] = 'SUBNET'
    else:
        env['ROS_AUTOMATIC_DISCOVERY_RANGE'] = 'LOCALHOST'
    env['PYTHONPATH'] = str(BENCH) + os.pathsep + env.get('PYTHONPATH', '')
    if case['transport'] == 'tuned':
        profile = workdir / 'tuned.xml'
        profile.write_text(sized_profile(case))
        env['FASTRTPS_DEFAULT_PROFILES_FILE'] = str(profile)
    # 'default' and 'packaged': no profile variable; py_vision's nodes then load their own.
    return env


def run_case(case, base_env, domain, duration, settle, python, hosts=None, log=print):
    """Run one case (a netns one on hosts); return its measurements (or an 'error')."""
    workdir = Path(tempfile.mkdtemp(prefix='pyv_bench_'))
    env = case_env(base_env, case, domain, workdir)
    pub_cmd, sub_cmd = commands(case, python)
    on_hosts = hosts if case['netns'] else None
    result = dict(case)
    sub = start_helper('subscriber', sub_cmd, env, workdir,
                       on_hosts and functools.partial(hosts.command, HOSTS[1]))
    pub = start_helper('publisher', pub_cmd, publisher_env(env, case, workdir), workdir,
                       on_hosts and functools.partial(hosts.command, HOSTS[0]))
    try:
        try:
            ros_harness.wait_until(lambda: FIRST_FRAME_MARK in sub.output()
                                   or sub.proc.poll() is not None
                                   or pub.proc.poll() is not None, 40, 0.05, 'a frame')
            if FIRST_FRAME_MARK not in sub.output():
                result['error'] = 'a process ended early'
        except AssertionError:
            result['error'] = 'no frame reached the subscriber within 40 s'
        if 'error' not in result:
            time.sleep(settle)
            pids = (pub.pid, sub.pid)
            t0 = time.monotonic()
            cpu0 = [cpu_ticks(pid) for pid in pids]
            m0 = machine_ticks()
            tx0 = veth_tx_bytes(on_hosts) if on_hosts else None
            drops0 = receive_buffer_errors(on_hosts) if on_hosts else None
            time.sleep(duration)  # the measurement window itself
            t1 = time.monotonic()
            cpu1 = [cpu_ticks(pid) for pid in pids]
            m1 = machine_ticks()
            tx1 = veth_tx_bytes(on_hosts) if on_hosts else None
            drops1 = receive_buffer_errors(on_hosts) if on_hosts else None
            result.update(window=(t0, t1), cpu0=cpu0, cpu1=cpu1, machine=(m0, m1),
                          receive_buffer_drops=(drops1 - drops0) if drops0 is not None
                          and drops1 is not None else None,
                          veth_bytes=(tx1 - tx0) if tx0 is not None and tx1 is not None
                          else None)
    finally:
        pub.end(timeout=15.0)
        # Frames still in flight when the publisher stopped may arrive a little later.
        time.sleep(0.5)
        sub.end(timeout=15.0)
    published, received = read_results(pub), read_results(sub)
    if 'error' not in result and (published is None or received is None):
        result['error'] = 'no results from the %s (exit %s)' % (
            'publisher' if published is None else 'subscriber',
            pub.proc.returncode if published is None else sub.proc.returncode)
    if 'error' in result:
        result['log_publisher'] = pub.output()[-2000:]
        result['log_subscriber'] = sub.output()[-2000:]
        log('  %s: %s' % (case['name'], result['error']))
    else:
        analyse(result, published['published'], received['received'])
        result['subscriber_log_tail'] = [line for line in sub.output().splitlines()
                                         if 'received' in line][-1:]
    shutil.rmtree(workdir, ignore_errors=True)
    return result


def analyse(result, published, received):
    """Count delivered and lost frames of the window and the latency of the delivered ones."""
    t0, t1 = result.pop('window')
    span = t1 - t0
    in_window = {index for t, index in published if t0 <= t <= t1 and index is not None}
    latency = {}
    undecoded = 0
    for _, index, lat in received:
        if index is None:
            undecoded += 1
        elif index in in_window and index not in latency:
            latency[index] = lat
    lats = sorted(latency.values())
    result['published'] = len(in_window)
    result['published_fps'] = round(len(in_window) / span, 2)
    if in_window:
        result['source_skipped'] = max(in_window) - min(in_window) + 1 - len(in_window)
    result['delivered'] = len(latency)
    result['delivered_fps'] = round(len(latency) / span, 2)
    result['delivered_pct'] = round(100.0 * len(latency) / max(1, len(in_window)), 2)
    result['lost'] = len(in_window) - len(latency)
    result['undecoded'] = undecoded
    result['latency_ms'] = [round(v * 1e3, 3) for v in lats]
    result['p50_ms'] = round(percentile(lats, 0.5) * 1e3, 2) if lats else None
    result['p99_ms'] = round(percentile(lats, 0.99) * 1e3, 2) if lats else None
    cpu0, cpu1 = result.pop('cpu0'), result.pop('cpu1')
    for role, a, b in zip(('pub', 'sub'), cpu0, cpu1):
        result['%s_cpu_pct' % role] = (round(100.0 * (b - a) / CLK_TCK / span, 1)
                                       if a is not None and b is not None else None)
    (busy0, total0), (busy1, total1) = result.pop('machine')
    cores = os.cpu_count() or 1
    result['machine_busy_pct'] = round(100.0 * cores * (busy1 - busy0) / max(1, total1 - total0),
                                       1)
    result['window_s'] = round(span, 3)
    if result.get('veth_bytes') is not None and result['delivered']:
        frame = result['width'] * result['height'] * 3
        result['veth_bytes_per_frame_ratio'] = round(
            result['veth_bytes'] / (frame * max(1, result['published'])), 3)


# ----------------------------------------------------------------------------- aggregation

NUMERIC = ('published_fps', 'delivered_fps', 'delivered_pct', 'lost', 'p50_ms', 'p99_ms',
           'pub_cpu_pct', 'sub_cpu_pct', 'machine_busy_pct', 'receive_buffer_drops')


def combine(runs):
    """Median of each number over the repeats of one case; latencies pooled."""
    ok = [r for r in runs if 'error' not in r]
    if not ok:
        return dict(runs[-1], repeats=len(runs))
    out = dict(ok[0])
    for key in NUMERIC:
        values = [r.get(key) for r in ok if r.get(key) is not None]
        value = statistics.median(values) if values else None
        out[key] = round(value, 2) if isinstance(value, float) else value
    out['latency_ms'] = sorted(v for r in ok for v in r['latency_ms'])
    out['repeats'] = len(ok)
    out['errors'] = [r['error'] for r in runs if 'error' in r]
    return out


def add_ratios(results):
    """p50 latency relative to the tuned bare reference of the same size, rate and QoS."""
    refs = {}
    for r in results:
        if r['transport'] == 'tuned' and r['publisher'] == 'bare' and r.get('p50_ms'):
            refs[(r['netns'], r['width'], r['height'], r['fps'], r['reliability'])] = r['p50_ms']
    for r in results:
        ref = refs.get((r['netns'], r['width'], r['height'], r['fps'], r['reliability']))
        r['p50_ratio'] = round(r['p50_ms'] / ref, 2) if ref and r.get('p50_ms') else None


def fmt(value, digits=1):
    if value is None:
        return '-'
    if isinstance(value, float):
        return '%.*f' % (digits, value)
    return str(value)


def table(results):
    lines = ['| case | transport | reliability | size | target fps | published fps | '
             'delivered fps | delivered % | lost | p50 ms | p99 ms | pub CPU% | sub CPU% | '
             'p50 vs tuned ref | UDP receive buffer drops |',
             '|---|---|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|']
    for r in results:
        where = ' (2 hosts)' if r['netns'] else ''
        if 'error' in r and 'delivered' not in r:
            lines.append('| %s%s | %s | %s | %dx%d | %g | %s |' % (
                r['group'], where, r['transport'], r['reliability'], r['width'], r['height'],
                r['fps'], 'failed: ' + r['error']))
            continue
        lines.append('| %s%s | %s | %s | %dx%d | %g | %s | %s | %s | %s | %s | %s | %s | %s | '
                     '%s | %s |'
                     % (r['group'], where, r['transport'], r['reliability'], r['width'],
                        r['height'], r['fps'], fmt(r['published_fps']),
                        fmt(r['delivered_fps']), fmt(r['delivered_pct'], 2), fmt(r['lost']),
                        fmt(r['p50_ms'], 2), fmt(r['p99_ms'], 2), fmt(r['pub_cpu_pct']),
                        fmt(r['sub_cpu_pct']),
                        fmt(r['p50_ratio'], 2) if r.get('p50_ratio') else '-',
                        fmt(r.get('receive_buffer_drops'))))
    return '\n'.join(lines)


def plot(results, path):
    """Latency distributions (box plots) and delivered fps against the target, per case."""
    import matplotlib
    matplotlib.use('Agg')
    import matplotlib.pyplot as plt

    done = [r for r in results if r.get('latency_ms')]
    if not done:
        return False
    labels = []
    for r in done:
        qos = 'BE' if r['reliability'] == 'best_effort' else 'R'
        labels.append('%s %s %dp@%g' % (r['group'].replace('netns ', '2h '), qos, r['height'],
                                        r['fps']))
    colours = {'ref-default': '#999999', 'ref-tuned': '#4477aa', 'pyv-pyv': '#228833',
               'pyv-bare': '#ccbb44'}
    colour = [colours.get(r['group'].replace('netns ', ''), '#aa3377') for r in done]
    fig, (top, bottom) = plt.subplots(2, 1, figsize=(max(10, 0.42 * len(done) + 2), 9),
                                      sharex=True)
    boxes = top.boxplot([r['latency_ms'] for r in done], whis=(1, 99), showfliers=False,
                        patch_artist=True)
    for patch, c in zip(boxes['boxes'], colour):
        patch.set_facecolor(c)
    top.set_yscale('log')
    top.set_ylabel('latency, stamp to callback (ms)\nbox: p25-p75, whiskers: p1-p99')
    top.grid(True, axis='y', which='both', alpha=0.3)
    x = range(1, len(done) + 1)
    bottom.bar(x, [r['delivered_pct'] for r in done], color=colour)
    bottom.axhline(99, color='red', linewidth=0.8, linestyle='--', label='99%')
    bottom.set_ylim(0, 105)
    bottom.set_ylabel('delivered frames (%)')
    for xi, r in zip(x, done):
        bottom.text(xi, 2, '%.0f fps' % r['delivered_fps'], rotation=90, ha='center',
                    va='bottom', fontsize=7)
    bottom.set_xticks(list(x))
    bottom.set_xticklabels(labels, rotation=90, fontsize=8)
    bottom.legend(loc='lower right')
    fig.suptitle('py_vision image pipeline: bare rclpy reference vs py_vision nodes '
                 '(grey: Fast DDS defaults, blue: tuned profile, green: py_vision -> '
                 'py_vision, yellow: py_vision -> bare)', fontsize=9)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return True


# ----------------------------------------------------------------------------- main

def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split('\n\n')[0])
    parser.add_argument('--quick', action='store_true',
                        help='640x480 only, 3 s windows (about 3 minutes)')
    parser.add_argument('--duration', type=float, help='measurement window per case, s (8)')
    parser.add_argument('--repeat', type=int, default=1,
                        help='runs per case; the table shows medians (1)')
    parser.add_argument('--cases', nargs='*', default=[],
                        help='groups (ref-default ref-tuned pyv-pyv pyv-bare netns) or '
                             'substrings of case names, e.g. "640x480@30"')
    parser.add_argument('--out', default=str(RESULTS), help='results directory')
    args = parser.parse_args(argv)
    duration = args.duration or (3.0 if args.quick else 8.0)
    cases = select_cases(all_cases(args.quick), args.cases)
    if not cases:
        parser.error('no case matches %s' % ' '.join(args.cases))
    if not PROFILE.is_file():
        sys.exit('%s is missing: build first with scripts/setup.sh' % PROFILE)
    base_env = ros_harness.plain_env()
    problems = check_profile(base_env)
    if problems:
        sys.exit('Fast DDS rejects %s:\n%s' % (PROFILE, '\n'.join(problems)))
    python = sys.executable
    out_dir = Path(args.out)
    out_dir.mkdir(parents=True, exist_ok=True)

    skipped = {}
    netns_reason = ros_harness.two_hosts_unavailable() if any(
        c['netns'] for c in cases) else None
    domain = DomainId()
    results = []
    hosts = None
    previous = {sig: signal.getsignal(sig) for sig in (signal.SIGINT, signal.SIGTERM)}

    def interrupted(signum, frame):
        raise KeyboardInterrupt

    signal.signal(signal.SIGTERM, interrupted)
    started = time.monotonic()
    try:
        for number, case in enumerate(cases, 1):
            if case['netns'] and netns_reason is None and hosts is None:
                try:
                    hosts = ros_harness.TwoHosts(HOSTS, tag=domain.value)
                except RuntimeError as error:
                    netns_reason = str(error)
            if case['netns'] and netns_reason is not None:
                skipped[case['name']] = netns_reason
                continue
            runs = []
            for _ in range(max(1, args.repeat)):
                runs.append(run_case(case, base_env, domain.value, duration, 1.0, python,
                                     hosts))
            result = combine(runs)
            results.append(result)
            print('[%2d/%d %4.0fs] %-42s delivered %6s%%  p50 %6s ms  pub CPU %5s%%' % (
                number, len(cases), time.monotonic() - started, case['name'],
                fmt(result.get('delivered_pct'), 2), fmt(result.get('p50_ms'), 2),
                fmt(result.get('pub_cpu_pct'))), flush=True)
    except KeyboardInterrupt:
        print('interrupted: reporting the cases done so far', file=sys.stderr)
    finally:
        if hosts is not None:
            hosts.close()
        domain.release()
        for sig, handler in previous.items():
            signal.signal(sig, handler)

    add_ratios(results)
    report = {
        'machine': {'cpus': os.cpu_count(), 'loadavg_end': os.getloadavg(),
                    'rmem_max': Path('/proc/sys/net/core/rmem_max').read_text().strip(),
                    'wmem_max': Path('/proc/sys/net/core/wmem_max').read_text().strip()},
        'duration_s': duration, 'repeat': args.repeat, 'skipped': skipped,
        'profile': str(PROFILE), 'results': results,
    }
    with open(out_dir / 'pipeline.json', 'w') as stream:
        json.dump(report, stream, indent=1)
    print()
    print(table(results))
    for name, reason in skipped.items():
        print('skipped %s: %s' % (name, reason))
    if plot(results, out_dir / 'pipeline.png'):
        print('\nwrote %s and %s' % (out_dir / 'pipeline.json', out_dir / 'pipeline.png'))
    return 0


if __name__ == '__main__':
    sys.exit(main())
