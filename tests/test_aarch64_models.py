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
The boards' TensorFlow Lite runtime, tflite_runtime 2.14.0's aarch64 build, on the shipped models.

The image petalinux/ builds installs tflite-runtime 2.14.0's aarch64 wheel as PyPI has it. Here
that build runs in Debian 12's aarch64 Python under QEMU's user-mode emulator
(scripts/aarch64_root.sh sets both up in a cache: without it these tests are skipped with the
reason, and fail in CI). The three models get the same inputs there, in the same release's
x86-64 build and in LiteRT 2.3 (the PC's runtime): the tensors py_vision's own code cuts from
the project's photographs (letterboxed for the palm and face detectors, the hand's rotated crop
for the landmark model), made once on x86-64 and saved, and a random tensor each. Their raw
outputs agree within the tolerance below, and so does what py_vision decodes of them: the
palms, faces and hands, boxes, keypoints, landmarks, scores and which hand.

The tolerance: every runtime runs these float32 models through XNNPACK, whose kernels are
written for each instruction set (NEON on aarch64, AVX and FMA on x86-64; LiteRT 2.3 has a
later XNNPACK). Where two kernels add a sum's terms in another order, or round at another
step, a result's last bits differ, and the layers after it carry that on. Measured: the face
model's outputs are the same to the bit in all three; the palm and landmark models' differ by
at most 7e-6 of an output's largest magnitude (some 60 float32 steps of it). RTOL, 1e-4 of an
output's largest magnitude, is ten times that and still the fourth significant digit (a
landmark moves by less than 0.02 pixel of the 224-pixel crop); decoded, the boxes, keypoints
and landmarks agree within PIXELS of the frame and the scores within SCORE.

