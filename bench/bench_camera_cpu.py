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
The camera node's CPU against the C++ drivers', side by side on one emulated USB camera.

  .venv/bin/python bench/bench_camera_cpu.py [--modes 640x480@30,1280x720@10] [--rounds 3]
      [--window 20] [--cases ...] [--before INSTALL_BASE] [--tag TAG]
  . scripts/board_env.sh && python bench/bench_camera_cpu.py      (the boards' versions)

The emulated 1080p USB 2.0 webcam of the tests (docs/emulated_cameras.md) streams YUYV at each
mode (640x480 at 30 fps, 1280x720 at 10: what USB 2.0 carries of YUYV), and one driver at a
time publishes it to one best-effort subscriber, a bare rclpy node in its own process
(bench/bare_image_subscriber.py). The drivers, each in its own process on a ROS domain of its
own:

- `py_vision bgr8` and `py_vision native`: the installed usbcam_publisher, output_encoding bgr8
  and native (the camera's YUYV as yuv422_yuy2, which the camera writes into the published
  messages themselves: V4L2 USERPTR), with its own Fast DDS profile, as users run it;
- `v4l2_camera` 0.4.0 and `usb_cam` 0.4.1, the C++ drivers the boards' meta-ros has, from the
  boards' Humble (../shared/humble, set up by scripts/setup.sh --board), at their defaults for
  a YUYV camera (both publish rgb8, converted from YUYV), first with Fast DDS' defaults, then
  `(profile)`: with the profile py_vision's node gets, its shared memory segment made large
  enough for them to deliver every frame (six frames: with py_vision's three, they delivered
  7 to 8 frames a second of 10 at 1280x720), which is the fair comparison and the one the
  ratios use.

The C++ drivers exist only for Humble: in the main environment (Jazzy) py_vision and its
subscriber run on Jazzy and the peers and theirs on the boards' Humble.

Measured: the CPU of the driver's process (utime + stime from /proc) over a window after the
frames have settled, the frames the camera filled for it in that window (captured) and those
its subscriber received (delivered): both must be the camera's rate for a ratio to mean
anything, and a row that falls short says so. The camera is plugged in anew before each case
(a driver inherits no format from the one before). The cases alternate within each round
(each round in another order); the table gives medians over the rounds, and the ratios are
py_vision's median over each peer's (profile), and in brackets the median of each round's
own ratio. With --before, another build of py_vision (the colcon install of main's code, say,
built with that environment's colcon) runs in the same rounds, and "x before" is this build
against it. With --floor, the least a Python driver does per frame (bench/camera_floor.py: read,
convert into the serialized message, publish it and the CameraInfo) runs too, as bgr8 and
native: what usbcam_publisher costs above it is the node's own. Prints a Markdown table and
writes bench/results/camera_cpu-py<version>[-TAG].json. The C++ drivers need Debian's
libopencv-core406 libopencv-imgproc406 libopencv-imgcodecs406 libavcodec59 libavutil57
libswscale6 libconsole-bridge1.0 libyaml-cpp0.7 (the run says which are missing).
"""

import argparse
import os
from pathlib import Path
import platform
import shutil
import statistics
import subprocess
import sys
import tempfile
import time

from bench_common import (BENCH, CLK_TCK, cpu_ticks, FIRST_FRAME_MARK, local_node_env,
                          read_results, REPO, save_results, start_helper)
from emulated_camera import EmulatedCamera
import ros_harness

MODES = '640x480@30,1280x720@10'
CASES = ('py_vision bgr8', 'py_vision native', 'v4l2_camera', 'v4l2_camera (profile)',
         'usb_cam', 'usb_cam (profile)')
# With --before: the same two cases run from another build of py_vision (its colcon install).
BEFORE = ('py_vision bgr8 (before)', 'py_vision native (before)')
# With --floor: the least a Python driver does per frame (bench/camera_floor.py).
FLOOR = ('python floor bgr8', 'python floor native')
PEERS = ('v4l2_camera (profile)', 'usb_cam (profile)')
CAMERA_NODE = 47
START_S = 60.0
SETTLE_S = 3.0
# The peers' segment, in frames: with py_vision's three, at 1280x720 they delivered 7 to 8
# of 10 fps (py_vision's node all 10); with six, all. Their CPU was the same either way.
PEER_SEGMENT_FRAMES = 6
# A delivered rate this far below the camera's is a case that did not keep up.
DELIVERED_MIN = 0.97
PEER_LIBRARIES = ('libopencv-core406 libopencv-imgproc406 libopencv-imgcodecs406 libavcodec59 '
                  'libavutil57 libswscale6 libconsole-bridge1.0 libyaml-cpp0.7')


def parse_modes(text):
    """Return [(width, height, fps)] from '640x480@30,1280x720@10'."""
    modes = []
    for item in text.split(','):
        size, fps = item.split('@')
        width, height = size.split('x')
        modes.append((int(width), int(height), float(fps)))
    return modes


def humble_env():
    """
    Return the environment of the boards' Humble (.venv-board), where the C++ drivers are.

    This process' own when it runs there; else what scripts/board_env.sh sets.
    """
    if os.environ.get('ROS_DISTRO') == 'humble':
        return dict(os.environ)
    script = REPO / 'scripts' / 'board_env.sh'
    out = subprocess.run(['bash', '-c', '. "$0" >/dev/null && env -0', str(script)],
                         capture_output=True)
    if out.returncode != 0:
        raise SystemExit("the boards' Humble is not set up (scripts/setup.sh --board): %s"
                         % out.stderr.decode(errors='replace').strip())
    return dict(item.split('=', 1) for item in out.stdout.decode().split('\0') if '=' in item)


def peer_executables(env):
    """Return {'v4l2_camera': path, 'usb_cam': path} in env's Humble; exit if unusable."""
    wanted = {'v4l2_camera': 'lib/v4l2_camera/v4l2_camera_node',
              'usb_cam': 'lib/usb_cam/usb_cam_node_exe'}
    found = {}
    for prefix in env.get('AMENT_PREFIX_PATH', '').split(os.pathsep):
        for name, tail in wanted.items():
            path = Path(prefix) / tail
            if name not in found and path.is_file():
                found[name] = str(path)
    missing = sorted(set(wanted) - set(found))
    if missing:
        raise SystemExit('%s not found in the Humble environment (scripts/setup.sh --board)'
                         % ', '.join(missing))
    for path in found.values():
        ldd = subprocess.run(['ldd', path], env=env, capture_output=True, text=True)
        absent = [line.split()[0] for line in ldd.stdout.splitlines() if 'not found' in line]
        if absent:
            raise SystemExit("%s cannot run: %s not found; install Debian's %s" % (
                path, ', '.join(absent), PEER_LIBRARIES))
    return found


def profiles_for(width, height):
    """
    Return the profiles (files) of a peer and of the subscribers, at this size.

    The peer's is the one py_vision's camera node gets at this size on the peers' Fast DDS
    (2.6: it receives through UDP, sends through shared memory, dds.py), with a segment of
    PEER_SEGMENT_FRAMES frames; the subscribers' the same without UDP (they read their images
    from the publisher's shared memory).
    """
    from py_vision import dds
    segment = PEER_SEGMENT_FRAMES * width * height * dds.BYTES_PER_PIXEL
    packaged = dds.packaged_profile()
    return {'peer': dds.tailor(packaged, segment, localhost=True, udp_receive=True),
            'subscriber': dds.tailor(packaged, segment, localhost=True)}


def installed_env_of(base):
    """Return the environment of the py_vision installed in the colcon install base `base`."""
    setup = Path(base) / 'setup.bash'
    if not (Path(base) / 'py_vision' / 'lib' / 'py_vision' / 'usbcam_publisher').is_file():
        raise SystemExit('%s holds no installed py_vision (a colcon install base)' % base)
    out = subprocess.run(['bash', '-c', 'source "$0" && env -0', str(setup)],
                         capture_output=True, check=True).stdout
    env = dict(item.split('=', 1) for item in out.decode().split('\0') if '=' in item)
    env.update(ROS_AUTOMATIC_DISCOVERY_RANGE='LOCALHOST', PYTHONUNBUFFERED='1',
               RCUTILS_COLORIZED_OUTPUT='0', PY_VISION_INSTALL=str(base))
    env.pop('ROS_LOCALHOST_ONLY', None)
    return env


def driver_command(case, device, width, height, fps, peers):
    """Return the driver's command line for a case."""
    if case in FLOOR:
        return [sys.executable, str(BENCH / 'camera_floor.py'), device, str(width), str(height),
                repr(fps), case.split()[2]]
    if case.startswith('py_vision'):
        executables = ros_harness.EXECUTABLES
        if case in BEFORE:
            executables = Path(peers['before']) / 'py_vision' / 'lib' / 'py_vision'
        return [str(executables / 'usbcam_publisher')] + ros_harness.ros_args({
            'video_device': device, 'image_width': width, 'image_height': height,
            'framerate': fps, 'pixel_format': 'yuyv',
            'output_encoding': case.split()[1]})
    if case.startswith('v4l2_camera'):
        return [peers['v4l2_camera'], '--ros-args', '-p', 'video_device:=%s' % device,
                '-p', 'image_size:=[%d,%d]' % (width, height),
                '-p', 'time_per_frame:=[1,%d]' % round(fps), '-p', 'pixel_format:=YUYV']
    return [peers['usb_cam'], '--ros-args', '-p', 'video_device:=%s' % device,
            '-p', 'image_width:=%d' % width, '-p', 'image_height:=%d' % height,
            '-p', 'framerate:=%r' % fps, '-p', 'pixel_format:=yuyv', '-p', 'io_method:=mmap']


def run_case(case, mode, camera, envs, peers, window, workdir):
    """Run one driver and its subscriber; return the driver's CPU and the delivered rate."""
    width, height, fps = mode
    ours = case.startswith(('py_vision', 'python floor'))
    # Plugged in anew: the format and rate the last driver left on the device go (a driver
    # that sets the rate before the size, as v4l2_camera does, would keep the last rate).
    camera.replug()
    domain = ros_harness.DomainId()
    which = 'before' if case in BEFORE else 'ours' if ours else 'humble'
    env = camera.env(dict(envs[which], ROS_DOMAIN_ID=str(domain.value)))
    for name in ('FASTRTPS_DEFAULT_PROFILES_FILE', 'FASTDDS_DEFAULT_PROFILES_FILE',
                 'RMW_IMPLEMENTATION'):
        env.pop(name, None)
    sub_env = dict(env)
    if ours or case.endswith('(profile)'):
        sub_env['FASTRTPS_DEFAULT_PROFILES_FILE'] = envs['profiles']['subscriber']
    if case.endswith('(profile)'):
        env['FASTRTPS_DEFAULT_PROFILES_FILE'] = envs['profiles']['peer']
    # py_vision's node tailors its own, as it always does.
    topic = 'usb_camera/image' if ours else 'image_raw'
    python = os.path.join(sub_env['VIRTUAL_ENV'], 'bin', 'python') if not ours and (
        sub_env.get('VIRTUAL_ENV')) else sys.executable
    cmd = driver_command(case, camera.device, width, height, fps, peers)
    subscriber = start_helper('subscriber', [
        python, str(BENCH / 'bare_image_subscriber.py'), '{out}', 'best_effort',
        '--ros-args', '-r', 'usb_camera/image:=%s' % topic], sub_env, workdir)
    driver = ros_harness.NodeProcess(cmd[0], cmd[1:], env, name='driver', log_dir=workdir)
    processes = [driver, subscriber]
    try:
        subscriber.wait_for_output(FIRST_FRAME_MARK, START_S)
        time.sleep(SETTLE_S)
        start, before, served = time.monotonic(), cpu_ticks(driver.pid), camera.frames_served
        time.sleep(window)
        end, after, served = time.monotonic(), cpu_ticks(driver.pid), (
            camera.frames_served - served)
        statuses = [proc.end() for proc in (driver, subscriber)]
    finally:
        for proc in processes:
            proc.kill()
        domain.release()
    if before is None or after is None or not all(statuses):
        raise SystemExit('%s did not run through its window:\n%s' % (case, driver.tail()))
    results = read_results(subscriber) or {}
    received = [event for event in results.get('received', ()) if start <= event[0] < end]
    seconds = end - start
    cpu_s = (after - before) / CLK_TCK
    return {'case': case, 'mode': '%dx%d@%g' % mode, 'seconds': round(seconds, 2),
            'delivered_fps': round(len(received) / seconds, 2),
            'captured_fps': round(served / seconds, 2),
            'cpu_percent': round(100.0 * cpu_s / seconds, 2),
            'cpu_ms_per_frame': round(1000.0 * cpu_s / len(received), 3) if received else None,
            'encoding': results.get('encoding')}


def median(values):
    values = [v for v in values if v is not None]
    return round(statistics.median(values), 3) if values else None


def round_ratios(results, mode, case, peer):
    """Return the median of a case's CPU over a peer's, each round's own."""
    ratios = []
    for run in results:
        if (run['mode'], run['case']) != (mode, case):
            continue
        base = [r['cpu_percent'] for r in results
                if (r['mode'], r['case'], r['round']) == (mode, peer, run['round'])]
        if base and base[0]:
            ratios.append(run['cpu_percent'] / base[0])
    return median(ratios)


def summarise(results, modes, cases):
    """Return one row per (mode, case): medians over the rounds, ratios to the peers."""
    rows = []
    for width, height, fps in modes:
        mode = '%dx%d@%g' % (width, height, fps)
        by_case = {}
        for case in cases:
            runs = [r for r in results if (r['mode'], r['case']) == (mode, case)]
            if not runs:
                continue
            by_case[case] = {
                'mode': mode, 'case': case, 'rounds': len(runs), 'fps': fps,
                'encoding': runs[0]['encoding'],
                'delivered_fps': median(r['delivered_fps'] for r in runs),
                'cpu_percent': median(r['cpu_percent'] for r in runs),
                'cpu_percent_runs': [r['cpu_percent'] for r in runs],
                'cpu_ms_per_frame': median(r['cpu_ms_per_frame'] for r in runs),
                'kept_up': all(min(r['delivered_fps'], r['captured_fps'])
                               >= DELIVERED_MIN * fps for r in runs)}
        for row in by_case.values():
            before = by_case.get(row['case'] + ' (before)')
            if before and before['cpu_percent']:
                row['x before'] = round(row['cpu_percent'] / before['cpu_percent'], 2)
            for peer in PEERS:
                base = by_case.get(peer)
                if base and base['cpu_percent'] and row['case'] not in PEERS:
                    row['x ' + peer] = round(row['cpu_percent'] / base['cpu_percent'], 2)
                    row['x %s, per round' % peer] = round_ratios(
                        results, mode, row['case'], peer)
            rows.append(row)
    return rows


def print_table(rows, loads):
    print('\n| mode | driver | encoding | delivered fps | CPU, % of a core | CPU a frame | '
          'x v4l2_camera (profile) | x usb_cam (profile) | x before |')
    print('|---|---|---|---:|---:|---:|---:|---:|---:|')
    for r in rows:
        ratios = []
        for peer in PEERS:
            ratios.append('%.2f (%.2f)' % (r['x ' + peer], r['x %s, per round' % peer])
                          if 'x ' + peer in r else '-')
        print('| %s | %s | %s | %.1f%s | %.2f | %.3f ms | %s | %s | %s |' % (
            r['mode'], r['case'], r['encoding'], r['delivered_fps'],
            '' if r['kept_up'] else ' (short)', r['cpu_percent'], r['cpu_ms_per_frame'] or 0,
            *ratios, r.get('x before', '-')))
    print("\nratios: the medians' ratio (the median of each round's own ratio); x before: "
          'against the same case of the --before build')
    print('\nload average (1 min) during the run: %.1f to %.1f on %d CPUs' % (
        min(loads), max(loads), os.cpu_count()))


def main():
    parser = argparse.ArgumentParser(description=__doc__.split('\n\n')[0])
    parser.add_argument('--modes', default=MODES, help='WxH@fps,... (%s)' % MODES)
    parser.add_argument('--rounds', type=int, default=3, help='rounds (3)')
    parser.add_argument('--window', type=float, default=20.0, help='window, s (20)')
    parser.add_argument('--cases', nargs='+', default=list(CASES),
                        choices=CASES + BEFORE + FLOOR, help='cases (all)')
    parser.add_argument('--floor', action='store_true',
                        help='also the least a Python driver does (bench/camera_floor.py)')
    parser.add_argument('--before', metavar='INSTALL_BASE',
                        help="another build's colcon install (e.g. main's): its usbcam_publisher "
                        'runs too, as "py_vision bgr8 (before)" and "py_vision native (before)"')
    parser.add_argument('--tag', default='', help='added to the results file name')
    args = parser.parse_args()
    modes = parse_modes(args.modes)
    ours_env = local_node_env()
    envs = {'ours': ours_env, 'humble': humble_env()}
    envs['humble'].update(PYTHONUNBUFFERED='1', RCUTILS_COLORIZED_OUTPUT='0')
    peers = peer_executables(envs['humble']) if any(
        not case.startswith('py_vision') for case in args.cases) else {}
    if args.before:
        envs['before'] = installed_env_of(os.path.abspath(args.before))
        peers['before'] = os.path.abspath(args.before)
        args.cases += [case for case in BEFORE if case not in args.cases]
    if args.floor:
        args.cases += [case for case in FLOOR if case not in args.cases]
    state = tempfile.mkdtemp(prefix='bench_camera_cpu_')
    camera = EmulatedCamera(state, 'webcam_1080p', CAMERA_NODE)
    results, loads = [], []
    try:
        for round_index in range(args.rounds):
            for mode in modes:
                envs['profiles'] = profiles_for(mode[0], mode[1])
                # Each round in another order, so that no case always follows the same one.
                shift = round_index % len(args.cases)
                order = args.cases[shift:] + args.cases[:shift]
                for case in order:
                    workdir = tempfile.mkdtemp(dir=state)
                    loads.append(os.getloadavg()[0])
                    result = run_case(case, mode, camera, envs, peers, args.window, workdir)
                    result['round'] = round_index
                    results.append(result)
                    print('round %d %-22s %-12s captured %5.1f fps, delivered %5.1f fps, '
                          '%5.2f %% of a core, %.3f ms a frame (%s)' % (
                              round_index + 1, case, result['mode'], result['captured_fps'],
                              result['delivered_fps'],
                              result['cpu_percent'], result['cpu_ms_per_frame'] or 0,
                              result['encoding']), flush=True)
                    shutil.rmtree(workdir, ignore_errors=True)
    finally:
        camera.close()
        shutil.rmtree(state, ignore_errors=True)
    rows = summarise(results, modes, args.cases)
    print_table(rows, loads)
    name = 'camera_cpu-py%s%s' % (''.join(platform.python_version_tuple()[:2]),
                                  '-' + args.tag if args.tag else '')
    save_results(name, {'window_s': args.window, 'rounds': args.rounds, 'rows': rows,
                        'runs': results, 'load_average': [min(loads), max(loads)],
                        'ros_distro': 'humble' if ros_harness.ON_HUMBLE else 'jazzy'})


if __name__ == '__main__':
    main()
