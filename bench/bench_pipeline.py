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
Writes bench/results/pipeline.json and pipeline.png and prints a Markdown table.
"""

import argparse
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

BENCH = Path(__file__).resolve().parent
REPO = BENCH.parent
INSTALL = Path(os.environ.get('PY_VISION_INSTALL', REPO / 'install')).resolve()
RESULTS = BENCH / 'results'
PROFILE = INSTALL / 'py_vision' / 'share' / 'py_vision' / 'config' / 'fastdds_image_profile.xml'
FIRST_FRAME_MARK = 'BENCH first frame'
PROFILE_VARIABLES = ('FASTRTPS_DEFAULT_PROFILES_FILE', 'FASTDDS_DEFAULT_PROFILES_FILE')

SIZES = ((640, 480), (1280, 720), (1920, 1080))
HIGH_RATE = {(640, 480): 200.0, (1280, 720): 60.0, (1920, 1080): 60.0}
RELIABILITIES = ('best_effort', 'reliable')
NETNS_FPS = 15.0

# The two "hosts": network namespaces joined by a veth pair on a private /24.
NETNS = ('pyvbench_pub', 'pyvbench_sub')
VETH = ('pyvb_pub', 'pyvb_sub')
NETNS_ADDR = ('10.77.0.1', '10.77.0.2')
# Each namespace side also gets a private /dev/shm, so that shared memory cannot carry frames
# between the "hosts" even if Fast DDS tried.
PRIVATE_SHM = 'mount -t tmpfs -o size=2g pyvbench_shm /dev/shm && exec "$@"'

CLK_TCK = os.sysconf('SC_CLK_TCK')

# The tests' harness reserves ROS domain ids through lock files: sharing it means a bench run
# and a test run on one machine never share a domain.
sys.path.insert(0, str(REPO / 'py_vision' / 'test'))
from ros_harness import DomainId  # noqa: E402,I100 (found through the path set just above)


# ----------------------------------------------------------------------------- environment

def installed_env():
    """Return os.environ plus `source install/setup.bash`, without any Fast DDS profile."""
    setup = INSTALL / 'setup.bash'
    if not setup.is_file():
        sys.exit('%s is missing: build first with scripts/setup.sh' % setup)
    out = subprocess.run(['bash', '-c', 'source "$0" && env -0', str(setup)],
                         check=True, capture_output=True).stdout
    env = dict(item.split('=', 1) for item in out.decode().split('\0') if '=' in item)
    for name in PROFILE_VARIABLES + ('RMW_IMPLEMENTATION', 'ROS_STATIC_PEERS',
                                     'ROS_LOCALHOST_ONLY', 'ROS_AUTOMATIC_DISCOVERY_RANGE'):
        env.pop(name, None)
    env['PYTHONUNBUFFERED'] = '1'
    return env


# ----------------------------------------------------------------------------- processes

def cpu_ticks(pid):
    """Return utime + stime of a process in clock ticks, or None when it is gone."""
    try:
        with open('/proc/%d/stat' % pid) as stream:
            fields = stream.read().rsplit(')', 1)[1].split()
    except OSError:
        return None
    return int(fields[11]) + int(fields[12])


def machine_ticks():
    """Return (busy, total) jiffies of the whole machine."""
    with open('/proc/stat') as stream:
        values = [int(v) for v in stream.readline().split()[1:]]
    idle = values[3] + values[4]
    total = sum(values[:8])
    return total - idle, total


class Proc:
    """One helper process; output to a log file, results to a JSON file."""

    def __init__(self, name, cmd, env, workdir, netns=None):
        self.name = name
        self.out = str(workdir / ('%s.json' % name))
        self.log_path = workdir / ('%s.log' % name)
        cmd = [c.replace('{out}', self.out) for c in cmd]
        if netns is not None:
            cmd = ['ip', 'netns', 'exec', netns, 'unshare', '--mount', '--propagation',
                   'private', 'sh', '-c', PRIVATE_SHM, 'sh'] + cmd
        self.cmd = cmd
        self._log = open(self.log_path, 'w')
        # ip netns exec, unshare and sh all exec, so the pid is the Python process itself.
        self.proc = subprocess.Popen(cmd, env=env, cwd=str(workdir), stdout=self._log,
                                     stderr=subprocess.STDOUT, stdin=subprocess.DEVNULL,
                                     start_new_session=True)
        self.pid = self.proc.pid

    def output(self):
        return self.log_path.read_text(errors='replace')

    def stop(self, timeout=15.0):
        """SIGINT, wait; SIGKILL if it does not end. Return the exit status."""
        if self.proc.poll() is None:
            self.proc.send_signal(signal.SIGINT)
            try:
                self.proc.wait(timeout)
            except subprocess.TimeoutExpired:
                os.killpg(self.pid, signal.SIGKILL)
                self.proc.wait()
        self._log.close()
        return self.proc.returncode

    def results(self):
        try:
            with open(self.out) as stream:
                return json.load(stream)
        except (OSError, ValueError):
            return None


def wait_for(predicate, timeout, interval=0.05):
    """Poll predicate until it is truthy or timeout seconds pass; return its last value."""
    deadline = time.monotonic() + timeout
    while True:
        value = predicate()
        if value or time.monotonic() > deadline:
            return value
        time.sleep(interval)


# ----------------------------------------------------------------------------- network namespaces

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


def netns_unavailable():
    """Return why the two-host cases cannot run here, or None."""
    if os.geteuid() != 0:
        return 'needs root (ip netns, veth, mount)'
    if shutil.which('ip') is None or shutil.which('unshare') is None:
        return 'needs the ip and unshare commands'
    return None


def _ip(*args, check=True):
    return subprocess.run(('ip',) + args, check=check, capture_output=True, text=True)


def netns_teardown():
    for ns in NETNS:
        _ip('netns', 'del', ns, check=False)


def netns_setup():
    """Create the two namespaces and the veth pair; return an error string or None."""
    netns_teardown()
    try:
        for ns in NETNS:
            _ip('netns', 'add', ns)
        _ip('link', 'add', VETH[0], 'type', 'veth', 'peer', 'name', VETH[1])
        for ns, dev, addr in zip(NETNS, VETH, NETNS_ADDR):
            _ip('link', 'set', dev, 'netns', ns)
            _ip('-n', ns, 'addr', 'add', addr + '/24', 'dev', dev)
            _ip('-n', ns, 'link', 'set', 'lo', 'up')
            _ip('-n', ns, 'link', 'set', dev, 'up')
            # Discovery multicast goes out of the veth (there is no default route).
            _ip('-n', ns, 'route', 'add', '224.0.0.0/4', 'dev', dev)
    except subprocess.CalledProcessError as error:
        netns_teardown()
        return 'cannot create network namespaces: %s' % (error.stderr or error).strip()
    return None


def receive_buffer_errors():
    """UDP datagrams the subscriber's namespace dropped for a full socket buffer, so far."""
    out = subprocess.run(['ip', 'netns', 'exec', NETNS[1], 'cat', '/proc/net/snmp'],
                         capture_output=True, text=True).stdout
    rows = [line.split() for line in out.splitlines() if line.startswith('Udp:')]
    if len(rows) < 2:
        return None
    return int(dict(zip(rows[0][1:], rows[1][1:])).get('RcvbufErrors', 0))


