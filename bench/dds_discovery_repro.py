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
How often a plain rclpy node, started while others start and stop, cannot be reached (issue 34).

  . scripts/board_env.sh && python bench/dds_discovery_repro.py [--starts 200] [--lanes 4]
      [--within 10] [VARIANT ...]              (Humble, Fast DDS 2.6.0: the boards' versions)
  .venv/bin/python bench/dds_discovery_repro.py ...          (Jazzy, Fast DDS 2.14, to compare)

No py_vision node runs: each start is this script's own `--node` mode, a bare rclpy node (its
parameter services, a publisher and a subscription of a small message at 10 Hz) that stops on
SIGINT or SIGTERM. Lanes run at the same time, as in the stop test
(py_vision/test/nodes/test_stop_after_parameters.py): each lane has a long-lived peer (an rclpy
context of this process) and, again and again, starts a node, waits until its peer both sees the
node's name in the graph and gets an answer from its get_parameters service, then stops it with
SIGINT or SIGTERM (SIGKILL after 10 s). A start is reached when both happen within --within
seconds (10). Unreached starts are listed with what the peer's graph held and the node's log
(what it saw of the graph).

Caught ports: every node prints Fast DDS' warnings, one for each failed read of its
shared-memory ports ('Error receiving data'). Fast DDS 2.6.0 to 2.6.5 fail on a caught port
thousands of times a second, and the port stays dead (docs/boards.md); with the fix (2.6.6, or
2.6.0 with commit df904f30) a read fails once for each message whose sender has gone, which it
takes off the port (a port holds 512, Fast DDS' default), and the port goes on working. So a
node with more failed reads than CAUGHT_READS had a caught port. To run on another build of
Humble (one with the fix), source its setup script after the boards' environment; the JSON
names the libfastrtps file that ran:
  . scripts/board_env.sh && . <that tree>/install/setup.bash && python bench/dds_discovery_repro.py

Variants (all with discovery on this host, as the tests run, unless said):
  default      Fast DDS' defaults in nodes and peers
  profile      the nodes on py_vision's profile as its nodes tailor it (py_vision.dds), a
               subscriber's 0.5 MB segment; the peers on defaults, as in the tests
  no-shm       the profile with its shared-memory transport removed (UDP only), nodes and peers
  daemon       as default, with the ros2 daemon running on the domain
  subnet       as default, discovery on the network (no ROS_LOCALHOST_ONLY / discovery range)
  fixed        the nodes on the profile py_vision gives a node that receives no images
               (py_vision.dds, as usbcam_publisher): on Humble it listens on UDP alone, so
               receives nothing through shared memory (it still sends through it)
  split        the nodes on the profile py_vision gives a node that receives images, the
               small topic standing for them: on Humble its reader of that topic listens on
               shared memory, everything else on UDP
Prints a Markdown table, writes bench/results/dds_discovery.json (one entry per variant run).
"""

import argparse
import fcntl
import json
import os
from pathlib import Path
import random
import signal
import subprocess
import sys
import tempfile
import threading
import time

SCRIPT = Path(__file__).resolve()
TOPIC = 'repro_chatter'  # every lane's nodes publish and subscribe to it
SPLIT = 'REPRO_SPLIT'  # set for a node of the split variant
BENCH = SCRIPT.parent
RESULTS = BENCH / 'results'
VARIANTS = ('default', 'profile', 'no-shm', 'daemon', 'subnet', 'fixed', 'split')
# Ad-hoc domain ids of this investigation, taken through the tests' own lock files so that a
# test run never shares one with it.
DOMAINS = range(170, 200)
LOCK_DIR = Path(tempfile.gettempdir()) / 'py_vision_test_domains'
STOP_WITHIN_S = 10.0
RESEND_AFTER_S = 2.0
POLL_S = 0.05
# Fast DDS warnings every node prints as it stops, left out of an unreached node's log (the
# first one is also what a stuck shared-memory listener repeats: counted apart, STUCK).
SHUTDOWN_NOISE = ('Error receiving data', 'remove_local_writer', 'Automatically unmatching',
                  'NO readers are listening')
STUCK = 'Error receiving data: No such file or directory'
CAUGHT_READS = 1024  # twice what a port holds; a caught 2.6.0 port fails more often each second
LOAD_EVERY_S = 5.0


def fast_dds_warnings():
    """Make Fast DDS print its warnings (it prints only errors unless told; rcl never tells it)."""
    import ctypes
    try:
        with open('/proc/self/maps') as maps:
            lib = next(line.split()[-1] for line in maps if 'libfastrtps.so' in line)
        # eprosima::fastdds::dds::Log::SetVerbosity(Log::Kind), a static function; Warning = 1.
        getattr(ctypes.CDLL(lib), '_ZN8eprosima7fastdds3dds3Log12SetVerbosityENS2_4KindE')(1)
    except (OSError, StopIteration, AttributeError) as error:
        print('Fast DDS warnings stay off: %s' % error, flush=True)


def run_node(name):
    """Be the node under test: parameters, a publisher, a subscription; stop on a signal."""
    if os.environ.get(SPLIT):
        sys.path.insert(0, str(BENCH))
        import bench_common  # noqa: F401 (puts the installed py_vision on sys.path)
        from py_vision import dds
        # As a py_vision node that publishes images (its last messages linger, dds.linger_s).
        dds.use_packaged_profile(dds.OWN_SIZE, [], name, image_topics=['/' + TOPIC])
        linger = dds.linger_s()
    else:
        linger = 0.0
    import rclpy
    from std_msgs.msg import String

    rclpy.init()
    fast_dds_warnings()
    stop = threading.Event()
    # After rclpy.init(), replacing rclpy's handlers: the loop below polls the flag.
    for sig in (signal.SIGINT, signal.SIGTERM):
        signal.signal(sig, lambda *_: stop.set())
    node = rclpy.create_node(name)
    publisher = node.create_publisher(String, TOPIC, 10)
    heard = set()

    def on_message(msg):
        if msg.data != name and msg.data not in heard:
            heard.add(msg.data)
            print('%.2f heard %s' % (time.monotonic(), msg.data), flush=True)
    node.create_subscription(String, TOPIC, on_message, 10)
    seen = {'names': None}

    def tick():
        publisher.publish(String(data=name))
        names = sorted(node.get_node_names())
        if names != seen['names']:
            seen['names'] = names
            print('%.2f sees %s' % (time.monotonic(), ' '.join(names)), flush=True)
    node.create_timer(0.1, tick)
    print('%.2f up' % time.monotonic(), flush=True)
    while not stop.is_set():
        try:
            rclpy.spin_once(node, timeout_sec=0.1)
        except Exception as error:  # as py_vision's nodes do: say it, keep going
            # Humble's rclpy raises here when a reply finds the client's reader not yet
            # matched ('client will not receive response'); the client asks again.
            print('%.2f callback failed: %s' % (time.monotonic(), error), flush=True)
    time.sleep(linger)
    node.destroy_node()
    rclpy.shutdown()
    print('%.2f stopped' % time.monotonic(), flush=True)


def new_peer(domain_id, name):
    """Return a long-lived in-process peer on domain_id: the tests' ros_harness.RosPeer."""
    sys.path.insert(0, str(BENCH))
    import bench_common  # noqa: F401 (puts the tests' harness on sys.path)
    import ros_harness
    return ros_harness.RosPeer(domain_id, name)


def reach(peer, clients, name, within):
    """Return (seconds until peer saw the name or None, until the answer or None, graph)."""
    from rcl_interfaces.srv import GetParameters
    client = peer.node.create_client(GetParameters, '/%s/get_parameters' % name)
    # Kept until the peer closes: destroying endpoints while messages arrive crashed Fast
    # DDS 2.6.0 (TopicPayloadPool::shrink) in this process three times in 1000 starts.
    clients.append(client)
    start = time.monotonic()
    seen = answered = future = None
    sent = 0.0
    try:
        while time.monotonic() - start < within and (seen is None or answered is None):
            now = time.monotonic()
            if seen is None and name in peer.node.get_node_names():
                seen = now - start
            if answered is None:
                if future is not None and future.done():
                    answered = now - start
                elif client.service_is_ready() and (future is None
                                                    or now - sent > RESEND_AFTER_S):
                    if future is not None:
                        client.remove_pending_request(future)
                    future = client.call_async(GetParameters.Request(names=['use_sim_time']))
                    sent = now
            time.sleep(POLL_S)
        graph = None
        if seen is None or answered is None:
            service = '/%s/get_parameters' % name
            graph = {
                'service_ready': client.service_is_ready(),
                'request_readers': sorted(i.node_name for i in
                                          peer.node.get_subscriptions_info_by_topic(
                                              'rq%sRequest' % service, no_mangle=True)),
                'reply_writers': sorted(i.node_name for i in
                                        peer.node.get_publishers_info_by_topic(
                                            'rr%sReply' % service, no_mangle=True)),
                'nodes': sorted(peer.node.get_node_names()),
            }
        return seen, answered, graph
    finally:
        if future is not None and not future.done():
            client.remove_pending_request(future)


def take_domain():
    """Return (domain id, lock handle) of a free id in DOMAINS."""
    LOCK_DIR.mkdir(exist_ok=True)
    for candidate in DOMAINS:
        handle = open(LOCK_DIR / ('%d.lock' % candidate), 'w')
        try:
            fcntl.flock(handle, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError:
            handle.close()
            continue
        return candidate, handle
    raise RuntimeError('no free ROS_DOMAIN_ID in %d-%d' % (DOMAINS[0], DOMAINS[-1]))


def on_humble():
    """Return True on Humble's rclpy (3.x), as the tests tell it (ros_harness.ON_HUMBLE)."""
    sys.path.insert(0, str(BENCH))
    import bench_common  # noqa: F401 (puts the tests' harness on sys.path)
    import ros_harness
    return ros_harness.ON_HUMBLE


def profile_file(workdir, variant):
    """Write and return the profile file the nodes of a variant get (None: Fast DDS defaults)."""
    sys.path.insert(0, str(BENCH))
    import bench_common  # noqa: F401 (puts the installed py_vision on sys.path)
    from py_vision import dds
    if variant == 'fixed':
        env = {'ROS_LOCALHOST_ONLY': '1'} if on_humble() else {
            'ROS_AUTOMATIC_DISCOVERY_RANGE': 'LOCALHOST'}
        return dds.use_packaged_profile(dds.NO_IMAGES, [], 'repro', environ=env, image_topics=[])
    path = dds.tailor(dds.packaged_profile(), dds.SMALL_SEGMENT, localhost=True)
    if variant == 'no-shm':
        text = Path(path).read_text()
        start = text.index('<transport_descriptor>')
        end = text.index('</transport_descriptor>', start) + len('</transport_descriptor>')
        text = text[:start] + text[end:]
        text = text.replace('<transport_id>py_vision_shm</transport_id>', '', 1)
        path = str(Path(workdir) / 'no_shm.xml')
        Path(path).write_text(text)
    return path


def variant_env(variant, domain_id, workdir):
    """Return (the nodes' environment, the peers' environment) of a variant."""
    env = dict(os.environ)
    for name in ('FASTRTPS_DEFAULT_PROFILES_FILE', 'FASTDDS_DEFAULT_PROFILES_FILE',
                 'RMW_IMPLEMENTATION', 'ROS_LOCALHOST_ONLY', 'ROS_AUTOMATIC_DISCOVERY_RANGE',
                 'ROS_STATIC_PEERS'):
        env.pop(name, None)
    env.update(ROS_DOMAIN_ID=str(domain_id), PYTHONUNBUFFERED='1')
    if variant != 'subnet':
        if on_humble():
            env['ROS_LOCALHOST_ONLY'] = '1'
        else:
            env['ROS_AUTOMATIC_DISCOVERY_RANGE'] = 'LOCALHOST'
    nodes, peers = dict(env), dict(env)
    if variant in ('profile', 'no-shm', 'fixed'):
        nodes['FASTRTPS_DEFAULT_PROFILES_FILE'] = profile_file(workdir, variant)
    if variant == 'split':  # each node its own profile (its own UDP port for its endpoints)
        nodes[SPLIT] = '1'
    if variant == 'no-shm':
        peers['FASTRTPS_DEFAULT_PROFILES_FILE'] = nodes['FASTRTPS_DEFAULT_PROFILES_FILE']
    return nodes, peers


def fast_dds_segments():
    """Return the number of Fast DDS files in /dev/shm."""
    try:
        return sum(1 for entry in os.listdir('/dev/shm')
                   if entry.startswith(('fastrtps', 'sem.fastrtps')))
    except OSError:
        return None


def udp_ports(pid):
    """Return the local UDP ports a process has sockets on (py_vision.dds reads them)."""
    sys.path.insert(0, str(BENCH))
    import bench_common  # noqa: F401 (puts the installed py_vision on sys.path)
    from py_vision import dds
    return sorted(dds.udp_ports(pid) or ())


def shm_ports(pid=None):
    """
    Return the Fast DDS shared-memory ports in /dev/shm, or those a process maps.

    A port a process maps after it was removed from /dev/shm (another process reset it) is
    given as '<port> deleted': what the process writes there nobody reads.
    """
    try:
        if pid is None:
            names = os.listdir('/dev/shm')
        else:
            with open('/proc/%d/maps' % pid) as maps:
                names = {line.split('/dev/shm/', 1)[1].strip()
                         for line in maps if '/dev/shm/fastrtps_port' in line}
    except OSError:
        return []
    ports = set()
    for name in names:
        number, _, deleted = name[len('fastrtps_port'):].partition(' ')
        if name.startswith('fastrtps_port') and number.isdigit():
            ports.add('%s deleted' % number if deleted else number)
    return sorted(ports, key=lambda port: int(port.split()[0]))


def port_caught(log):
    """
    Return (failed reads, caught) from a node's log (the module's docstring says what caught is).

    Counted in the whole text: Fast DDS writes a line in pieces, and a print of the node's may
    come between them.
    """
    failures = log.count(STUCK)
    return failures, failures > CAUGHT_READS


def run_lane(lane, starts, within, nodes_env, domain_id, rng, results, workdir, peers):
    """
    Start, reach and stop `starts` nodes one after the other; append a record for each.

    The lane's peer is appended to peers, for the caller to close once the results are saved:
    Fast DDS 2.6.0 crashed now and then as a peer with many clients was destroyed.
    """
    peer = new_peer(domain_id, 'repro_peer_%d' % lane)
    peers.append(peer)
    clients = []  # the peer's clients, none destroyed before the peer (see reach)
    for number in range(starts):
        name = 'repro_%d_%d' % (lane, number)
        log_path = Path(workdir) / ('%s.log' % name)
        with open(log_path, 'w') as log:
            proc = subprocess.Popen(
                [sys.executable, str(SCRIPT), '--node', name], env=nodes_env, stdout=log,
                stderr=subprocess.STDOUT, stdin=subprocess.DEVNULL, start_new_session=True)
        try:
            seen, answered, graph = reach(peer, clients, name, within)
            if graph is not None:
                graph.update(node_udp=udp_ports(proc.pid), node_shm=shm_ports(proc.pid),
                             peers_udp=udp_ports(os.getpid()),
                             peers_shm=shm_ports(os.getpid()), dev_shm=shm_ports())
        finally:
            sig = rng.choice([signal.SIGINT, signal.SIGTERM])
            proc.send_signal(sig)
            try:
                status = proc.wait(STOP_WITHIN_S)
            except subprocess.TimeoutExpired:
                os.killpg(proc.pid, signal.SIGKILL)
                status = proc.wait()
        text = log_path.read_text(errors='replace')
        lines = text.splitlines()
        failures, caught = port_caught(text)
        record = {'lane': lane, 'number': number, 'name_s': seen, 'answer_s': answered,
                  'reached': seen is not None and answered is not None, 'status': status,
                  # Other lanes' nodes whose messages it received (through shared memory in
                  # `split`), how often Fast DDS' shared-memory listener failed (docs/boards.md:
                  # 2.6.0 repeats it tens of thousands of times once caught), and whether its
                  # port was caught.
                  'heard': sum(1 for line in lines if ' heard ' in line),
                  'shm_read_failures': failures, 'shm_caught': caught}
        if not record['reached'] or failures or status != 0:
            record['graph'] = graph
            record['log'] = [line for line in lines
                             if not any(noise in line for noise in SHUTDOWN_NOISE)][-40:]
            if not record['reached']:
                print('  unreached %s: %s' % (name, json.dumps(graph)), flush=True)
            elif caught:
                print('  %s reached, its shared-memory port caught (%d failed reads)' % (
                    name, failures), flush=True)
            elif failures:
                print('  %s reached, %d failed reads, its shared-memory port still read' % (
                    name, failures), flush=True)
            else:
                print('  %s reached, exit status %s' % (name, status), flush=True)
        else:
            log_path.unlink()
        results.append(record)
        if len(results) % 50 == 0:
            print('  %d starts, %d reached' % (
                len(results), sum(1 for r in results if r['reached'])), flush=True)


def sample_load(loads, done):
    """Append the 1-minute load average to loads every LOAD_EVERY_S until done is set."""
    while True:
        loads.append(round(os.getloadavg()[0], 2))
        if done.wait(LOAD_EVERY_S):
            return


def measure(variant, total, lanes, within, peers):
    """Run one variant: `total` starts over `lanes` lanes; return its summary dict."""
    domain_id, lock = take_domain()
    workdir = tempfile.mkdtemp(prefix='dds_repro_')
    daemon = None
    try:
        nodes_env, peers_env = variant_env(variant, domain_id, workdir)
        for name in ('ROS_LOCALHOST_ONLY', 'ROS_AUTOMATIC_DISCOVERY_RANGE',
                     'FASTRTPS_DEFAULT_PROFILES_FILE'):
            os.environ.pop(name, None)
            if name in peers_env:
                os.environ[name] = peers_env[name]
        if variant == 'daemon':
            subprocess.run(['ros2', 'daemon', 'stop'], env=nodes_env, capture_output=True)
            subprocess.run(['ros2', 'daemon', 'start'], env=nodes_env, capture_output=True,
                           check=True, timeout=60)
            daemon = nodes_env
        before = fast_dds_segments()
        results = []
        started = time.monotonic()
        loads, done = [], threading.Event()
        sampler = threading.Thread(target=sample_load, args=(loads, done), daemon=True)
        sampler.start()
        per_lane = [total // lanes + (1 if lane < total % lanes else 0) for lane in range(lanes)]
        threads = [threading.Thread(target=run_lane, args=(
            lane, per_lane[lane], within, nodes_env, domain_id,
            random.Random('%s %d' % (variant, lane)), results, workdir, peers))
            for lane in range(lanes)]
        for thread in threads:
            thread.start()
        for thread in threads:
            thread.join()
        done.set()
        sampler.join()
        loads.sort()  # at least one sample: the first is taken at once
        reached = [r for r in results if r['reached']]
        answers = sorted(r['answer_s'] for r in reached)
        return {
            'variant': variant, 'starts': len(results), 'reached': len(reached),
            'unreached': [r for r in results if not r['reached']],
            'answer_median_s': round(answers[len(answers) // 2], 2) if answers else None,
            'answer_max_s': round(answers[-1], 2) if answers else None,
            'not_stopped_cleanly': sum(1 for r in results if r['status'] != 0),
            'shm_read_failed': sum(1 for r in results if r['shm_read_failures']),
            'shm_caught': sum(1 for r in results if r['shm_caught']),
            'heard_none': sum(1 for r in results if not r['heard']),
            'shm_files_before': before, 'shm_files_after': fast_dds_segments(),
            'seconds': round(time.monotonic() - started, 1), 'lanes': lanes, 'within_s': within,
            'domain_id': domain_id,
            # the 1-minute load average, sampled every LOAD_EVERY_S: lowest, median, highest
            'load': [loads[0], loads[len(loads) // 2], loads[-1]],
        }
    finally:
        if daemon is not None:
            subprocess.run(['ros2', 'daemon', 'stop'], env=daemon, capture_output=True)
        lock.close()


def versions():
    """Return the ROS distribution's rclpy version and the Fast DDS library in use."""
    import rclpy
    found = {'python': '%d.%d' % sys.version_info[:2], 'humble': on_humble()}
    try:
        with open('/proc/self/maps') as maps:
            libs = {line.split()[-1] for line in maps if 'libfastrtps.so' in line}
        found['fastdds'] = sorted(os.path.realpath(lib).rsplit('.so.', 1)[-1] for lib in libs)
        found['fastdds_library'] = sorted(os.path.realpath(lib) for lib in libs)
    except OSError:
        pass
    found['rclpy'] = os.path.dirname(rclpy.__file__)
    return found


def save(run):
    """Append one variant's run to bench/results/dds_discovery.json."""
    RESULTS.mkdir(exist_ok=True)
    out = RESULTS / 'dds_discovery.json'
    try:
        previous = json.loads(out.read_text())
    except (OSError, ValueError):
        previous = []
    out.write_text(json.dumps(previous + [run], indent=1))


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split('\n\n')[0])
    parser.add_argument('variants', nargs='*', default=['default'],
                        help='any of %s (default)' % ', '.join(VARIANTS))
    parser.add_argument('--starts', type=int, default=200, help='node starts per variant')
    parser.add_argument('--lanes', type=int, default=4, help='lanes at the same time (4)')
    parser.add_argument('--within', type=float, default=10.0, help='seconds to reach a node')
    parser.add_argument('--node', help=argparse.SUPPRESS)
    args, _ = parser.parse_known_args(argv)
    if args.node:
        run_node(args.node)
        return 0
    unknown = [v for v in args.variants if v not in VARIANTS]
    if unknown:
        parser.error('unknown variant(s) %s: choose from %s' % (
            ', '.join(unknown), ', '.join(VARIANTS)))
    runs = []
    for variant in args.variants:
        print('%s: %d starts in %d lanes' % (variant, args.starts, args.lanes), flush=True)
        peers = []
        run = measure(variant, args.starts, args.lanes, args.within, peers)
        found = versions()  # Fast DDS is loaded once a context has been initialised
        run.update(versions=found, when=time.strftime('%Y-%m-%dT%H:%M:%SZ', time.gmtime()))
        save(run)  # each variant as soon as it is measured, before its peers are closed
        runs.append(run)
        for peer in peers:
            peer.close()
    print()
    print('| variant | Fast DDS | reached within %gs | ports caught (nodes with failed reads) '
          '| median / max answer (s) | load | time (s) |' % args.within)
    print('|---|---|---|---|---|---|---|')
    for run in runs:
        print('| %s | %s | %d of %d | %d (%d) | %s / %s | %.1f to %.1f | %.0f |' % (
            run['variant'], ','.join(found.get('fastdds', [])), run['reached'], run['starts'],
            run['shm_caught'], run['shm_read_failed'], run['answer_median_s'],
            run['answer_max_s'], run['load'][0], run['load'][2], run['seconds']))
    return 0


if __name__ == '__main__':
    sys.exit(main())
