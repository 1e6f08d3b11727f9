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
Measure what publishing /diagnostics costs: usbcam_publisher with and without it.

  .venv/bin/python bench/bench_diagnostics.py [--duration S] [--rounds N]

1. One report: the publisher's camera status built and published on /diagnostics, called
   directly --calls times in this process (CPU time per call, so CPU per second at 1 Hz).
2. The node: usbcam_publisher as installed on the synthetic camera (640x480 at 30 fps, a
   subscriber on /diagnostics in this process so that the reports are sent), and the same
   node publishing no reports (its timer, which syncs the control parameters too, left),
   one after the other, --rounds times each,
   alternating; CPU (utime + stime from /proc) per second over --duration seconds after
   a settling time. The difference is the diagnostics' cost, the node without them the
   reference, both measured in this run.
Prints a Markdown table and writes bench/results/diagnostics.json.
"""

import argparse
import os
import signal
import statistics
import sys
import time

from bench_common import CLK_TCK, cpu_ticks, local_node_env, save_results
import ros_harness

CAMERA = {'video_device': 'synthetic', 'image_width': 640, 'image_height': 480,
          'framerate': 30.0}
SETTLE_S = 3.0


def run_node(diagnostics):
    """Run usbcam_publisher (this file's `node on|off` mode), its diagnostics on or off."""
    from py_vision import node_main
    from py_vision.usbcam_publisher import USBImagePublisher

    class WithoutDiagnostics(USBImagePublisher):
        """usbcam_publisher that never publishes /diagnostics (its timer still syncs controls)."""

        def _setup(self, values):
            super()._setup(values)
            self.diagnostics.publish = lambda: None

    node_class = USBImagePublisher if diagnostics == 'on' else WithoutDiagnostics
    sys.exit(node_main.run(node_class, args=sys.argv[:1] + sys.argv[3:]))


def one_report(calls):
    """Return the CPU seconds one camera status report costs, built and published."""
    from dataclasses import replace

    from py_vision.camera_diagnostics import CameraMonitor
    from py_vision.capture import CaptureStats
    from py_vision.diagnostics import Diagnostics
    from py_vision.params import Parameters
    import rclpy
    context = rclpy.Context()
    domain = ros_harness.DomainId()
    rclpy.init(context=context, domain_id=domain.value)
    node = rclpy.create_node('bench_diagnostics', context=context)
    try:
        monitor = CameraMonitor()
        stats = [CaptureStats(present=True, streaming=True, pixel_format='yuyv', width=640,
                              height=480, fps=30.0, measured_fps=29.9)]
        subscribers = {'/usb_camera/image': 1, '/usb_camera/image/compressed': 0,
                       '/usb_camera/camera_info': 1}

        def report():
            # A new frame count every report, as while streaming: the full status is made.
            stats[0] = replace(stats[0], frames=stats[0].frames + 30)
            return monitor.status(stats[0], 'synthetic', 30.0, subscribers)
        diagnostics = Diagnostics(Parameters(node), hardware_id='synthetic', period_s=3600.0)
        diagnostics.add('camera', report)
        diagnostics.publish()  # the first call creates what later ones reuse
        start = time.process_time()
        for _ in range(calls):
            diagnostics.publish()
        return (time.process_time() - start) / calls
    finally:
        node.destroy_node()
        rclpy.shutdown(context=context)
        domain.release()


def node_cpu(diagnostics, duration, env):
    """Run the node with diagnostics on or off; return its CPU seconds per second."""
    from diagnostic_msgs.msg import DiagnosticArray
    domain = ros_harness.DomainId()
    env = dict(env, ROS_DOMAIN_ID=str(domain.value))
    node = ros_harness.NodeProcess(sys.executable, [__file__, 'node', diagnostics] +
                                   ros_harness.ros_args(CAMERA), env,
                                   name='usbcam_publisher')
    peer = ros_harness.RosPeer(domain.value, name='bench_monitor')
    try:
        reports = peer.collect(DiagnosticArray, '/diagnostics')
        node.wait_for_output('opened synthetic', 60)
        time.sleep(SETTLE_S)
        before, start = cpu_ticks(node.proc.pid), time.monotonic()
        time.sleep(duration)
        after, end = cpu_ticks(node.proc.pid), time.monotonic()
        received = len(reports)
    finally:
        peer.close()
        status = node.stop(signal.SIGINT, 15.0)
        log = node.output()
        node.kill()
        domain.release()
    if status != 0 or 'Traceback' in log:
        raise SystemExit('the node ended with %s:\n%s' % (status, log))
    if (diagnostics == 'on') != (received > 0):
        raise SystemExit('diagnostics %s, but %d reports received' % (diagnostics, received))
    return (after - before) / CLK_TCK / (end - start)


def main():
    if sys.argv[1:2] == ['node']:
        run_node(sys.argv[2])
        return
    parser = argparse.ArgumentParser(description=__doc__.split('\n\n')[1])
    parser.add_argument('--duration', type=float, default=20.0, help='seconds measured a run')
    parser.add_argument('--rounds', type=int, default=3, help='runs with and without each')
    parser.add_argument('--calls', type=int, default=2000, help='reports timed in process')
    options = parser.parse_args()

    env = local_node_env()  # the monitor joins the nodes on their transport

    report_s = one_report(options.calls)
    print('one camera report, built and published: %.3f ms CPU (%d calls)' % (
        report_s * 1e3, options.calls), flush=True)
    runs = {'on': [], 'off': []}
    load_before = os.getloadavg()[0]
    for round_ in range(options.rounds):
        for diagnostics in ('off', 'on'):
            cpu = node_cpu(diagnostics, options.duration, env)
            runs[diagnostics].append(cpu)
            print('round %d, diagnostics %-3s: %.2f%% of a core' % (
                round_ + 1, diagnostics, cpu * 100), flush=True)
    load = (load_before, os.getloadavg()[0])
    off, on = statistics.median(runs['off']), statistics.median(runs['on'])
    print('\n| measured | CPU, % of one core | ratio to the node without diagnostics |')
    print('|---|---:|---:|')
    print('| usbcam_publisher without diagnostics (median of %d) | %.2f %% | 1.000 |' % (
        options.rounds, off * 100))
    print('| usbcam_publisher with diagnostics (median of %d) | %.2f %% | %.3f |' % (
        options.rounds, on * 100, on / off))
    print('| difference of the medians | %+.2f %% | %+.3f |' % (
        (on - off) * 100, (on - off) / off))
    print('| one report a second, timed in process | %.3f %% | %.4f |' % (
        report_s * 100, report_s / off))
    print('machine load average (1 min) before and after: %.1f, %.1f on %d CPUs' % (
        load + (os.cpu_count(),)))
    save_results('diagnostics', {
        'camera': '%(image_width)dx%(image_height)d at %(framerate)g fps, synthetic' % CAMERA,
        'duration_s': options.duration, 'rounds': options.rounds, 'calls': options.calls,
        'report_cpu_ms': round(report_s * 1e3, 4),
        'node_cpu_fraction': {k: [round(v, 5) for v in vs] for k, vs in runs.items()},
        'median_off': round(off, 5), 'median_on': round(on, 5),
        'cpus': os.cpu_count(), 'load_average': load})


if __name__ == '__main__':
    main()