Debian 12 has no Python 3.10, the boards' Python: the wheel run here is the one for Python
3.11. Its library is the Python 3.10 one's build for another Python (the same TensorFlow Lite
and XNNPACK machine code, the Python binding aside): test_the_wheel_run_here_is_the_image_build
compares the two.
"""

import collections
import hashlib
import json
import os
from pathlib import Path
import re
import struct
import subprocess
import sys
import zipfile

import numpy as np
from photos import hand_photo, photo
from py_vision.models.faces import FaceDetector
from py_vision.models.files import shipped_model
from py_vision.models.hands import HandTracker
from py_vision.models.palm import PalmDetector
from py_vision.models.runtime import load
import pytest

REPO = Path(__file__).resolve().parents[1]
RUNNER = Path(__file__).resolve().parent / 'tflite_runner.py'
RECIPES = REPO / 'petalinux' / 'meta-user' / 'recipes-python' / 'python3-tflite-runtime'
CACHE = Path(os.environ.get('PY_VISION_AARCH64_CACHE') or Path(
    os.environ.get('XDG_CACHE_HOME') or Path.home() / '.cache') / 'py_vision' / 'aarch64')
IMAGE_WHEEL = 'tflite_runtime-2.14.0-cp310-cp310-manylinux_2_34_aarch64.whl'
RUN_WHEEL = 'tflite_runtime-2.14.0-cp311-cp311-manylinux_2_34_aarch64.whl'
LIBRARY = 'tflite_runtime/_pywrap_tensorflow_interpreter_wrapper.so'

# The models and the value range of their input (their code's letterbox and rotated_crop).
MODELS = {'palm_detection_lite': (0.0, 1.0), 'hand_landmark_lite': (0.0, 1.0),
          'face_detection_short_range': (-1.0, 1.0)}
# The photographs: a hand (OpenCV's documentation's), a face, and a horse whose leg the palm
# detector takes for a palm (test_hands.py), whose landmarks the landmark model then scores low.
PICTURES = {'hand': hand_photo, 'astronaut': lambda: photo('astronaut.png'),
            'horse': lambda: photo('horse.png')}
AARCH64, X86, LITERT = 'aarch64', 'x86-64', 'LiteRT'
RUNTIMES = {AARCH64: 'tflite_runtime 2.14.0 aarch64 (QEMU)',
            X86: 'tflite_runtime 2.14.0 x86-64', LITERT: 'LiteRT 2.3 x86-64'}
# Raw outputs: |a - b| <= RTOL times the output's largest magnitude (module docstring).
RTOL = 1e-4
# Decoded results: boxes, keypoints and landmarks in frame pixels (measured: 5e-4 at most),
# scores 0 to 1 (measured: 5e-7 at most).
PIXELS, SCORE = 0.01, 1e-5
# QEMU runs the 11 inputs in 45 to 100 s on the 2-core test machine; this is for a far busier one.
TIMEOUT = 1800


def _unavailable(why: str) -> None:
    if os.environ.get('CI') == 'true':
        pytest.fail(why + ', and CI requires it')
    pytest.skip(why)


@pytest.fixture(scope='module')
def cache() -> Path:
    """Return the cache scripts/aarch64_root.sh filled; skip (fail in CI) where it did not."""
    if not (CACHE / '.complete').is_file():
        problem = CACHE / 'problem.txt'
        _unavailable('no aarch64 Python and tflite_runtime in %s (%s)' % (
            CACHE, problem.read_text().strip() if problem.is_file()
            else 'run scripts/aarch64_root.sh'))
    if sys.version_info[:2] != (3, 11):
        _unavailable('the x86-64 tflite_runtime wheel in %s is for Python 3.11, this is %d.%d'
                     % (CACHE, *sys.version_info[:2]))
    return CACHE


class _Recorder:
    """A model that keeps each distinct input it runs on, under a case name, and its outputs."""

    def __init__(self, model):
        self.model = model
        self.case = ''
        self.tensors, self.results = {}, {}

    def __getattr__(self, name):
        return getattr(self.model, name)

    def run(self, *arrays):
        outputs = self.model.run(*arrays)
        if _key(arrays[0]) not in {_key(array) for array in self.tensors.values()}:
            name = self.case
            number = 1
            while name in self.tensors:
                number += 1
                name = '%s-%d' % (self.case, number)
            self.tensors[name] = np.ascontiguousarray(arrays[0], np.float32)
            self.results[name] = outputs
        return outputs


class _Replay:
    """A model that answers with what a runtime gave for the same input."""

    def __init__(self, model, tensors, results):
        self.model = model
        self.answers = {_key(tensors[case]): results[case] for case in tensors}

    def __getattr__(self, name):
        return getattr(self.model, name)

    def run(self, *arrays):
        return [array.copy() for array in self.answers[_key(arrays[0])]]


def _key(array: np.ndarray) -> str:
    return hashlib.sha256(np.ascontiguousarray(array, np.float32).tobytes()).hexdigest()


@pytest.fixture
def runs(cache, tmp_path):
    """
    Return the inputs, each runtime's outputs and what each run says of itself.

    The inputs are what py_vision's detectors and hand tracker feed the models (in LiteRT) on
    the photographs, plus a random tensor per model; saved as .npy and run by tflite_runner.py
    in the x86-64 and the aarch64 tflite_runtime.
    """
    pictures = {name: read() for name, read in PICTURES.items()}
    models = {name: _Recorder(load(shipped_model(name + '.tflite'), 1, 'litert'))
              for name in MODELS}
    palm, landmark, face = (models[name] for name in MODELS)
    for name, image in pictures.items():
        palm.case = face.case = landmark.case = name
        PalmDetector(palm).detect(image)
        FaceDetector(face).detect(image)
        HandTracker(palm, landmark, min_hand_score=0.0, track=False).find(image)
    random = np.random.default_rng(38)
    for name, (low, high) in MODELS.items():
        models[name].case = 'random'
        models[name].run(random.uniform(low, high, models[name].inputs[0].shape)
                         .astype(np.float32))
    assert 'hand' in landmark.tensors and 'horse' in landmark.tensors, list(landmark.tensors)

    for name, model in models.items():
        (tmp_path / 'cases' / name).mkdir(parents=True)
        for case, tensor in model.tensors.items():
            np.save(tmp_path / 'cases' / name / (case + '.npy'), tensor)
    folder = os.path.dirname(shipped_model('palm_detection_lite.tflite'))
    root = cache / 'aarch64'
    commands = {
        X86: [sys.executable, '-I', str(RUNNER), str(cache / 'site-x86_64')],
        AARCH64: [str(cache / 'qemu-aarch64-static'), '-L', str(root),
                  str(root / 'usr' / 'bin' / 'python3.11'), '-I', str(RUNNER),
                  str(cache / 'site-aarch64')],
    }
    outputs = {LITERT: {name: model.results for name, model in models.items()}}
    about = {}
    for runtime, command in commands.items():
        out = tmp_path / runtime
        result = subprocess.run(command + [folder, str(tmp_path / 'cases'), str(out)],
                                stdin=subprocess.DEVNULL, capture_output=True, text=True,
                                timeout=TIMEOUT)
        assert result.returncode == 0, '%s failed (%d):\n%s' % (
            RUNTIMES[runtime], result.returncode, result.stderr[-3000:])
        about[runtime] = json.loads((out / 'about.json').read_text())
        outputs[runtime] = {
            name: {case: [np.load(out / name / ('%s.%d.npy' % (case, number)))
                          for number in range(len(model.outputs))]
                   for case in model.tensors}
            for name, model in models.items()}
    return {'pictures': pictures, 'models': models, 'outputs': outputs, 'about': about}


def _differences(runs):
    """Yield (model, case, output name, {pair: max |a - b|}, max |value|, within tolerance)."""
    outputs = runs['outputs']
    for name, model in runs['models'].items():
        for case in model.tensors:
            for number, info in enumerate(model.outputs):
                values = {runtime: outputs[runtime][name][case][number].astype(np.float64)
                          for runtime in RUNTIMES}
                pairs = {}
                within = True
                for a, b in ((AARCH64, X86), (AARCH64, LITERT), (X86, LITERT)):
                    gap = np.abs(values[a] - values[b])
                    pairs[a, b] = float(gap.max())
                    within &= pairs[a, b] <= RTOL * float(np.abs(values[b]).max())
                yield (name, case, info.name, pairs, float(np.abs(values[X86]).max()), within)


def _table(rows) -> str:
    lines = ['%-27s %-9s %-22s %11s %11s %11s %9s' % (
        'model', 'input', 'output', 'aarch64-x86', 'aarch64-LRT', 'x86-LRT', 'max |x|')]
    for name, case, output, pairs, scale, within in rows:
        lines.append('%-27s %-9s %-22s %11.2e %11.2e %11.2e %9.3g%s' % (
            name, case, output[:22], pairs[AARCH64, X86], pairs[AARCH64, LITERT],
            pairs[X86, LITERT], scale, '' if within else '  BEYOND TOLERANCE'))
    return '\n'.join(lines)


def _decoded(runs, runtime):
    """Return what py_vision decodes of a runtime's outputs: palms, faces, hands per picture."""
    models, outputs = runs['models'], runs['outputs']

    def replay(name, source=runtime):
        return _Replay(models[name].model, models[name].tensors, outputs[source][name])

    found = {}
    for picture, image in runs['pictures'].items():
        # The hands from the reference's palms, so that every runtime's landmark model gets the
        # same crops (the palms each runtime finds are compared on their own).
        tracker = HandTracker(replay('palm_detection_lite', LITERT), replay('hand_landmark_lite'),
                              min_hand_score=0.0, track=False)
        found[picture] = {
            'palms': PalmDetector(replay('palm_detection_lite')).detect(image),
            'faces': FaceDetector(replay('face_detection_short_range')).detect(image),
            'hands': tracker.find(image)}
    return found