def veth_tx_bytes():
    """Bytes the publisher's veth end has sent so far."""
    out = subprocess.run(['ip', 'netns', 'exec', NETNS[0], 'cat',
                          '/sys/class/net/%s/statistics/tx_bytes' % VETH[0]],
                         capture_output=True, text=True).stdout
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


def run_case(case, base_env, domain, duration, settle, python, log=print):
    """Run one case; return its measurements (or an 'error')."""
    workdir = Path(tempfile.mkdtemp(prefix='pyv_bench_'))
    env = case_env(base_env, case, domain, workdir)
    pub_cmd, sub_cmd = commands(case, python)
    pub_ns = NETNS[0] if case['netns'] else None
    sub_ns = NETNS[1] if case['netns'] else None
    result = dict(case)
    sub = Proc('subscriber', sub_cmd, env, workdir, sub_ns)
    pub = Proc('publisher', pub_cmd, publisher_env(env, case, workdir), workdir, pub_ns)
    try:
        if not wait_for(lambda: FIRST_FRAME_MARK in sub.output()
                        or sub.proc.poll() is not None or pub.proc.poll() is not None, 40):
            result['error'] = 'no frame reached the subscriber within 40 s'
        elif FIRST_FRAME_MARK not in sub.output():
            result['error'] = 'a process ended early'
        if 'error' not in result:
            time.sleep(settle)
            pids = (pub.pid, sub.pid)
            t0 = time.monotonic()
            cpu0 = [cpu_ticks(pid) for pid in pids]
            m0 = machine_ticks()
            tx0 = veth_tx_bytes() if case['netns'] else None
            drops0 = receive_buffer_errors() if case['netns'] else None
            time.sleep(duration)  # the measurement window itself
            t1 = time.monotonic()
            cpu1 = [cpu_ticks(pid) for pid in pids]
            m1 = machine_ticks()
            tx1 = veth_tx_bytes() if case['netns'] else None
            drops1 = receive_buffer_errors() if case['netns'] else None
            result.update(window=(t0, t1), cpu0=cpu0, cpu1=cpu1, machine=(m0, m1),
                          receive_buffer_drops=(drops1 - drops0) if drops0 is not None
                          and drops1 is not None else None,
                          veth_bytes=(tx1 - tx0) if tx0 is not None and tx1 is not None
                          else None)
    finally:
        pub_status = pub.stop()
        # Frames still in flight when the publisher stopped may arrive a little later.
        time.sleep(0.5)
        sub_status = sub.stop()
    published, received = pub.results(), sub.results()
    if 'error' not in result and (published is None or received is None):
        result['error'] = 'no results from the %s (exit %s)' % (
            'publisher' if published is None else 'subscriber',
            pub_status if published is None else sub_status)
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


