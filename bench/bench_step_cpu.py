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
Measure vision_step's CPU a processed frame against its models' alone: the step's own work.

  .venv/bin/python bench/bench_step_cpu.py [--sizes 640x480,1280x720] [--fps 10]
      [--window S] [--rounds N] [--cases ...] [--hand-photo PATH]
  (. scripts/board_env.sh && python bench/bench_step_cpu.py)    # tflite_runtime 2.14

Behind usbcam_publisher at each size and --fps, each node the installed executable in a
process of its own on a ROS domain of its own, nobody subscribed to vision_step/image (the
step's image is not published), `threads` 1:

- `no hand`: vision_step with step:=hand_signs on the synthetic camera: the palm detector runs
  on every frame;
- `hand`: the same on a looping clip of the photograph of a hand (bench_hand_signs.py's: the
  hand drifting a few pixels a frame): the step follows it, the landmark model alone on each
  frame (the frames whose hand_sign says no_hand are counted: those ran the palm detector);
- `circle`, a reference: vision_step with the trivial circle step, the node without models:
  receiving a frame, converting it, the node's own bookkeeping;
- `bare`, a reference: a bare rclpy subscriber (bare_image_subscriber.py) of the same camera:
  what receiving a frame costs any rclpy node (issue 44's item 2 works on that part).

Each node's CPU time (utime + stime from /proc, all its threads) over --window seconds is
divided by the frames it processed in that time (vision_step's /diagnostics count; the bare
subscriber's own record). Where the node's /diagnostics splits its processing time into the
models' and the rest, that is recorded too (p50 of its last 5 s), and so is the split of its
CPU over the same window (its 'processing CPU ms' and 'models CPU ms', since start): the
worker thread's CPU a frame, of it the models' (in the node), the step's own work (the worker's
CPU less the models'), and the rest of the node (its CPU less the worker's: receiving the frame,
the executor, DDS).

The models alone, in this process, between the node runs (nothing else of the benchmark's
running): the same runtime as the node's (the first .tflite runtime installed: LiteRT in .venv,
tflite_runtime in the board-version environment) and the same threads, an interpreter of the
model file made directly with the runtime's own API (not py_vision's), its input set once to
the tensor the step feeds it for that case (the letterboxed synthetic frame; the crop around
the hand of the clip's first frame), then invoked --invokes times back to back: the thread's
CPU time a call. The ratio of a round is the node's CPU a processed frame over that; medians
over --rounds rounds, the cases interleaved. A model run once a frame period finds less of
itself in the caches than one run back to back (the machine's other work runs between): the
same model is also timed invoked at the camera's rate (--paced calls, one every frame period),
and the node's CPU given against that too. Prints a Markdown table and writes
bench/results/step_cpu-py<version>.json.
"""

import argparse
import os
from pathlib import Path
import statistics
import sys
import tempfile
import time

from bench_common import (BENCH, CLK_TCK, cpu_ticks, FIRST_FRAME_MARK, fresh_report,
                          local_node_env, processing_values, read_results, save_results,
                          start_helper)
from bench_hand_signs import hand_photo_path, make_clip
import ros_harness

SIZES = '640x480,1280x720'
CASES = ('bare', 'circle', 'no hand', 'hand')
SETTLE_S = 3.0
START_S = 90.0
PROFILE = ros_harness.SHARE / 'config' / 'fastdds_image_profile.xml'
# What the node's /diagnostics says of its processing time, where it says it (p50, ms).
SPLIT_KEYS = {'processing p50 ms': 'processing_ms_p50', 'models p50 ms': 'models_ms_p50',
              'rest p50 ms': 'rest_ms_p50'}
# Its worker thread's CPU since start, in processing and of it in models (ms).
CPU_KEYS = {'processing CPU ms': 'worker_cpu_ms', 'models CPU ms': 'models_in_node_cpu_ms'}


def interpreter_module():
    """Return (runtime name, the Interpreter class) of the first .tflite runtime installed."""
    from py_vision.models.runtime import RUNTIMES
    for name in RUNTIMES['.tflite']:
        try:
            if name == 'litert':
                from ai_edge_litert.interpreter import Interpreter
                from importlib.metadata import version
                return 'LiteRT %s' % version('ai-edge-litert'), Interpreter
            from tflite_runtime import __version__
            from tflite_runtime.interpreter import Interpreter
            return 'tflite_runtime %s' % __version__, Interpreter
        except ImportError:
            continue
    raise SystemExit('no .tflite runtime installed (ai-edge-litert, tflite-runtime)')


class ModelAlone:
    """One model file in the runtime's own interpreter, fed one tensor, invoked and timed."""

    def __init__(self, path, threads, tensor, interpreter_class):
        self.interpreter = interpreter_class(model_path=path, num_threads=threads)
        self.interpreter.allocate_tensors()
        index = self.interpreter.get_input_details()[0]['index']
        self.interpreter.set_tensor(index, tensor)

    def cpu_ms(self, invokes, period_s=0.0):
        """
        Return the calling thread's CPU a call, over invokes calls (after a few unmeasured).

        With a period_s, one call every period_s seconds (as a step at the camera's rate).
        """
        for _ in range(3):
            self.interpreter.invoke()
        cpu, due = 0.0, time.monotonic()
        for _ in range(invokes):
            if period_s:
                due += period_s
                time.sleep(max(0.0, due - time.monotonic()))
            start = time.thread_time()
            self.interpreter.invoke()
            cpu += time.thread_time() - start
        return cpu / invokes * 1e3


def model_inputs(size, clip):
    """Return {case: (model file, input tensor)}: what the step feeds its model in each case."""
    import cv2
    from py_vision.capture.synthetic_picture import synthetic_frame
    from py_vision.models.crops import letterbox, rotated_crop
    from py_vision.models.hands import HandTracker, LANDMARK_FILE, landmark_region
    from py_vision.models.palm import MODEL_FILE as PALM_FILE
    inputs = {'no hand': (PALM_FILE, letterbox(synthetic_frame(0, *size), 192, 192,
                                               (0.0, 1.0)).tensor)}
    if clip is not None:
        capture = cv2.VideoCapture(clip)
        ok, frame = capture.read()
        capture.release()
        if not ok:
            raise SystemExit('cannot read the clip %s' % clip)
        hands = HandTracker.from_files(max_hands=1).find(frame)
        if not hands:
            raise SystemExit('no hand found in the first frame of %s' % clip)
        region = landmark_region(hands[0].landmarks)
        inputs['hand'] = (LANDMARK_FILE, rotated_crop(
            frame, (region.x, region.y), region.side, region.rotation, 224, (0.0, 1.0)).tensor)
    return inputs


def camera_process(size, fps, device, env):
    return ros_harness.NodeProcess('usbcam_publisher', ros_harness.ros_args({
        'video_device': device, 'image_width': size[0], 'image_height': size[1],
        'framerate': float(fps)}), env, name='camera')


def measure_bare(size, fps, window, env, workdir):
    """Run the camera and a bare rclpy subscriber; return its CPU a received frame."""
    domain = ros_harness.DomainId()
    env = dict(env, ROS_DOMAIN_ID=str(domain.value))
    processes = []
    try:
        processes.append(camera_process(size, fps, 'synthetic', env))
        subscriber = start_helper('bare_subscriber', [
            sys.executable, str(BENCH / 'bare_image_subscriber.py'), '{out}', 'reliable'],
            dict(env, FASTRTPS_DEFAULT_PROFILES_FILE=str(PROFILE)), workdir)
        processes.append(subscriber)
        subscriber.wait_for_output(FIRST_FRAME_MARK, START_S)
        time.sleep(SETTLE_S)
        start, ticks = time.monotonic(), cpu_ticks(subscriber.pid)
        time.sleep(window)
        end, ticks = time.monotonic(), cpu_ticks(subscriber.pid) - ticks
        statuses = [proc.stop(timeout=15.0) for proc in reversed(processes)]
    finally:
        for proc in processes:
            proc.kill()
        domain.release()
    if any(statuses):
        raise SystemExit('the bare subscriber or its camera ended with %s' % statuses)
    frames = sum(1 for event in read_results(subscriber)['received'] if start <= event[0] < end)
    if not frames:
        raise SystemExit('the bare subscriber received no frame in the window')
    return {'cpu_ms_per_frame': ticks / CLK_TCK / frames * 1e3, 'frames': frames}


def measure_node(case, size, fps, window, env, clip):
    """Run the camera and vision_step; return its CPU a processed frame and its own split."""
    from diagnostic_msgs.msg import DiagnosticArray
    from rclpy.qos import QoSProfile, ReliabilityPolicy
    from std_msgs.msg import String
    domain = ros_harness.DomainId()
    env = dict(env, ROS_DOMAIN_ID=str(domain.value))
    peer = ros_harness.RosPeer(domain.value, name='bench_step_cpu')
    processes = []
    try:
        arrays = peer.collect(DiagnosticArray, '/diagnostics', QoSProfile(
            depth=100, reliability=ReliabilityPolicy.RELIABLE))
        signs = peer.collect(String, 'hand_sign', QoSProfile(
            depth=100, reliability=ReliabilityPolicy.RELIABLE))
        processes.append(camera_process(size, fps, clip if case == 'hand' else 'synthetic',
                                        env))
        node = ros_harness.NodeProcess('vision_step', ros_harness.ros_args({
            'step': 'circle' if case == 'circle' else 'hand_signs', 'threads': 1}),
            env, name='step')
        processes.append(node)
        ros_harness.wait_until(
            lambda: int(processing_values(arrays).get('processed', 0)) > 0, START_S, 0.1,
            'frames processed')
        time.sleep(SETTLE_S)
        # A fresh report at each end of the window: the counts and the CPU together.
        before = fresh_report(arrays)
        ticks, first_sign = cpu_ticks(node.pid), len(signs)
        time.sleep(window)
        after = fresh_report(arrays)
        ticks, window_signs = cpu_ticks(node.pid) - ticks, list(signs[first_sign:])
        statuses = [proc.stop(timeout=15.0) for proc in reversed(processes)]
        log = node.output()
    finally:
        peer.close()
        for proc in processes:
            proc.kill()
        domain.release()
    if any(statuses) or 'Traceback' in log:
        raise SystemExit('%s: the node or its camera ended with %s:\n%s' % (
            case, statuses, log))
    frames = int(after['processed']) - int(before['processed'])
    if frames <= 0:
        raise SystemExit('%s: no frame processed in the window' % case)
    result = {'cpu_ms_per_frame': ticks / CLK_TCK / frames * 1e3, 'frames': frames,
              'skipped': int(after['skipped']) - int(before['skipped'])}
    for key, name in SPLIT_KEYS.items():
        if after.get(key) not in (None, '', 'None', 'none'):
            result[name] = float(after[key])
    for key, name in CPU_KEYS.items():
        if key in after and key in before:
            result[name] = (int(after[key]) - int(before[key])) / frames
    if 'worker_cpu_ms' in result:
        result['own_in_node_ms'] = result['worker_cpu_ms'] - result['models_in_node_cpu_ms']
        result['node_rest_ms'] = result['cpu_ms_per_frame'] - result['worker_cpu_ms']
    if case != 'circle':
        result['no_hand_frames'] = sum(1 for sign in window_signs if sign.data == 'no_hand')
    return result


def summarise(runs, cases, sizes):
    """Return one row per (size, case): medians over the rounds, and the ratios."""
    rows = []
    for size in sizes:
        label = '%dx%d' % size
        references = {}
        for case in cases:
            taken = [run for run in runs if (run['size'], run['case']) == (label, case)]
            if not taken:
                continue

            def median(key, taken=taken):
                values = [run[key] for run in taken if run.get(key) is not None]
                return round(statistics.median(values), 3) if values else None
            row = {'size': label, 'case': case, 'rounds': len(taken),
                   'cpu_ms_per_frame': median('cpu_ms_per_frame'),
                   'frames': median('frames')}
            for key in ('model_cpu_ms', 'ratio', 'paced_model_cpu_ms', 'ratio_paced',
                        'no_hand_frames', 'processing_ms_p50',
                        'models_ms_p50', 'rest_ms_p50', 'worker_cpu_ms',
                        'models_in_node_cpu_ms', 'own_in_node_ms', 'node_rest_ms',
                        'ratio_in_node'):
                if median(key) is not None:
                    row[key] = median(key)
            if case in ('bare', 'circle'):
                references[case] = row['cpu_ms_per_frame']
            else:
                row.update({'x_%s' % name: round(row['cpu_ms_per_frame'] / value, 2)
                            for name, value in references.items()})
                # Beyond the node without models (circle) and the models alone: the step's own.
                if 'circle' in references and row.get('model_cpu_ms'):
                    row['own_ms'] = round(row['cpu_ms_per_frame'] - references['circle']
                                          - row['model_cpu_ms'], 3)
            rows.append(row)
    return rows


def print_table(rows, runtime, load):
    print('\n| size | case | CPU a processed frame | model alone (%s) | ratio | model alone '
          "at the camera's rate | ratio | circle (no models) | own work beyond circle and "
          'model | bare subscriber | node: processing / models / rest p50 |' % runtime)
    print('|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|')
    print_rows(rows)
    if any(row.get('worker_cpu_ms') for row in rows):
        print("\nThe same frames, the node's CPU split by its own accounting (ms a frame):")
        print("\n| size | case | node | worker thread | of it models | of it the step's own "
              'work | rest of the node (receiving, executor, DDS) | node / its models |')
        print('|---|---|---:|---:|---:|---:|---:|---:|')
        for row in rows:
            if row.get('worker_cpu_ms') is None:
                continue
            print('| %s | %s | %.2f | %.2f | %.2f | %.2f | %.2f | %s |' % (
                row['size'], row['case'], row['cpu_ms_per_frame'], row['worker_cpu_ms'],
                row['models_in_node_cpu_ms'], row['own_in_node_ms'], row['node_rest_ms'],
                '%.2f' % row['ratio_in_node'] if row.get('ratio_in_node') else '-'))
    print('\nmachine load average (1 min) during the run: %.1f to %.1f on %d CPUs' % (
        min(load), max(load), os.cpu_count()))


def print_rows(rows):
    for size in sorted({row['size'] for row in rows}, key=lambda s: int(s.split('x')[0])):
        of_size = {row['case']: row for row in rows if row['size'] == size}
        for case, row in of_size.items():
            if case in ('bare', 'circle'):
                continue

            def ms(value):
                return '-' if value is None else '%.2f ms' % value
            split = '/'.join('-' if row.get(key) is None else '%.1f' % row[key] for key in (
                'processing_ms_p50', 'models_ms_p50', 'rest_ms_p50'))
            print('| %s | %s | %s | %s | %s | %s | %s | %s | %s | %s | %s ms |' % (
                size, case, ms(row['cpu_ms_per_frame']), ms(row.get('model_cpu_ms')),
                '%.2f' % row['ratio'] if row.get('ratio') else '-',
                ms(row.get('paced_model_cpu_ms')),
                '%.2f' % row['ratio_paced'] if row.get('ratio_paced') else '-',
                ms(of_size.get('circle', {}).get('cpu_ms_per_frame')), ms(row.get('own_ms')),
                ms(of_size.get('bare', {}).get('cpu_ms_per_frame')), split))


def main():
    parser = argparse.ArgumentParser(description=__doc__.split('\n\n')[1])
    parser.add_argument('--sizes', default=SIZES, help='frame sizes, comma-separated')
    parser.add_argument('--fps', type=float, default=10.0, help="the camera's rate")
    parser.add_argument('--window', type=float, default=20.0, help='seconds measured a case')
    parser.add_argument('--rounds', type=int, default=3, help='rounds (medians over them)')
    parser.add_argument('--invokes', type=int, default=100,
                        help='calls of a model alone, back to back, each time it is measured')
    parser.add_argument('--paced', type=int, default=30,
                        help="calls of a model alone at the camera's rate, each time")
    parser.add_argument('--cases', default=','.join(CASES), help='cases, comma-separated')
    parser.add_argument('--hand-photo', default='', help='photograph of a hand for the clip')
    options = parser.parse_args()
    sizes = [tuple(int(v) for v in size.split('x')) for size in options.sizes.split(',')]
    cases = options.cases.split(',')
    if not set(cases) <= set(CASES):
        raise SystemExit('--cases: choose from %s' % ', '.join(CASES))
    env = local_node_env()  # this process' subscribers join the nodes on their transport
    from py_vision.models.files import shipped_model
    runtime, interpreter_class = interpreter_module()
    runs, load = [], [os.getloadavg()[0]]
    with tempfile.TemporaryDirectory(prefix='bench_step_cpu_') as workdir:
        photo = hand_photo_path(options.hand_photo) if 'hand' in cases else None
        clips = {size: make_clip(photo, workdir, size) for size in sizes} if photo else {}
        models = {}
        for size in sizes:
            for case, (name, tensor) in model_inputs(size, clips.get(size)).items():
                models[size, case] = ModelAlone(shipped_model(name), 1, tensor,
                                                interpreter_class)
        for round_index in range(options.rounds):
            for size in sizes:
                for case in cases:
                    print('round %d, %dx%d at %g fps, %s ...' % (
                        (round_index + 1,) + size + (options.fps, case)), flush=True)
                    if case == 'bare':
                        result = measure_bare(size, options.fps, options.window, env, workdir)
                    else:
                        result = measure_node(case, size, options.fps, options.window, env,
                                              clips.get(size))
                    if (size, case) in models:
                        alone = models[size, case]
                        result['model_cpu_ms'] = alone.cpu_ms(options.invokes)
                        result['ratio'] = result['cpu_ms_per_frame'] / result['model_cpu_ms']
                        result['paced_model_cpu_ms'] = alone.cpu_ms(options.paced,
                                                                    1.0 / options.fps)
                        result['ratio_paced'] = (result['cpu_ms_per_frame']
                                                 / result['paced_model_cpu_ms'])
                    if result.get('models_in_node_cpu_ms'):
                        # Against the models' CPU in the node, measured in the same window.
                        result['ratio_in_node'] = (result['cpu_ms_per_frame']
                                                   / result['models_in_node_cpu_ms'])
                    load.append(os.getloadavg()[0])
                    result.update(round=round_index + 1, size='%dx%d' % size, case=case,
                                  load_average=load[-1])
                    runs.append(result)
                    print('  %s' % {key: round(value, 3) if isinstance(value, float) else value
                                    for key, value in result.items()}, flush=True)
    rows = summarise(runs, cases, sizes)
    print_table(rows, runtime, load)
    save_results('step_cpu-py%d%d' % sys.version_info[:2], {
        'runtime': runtime, 'threads': 1, 'fps': options.fps, 'sizes': options.sizes,
        'window_s': options.window, 'rounds': options.rounds, 'invokes': options.invokes,
        'cpus': os.cpu_count(), 'load_average': [min(load), max(load)], 'rows': rows,
        'runs': runs, 'photo': Path(photo).name if photo else None})


if __name__ == '__main__':
    main()