def _gaps(one, other):
    """Return the largest differences of two lists of found things, matched in order."""
    pixels = score = 0.0
    for a, b in zip(one, other):
        for field in ('box', 'keypoints', 'landmarks'):
            if hasattr(a, field):
                gap = np.abs(getattr(a, field).astype(np.float64) - getattr(b, field))
                pixels = max(pixels, float(gap.max()))
        score = max(score, abs(a.score - b.score))
    return pixels, score


def _decoded_problems(runs):
    """Return what the runtimes' decoded results show (lines) and where they differ."""
    found = {runtime: _decoded(runs, runtime) for runtime in RUNTIMES}
    lines, problems = [], []
    for picture in runs['pictures']:
        for kind in ('palms', 'faces', 'hands'):
            reference = found[X86][picture][kind]
            counts = {runtime: len(found[runtime][picture][kind]) for runtime in RUNTIMES}
            line = '%-9s %-5s %d' % (picture, kind, len(reference))
            if len(set(counts.values())) != 1:
                problems.append('%s %s: found %s' % (picture, kind, counts))
                continue
            for other in (X86, LITERT):
                pixels, score = _gaps(found[AARCH64][picture][kind], found[other][picture][kind])
                line += '   %-7s %7.1e px %7.1e' % (other, pixels, score)
                if pixels > PIXELS or score > SCORE:
                    problems.append('%s %s: aarch64 and %s differ by %g px, %g in score'
                                    % (picture, kind, other, pixels, score))
            if kind == 'hands':
                sides = {runtime: [hand.handedness for hand in found[runtime][picture][kind]]
                         for runtime in RUNTIMES}
                line += '   ' + ' '.join('%s %.3f' % (hand.handedness, hand.score)
                                         for hand in reference)
                if sides[AARCH64] != sides[X86] or sides[AARCH64] != sides[LITERT]:
                    problems.append('%s: which hand differs: %s' % (picture, sides))
            lines.append(line)
    # What the photographs must give, else the comparison compares nothing.
    hands, faces = found[X86]['hand']['hands'], found[X86]['astronaut']['faces']
    if not (hands and hands[0].score > 0.9 and len(faces) == 1
            and found[X86]['horse']['hands'] and found[X86]['horse']['hands'][0].score < 0.5):
        problems.append('the photographs no longer give a hand, a face and a mistaken palm')
    return lines, problems