def percentile(sorted_values, fraction):
    """Nearest-rank percentile of a sorted, non-empty list."""
    rank = min(len(sorted_values) - 1, max(0, int(round(fraction * len(sorted_values))) - 1))
    return sorted_values[rank]


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


def median(values):
    values = sorted(v for v in values if v is not None)
    if not values:
        return None
    mid = len(values) // 2
    return values[mid] if len(values) % 2 else (values[mid - 1] + values[mid]) / 2


def combine(runs):
    """Median of each number over the repeats of one case; latencies pooled."""
    ok = [r for r in runs if 'error' not in r]
    if not ok:
        return dict(runs[-1], repeats=len(runs))
    out = dict(ok[0])
    for key in NUMERIC:
        value = median([r.get(key) for r in ok])
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
    base_env = installed_env()
    problems = check_profile(base_env)
    if problems:
        sys.exit('Fast DDS rejects %s:\n%s' % (PROFILE, '\n'.join(problems)))
    python = sys.executable
    out_dir = Path(args.out)
    out_dir.mkdir(parents=True, exist_ok=True)

    skipped = {}
    netns_reason = netns_unavailable() if any(c['netns'] for c in cases) else None
    domain = DomainId()
    results = []
    netns_ready = False
    previous = {sig: signal.getsignal(sig) for sig in (signal.SIGINT, signal.SIGTERM)}

    def interrupted(signum, frame):
        raise KeyboardInterrupt

    signal.signal(signal.SIGTERM, interrupted)
    started = time.monotonic()
    try:
        for number, case in enumerate(cases, 1):
            if case['netns']:
                if netns_reason is None and not netns_ready:
                    netns_reason = netns_setup()
                    netns_ready = netns_reason is None
                if netns_reason is not None:
                    skipped[case['name']] = netns_reason
                    continue
            runs = []
            for _ in range(max(1, args.repeat)):
                runs.append(run_case(case, base_env, domain.value, duration, 1.0, python))
            result = combine(runs)
            results.append(result)
            print('[%2d/%d %4.0fs] %-42s delivered %6s%%  p50 %6s ms  pub CPU %5s%%' % (
                number, len(cases), time.monotonic() - started, case['name'],
                fmt(result.get('delivered_pct'), 2), fmt(result.get('p50_ms'), 2),
                fmt(result.get('pub_cpu_pct'))), flush=True)
    except KeyboardInterrupt:
        print('interrupted: reporting the cases done so far', file=sys.stderr)
    finally:
        if netns_ready:
            netns_teardown()
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
