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
Measure the models on a VGA frame: HandTracker.find and FaceDetector.detect, per runtime.

  .venv/bin/python bench/bench_models.py [--rounds N]
  (. scripts/board_env.sh && python bench/bench_models.py)    # tflite_runtime, the boards'

For each .tflite runtime installed in the running Python (LiteRT in .venv, tflite_runtime in
the board-version .venv-board) and 1 and 2 threads, it times per call:
  faces            FaceDetector.detect on a 640x480 frame with one face (the astronaut)
  hands, none      HandTracker.find on the synthetic camera's 640x480 frame: the palm
                   detector alone (no palm there)
  hands, one       HandTracker.find with every threshold at 0 and at most one hand, not
                   tracking: the palm detector and one landmark pass, what a frame with a new
                   hand costs
  hands, tracked   the same, tracking: the hand found in the previous frame is looked for
                   where it was, one landmark pass and no palm detector (a hand followed)
  palm model, landmark model, face model: the model's run() alone
  reference        cv2.resize to 320x240 and cv2.imencode to JPEG of the same frame
The cases run interleaved, one call each per round, so a busy machine slows them alike; each
case's p50 is also given as a multiple of the reference's p50. Prints a Markdown table and
writes bench/results/models-<python>.json.
"""

import argparse
import os
import statistics
import sys
import time

from bench_common import save_results
import cv2
import numpy as np
from py_vision.capture.synthetic_picture import synthetic_frame
from py_vision.models.faces import FaceDetector
from py_vision.models.files import shipped_model
from py_vision.models.hands import HandTracker, LANDMARK_FILE
from py_vision.models.palm import MODEL_FILE as PALM_FILE
from py_vision.models.runtime import load, RuntimeMissing

RUNTIMES = ('litert', 'tflite_runtime')
THREADS = (1, 2)
WARMUP = 5


def face_frame():
    """Return a 640x480 frame with the astronaut's face (or the synthetic one without it)."""
    frame = np.full((480, 640, 3), 90, np.uint8)
    try:
        from photos import photo
        frame[20:470, 150:600] = cv2.resize(photo('astronaut.png')[30:330, 110:410],
                                            (450, 450), interpolation=cv2.INTER_LINEAR)
    except AssertionError as error:  # scikit-image missing: say so in the table's title
        print('no astronaut photograph (%s): the face case has no face' % error)
    return frame


def cases_for(runtime, threads, frames):
    """Return {case: function} for one runtime and thread count (None when not installed)."""
    def model(name):
        return load(shipped_model(name), threads, runtime)
    try:
        palm, landmark, face = model(PALM_FILE), model(LANDMARK_FILE), model(
            'face_detection_short_range.tflite')
    except RuntimeMissing:
        return None, None
    faces = FaceDetector(face)
    tracker = HandTracker(palm, landmark)
    one_hand = HandTracker(palm, landmark, min_palm_score=0.0, min_hand_score=0.0,
                           max_hands=1, track=False)
    tracked = HandTracker(palm, landmark, min_palm_score=0.0, min_hand_score=0.0, max_hands=1)
    assert len(one_hand.find(frames['synthetic'])) == 1
    assert len(tracked.find(frames['synthetic'])) == 1
    assert tracker.find(frames['synthetic']) == []
    zeros = {m: np.zeros(m.inputs[0].shape, np.float32) for m in (palm, landmark, face)}
    return palm.runtime, {
        'faces': lambda: faces.detect(frames['face']),
        'hands, none': lambda: tracker.find(frames['synthetic']),
        'hands, one': lambda: one_hand.find(frames['synthetic']),
        'hands, tracked': lambda: tracked.find(frames['synthetic']),
        'palm model': lambda: palm.run(zeros[palm]),
        'landmark model': lambda: landmark.run(zeros[landmark]),
        'face model': lambda: face.run(zeros[face]),
    }


def reference(frame):
    """Return the reference: a resize and a JPEG encoding of the frame."""
    return lambda: cv2.imencode('.jpg', cv2.resize(frame, (320, 240),
                                                   interpolation=cv2.INTER_AREA))


def measure(cases, rounds):
    """Return {case: [seconds per call]}, the cases interleaved round by round."""
    for func in cases.values():
        for _ in range(WARMUP):
            func()
    samples = {name: [] for name in cases}
    for _ in range(rounds):
        for name, func in cases.items():
            start = time.perf_counter()
            func()
            samples[name].append(time.perf_counter() - start)
    return samples


def percentile(values, fraction):
    """Return the value below which `fraction` of the values lie (nearest rank)."""
    ordered = sorted(values)
    return ordered[min(len(ordered) - 1, max(0, int(round(fraction * len(ordered))) - 1))]


def main():
    parser = argparse.ArgumentParser(description=__doc__.split('\n\n')[1])
    parser.add_argument('--rounds', type=int, default=200,
                        help='calls of each case (default 200)')
    args = parser.parse_args()
    frames = {'face': face_frame(), 'synthetic': synthetic_frame(0, 640, 480)}
    load_before = os.getloadavg()[0]
    rows = []
    for runtime in RUNTIMES:
        for threads in THREADS:
            name, cases = cases_for(runtime, threads, frames)
            if cases is None:
                print('%s: not installed here' % runtime)
                break
            cases = dict({'reference': reference(frames['synthetic'])}, **cases)
            samples = measure(cases, args.rounds)
            ref_p50 = statistics.median(samples['reference'])
            for case, times in samples.items():
                p50 = statistics.median(times)
                rows.append({'runtime': name, 'threads': threads, 'case': case,
                             'p50_ms': round(p50 * 1e3, 2),
                             'p99_ms': round(percentile(times, 0.99) * 1e3, 2),
                             'x_reference': round(p50 / ref_p50, 1),
                             'fps_at_p50': round(1 / p50, 1)})
    print('\n| runtime | threads | case | p50 ms | p99 ms | p50 / reference | calls/s at p50 |')
    print('|---|---|---|---|---|---|---|')
    for row in rows:
        print('| %(runtime)s | %(threads)d | %(case)s | %(p50_ms).2f | %(p99_ms).2f | '
              '%(x_reference).1f | %(fps_at_p50).1f |' % row)
    # The machine's load: the p50 / reference column is what stays comparable under load.
    load = (round(load_before, 2), round(os.getloadavg()[0], 2))
    print('\nload average (1 min) before and after: %.2f, %.2f on %d CPUs'
          % (load + (os.cpu_count(),)))
    save_results('models-py%s' % ''.join(map(str, sys.version_info[:2])),
                 {'rounds': args.rounds, 'frame': '640x480', 'cpus': os.cpu_count(),
                  'load_average': load, 'rows': rows})


if __name__ == '__main__':
    main()