def _seconds(about) -> float:
    return sum(sum(times) for times in about['seconds'].values())


def test_the_aarch64_build_gives_what_x86_64_gives(runs):
    about = runs['about']
    assert about[AARCH64]['machine'] == 'aarch64', about[AARCH64]
    assert about[X86]['machine'] == 'x86_64', about[X86]
    for runtime in (AARCH64, X86):
        assert (about[runtime]['tflite_runtime'], about[runtime]['numpy']) \
            == ('2.14.0', '1.23.3'), about[runtime]
    rows = list(_differences(runs))
    table = _table(rows)
    lines, problems = _decoded_problems(runs)
    print('\n%d inputs; the runs took %.0f s in the aarch64 build under QEMU, %.1f s in the '
          'x86-64 build\n\nmax |a - b| per output (LRT: LiteRT)\n%s\n\ndecoded: how many '
          'found, then the largest difference of aarch64 and the others (pixels, score)\n%s'
          % (sum(len(model.tensors) for model in runs['models'].values()),
             _seconds(about[AARCH64]), _seconds(about[X86]), table, '\n'.join(lines)))
    problems += ['%s %s %s: beyond %g of its largest magnitude' % (row[:3] + (RTOL,))
                 for row in rows if not row[5]]
    assert len(rows) >= 20 and not problems, '\n'.join(problems + [table] + lines)
    # Not a runtime compared with itself: the two builds differ where their kernels do.
    assert any(row[3][AARCH64, X86] > 0 for row in rows), table


def _recipe():
    """Return (wheel file name, sha256) of petalinux's recipe, or None without one."""
    recipes = sorted(RECIPES.glob('python3-tflite-runtime_*.bb'))
    if not recipes:
        return None
    text = recipes[0].read_text()
    url = re.search(r'^SRC_URI\s*=\s*"([^";\s]+)', text, re.M)
    digest = re.search(r'^SRC_URI\[sha256sum\]\s*=\s*"([0-9a-f]{64})"', text, re.M)
    assert url and digest, '%s: no one-line SRC_URI and SRC_URI[sha256sum]' % recipes[0]
    return url.group(1).rsplit('/', 1)[-1], digest.group(1)


def test_the_wheel_of_the_image_is_the_one_compared(cache):
    recipe = _recipe()
    if recipe is None:
        pytest.skip('no tflite-runtime recipe in %s: scripts/aarch64_root.sh checked its own '
                    'sha256 pin' % RECIPES.relative_to(REPO))
    wheel = cache / 'wheels' / IMAGE_WHEEL
    assert recipe == (IMAGE_WHEEL, hashlib.sha256(wheel.read_bytes()).hexdigest()), (
        'the image installs %s, scripts/aarch64_root.sh fetched %s: make them the same'
        % (recipe, IMAGE_WHEEL))


# The AArch64 instructions whose operand is an address relative to where the code is (it
# differs between two links of the same code): B and BL, ADR and ADRP, the ADD and the
# LDR/STR that take an address's low 12 bits, LDR of a literal. (mask, value, kept bits).
_RELATIVE = ((0x7c000000, 0x14000000, 0xfc000000), (0x1f000000, 0x10000000, 0x9f00001f),
             (0xffc00000, 0x91000000, 0xffc003ff), (0x3b000000, 0x39000000, 0xffc003ff),
             (0x3b000000, 0x18000000, 0xff00001f))
_BRANCH = 0x14000000


def _code_words(code: bytes):
    """Return an AArch64 function's instructions with their relative addresses left out."""
    words = []
    for word in struct.unpack('<%dI' % (len(code) // 4), code[:len(code) // 4 * 4]):
        for mask, value, kept in _RELATIVE:
            if word & mask == value:
                word &= kept
                break
        words.append(word)
    return tuple(words)


def _functions(library: bytes):
    """Return {symbol: [instructions, ...]} of an ELF64 AArch64 library's defined functions."""
    assert library[:6] == b'\x7fELF\x02\x01' and struct.unpack_from('<H', library, 18)[0] == 183
    offset = struct.unpack_from('<Q', library, 0x28)[0]
    size, count = struct.unpack_from('<HH', library, 0x3a)
    # (name, type, flags, address, offset, size, link, info, align, entry size)
    sections = [struct.unpack_from('<IIQQQQIIQQ', library, offset + number * size)
                for number in range(count)]
    symbols = next(section for section in sections if section[1] == 2)  # SHT_SYMTAB
    names = sections[symbols[6]][4]
    found = collections.defaultdict(list)
    for number in range(symbols[5] // 24):
        name, info, _, index, address, length = struct.unpack_from(
            '<IBBHQQ', library, symbols[4] + 24 * number)
        if info & 0xf != 2 or not 0 < index < count or not length:  # STT_FUNC, defined
            continue
        name = library[names + name:library.index(b'\0', names + name)].decode()
        start = sections[index][4] + address - sections[index][3]
        found[name].append(_code_words(library[start:start + length]))
    return found


def _same_code(one, other) -> bool:
    """Whether two functions are the same code, one of them patched by the linker."""
    if len(one) != len(other):
        return False
    # Cortex-A53 erratum 843419: the linker replaces an ADRP-based load that lands at certain
    # page offsets by a branch to a copy of it; where that happens depends on the layout.
    return all(a == b or _BRANCH in (a, b) for a, b in zip(one, other))


def _all_same(ones, others) -> bool:
    """Whether the functions of one name (static ones may share it) are the same code."""
    return len(ones) == len(others) and all(
        _same_code(a, b) for a, b in zip(sorted(ones), sorted(others)))


def test_the_wheel_run_here_is_the_image_build(cache):
    with zipfile.ZipFile(cache / 'wheels' / IMAGE_WHEEL) as wheel:
        image = _functions(wheel.read(LIBRARY))
    with zipfile.ZipFile(cache / 'wheels' / RUN_WHEEL) as wheel:
        here = _functions(wheel.read(LIBRARY))
    # TensorFlow Lite (tflite::), its kernels' libraries (XNNPACK, ruy, Eigen, gemmlowp) and
    # its thread pool; the Python binding (interpreter_wrapper, pybind11) is built per Python.
    engine = re.compile(r'^(_ZN|_ZNK)(6tflite|3ruy|5Eigen|8gemmlowp)|^(xnn_|pthreadpool)')
    names = [name for name in image if engine.match(name) and 'interpreter_wrapper' not in name]
    different = [name for name in names if not _all_same(image[name], here.get(name, []))]
    assert len(names) > 3000, 'found only %d functions of TensorFlow Lite' % len(names)
    assert not different, '%d of %d functions differ: %s' % (
        len(different), len(names), different[:10])
    print('\n%d functions of TensorFlow Lite and XNNPACK, the same code in %s and %s'
          % (len(names), IMAGE_WHEEL, RUN_WHEEL))
