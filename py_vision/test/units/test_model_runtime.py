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


"""The model runtimes: both .tflite runtimes where installed, ONNX through OpenCV, each error."""

import hashlib
import importlib.util
import os
import re
import sys

import numpy as np
import onnx_model
from py_vision.models.files import SHIPPED, shipped_model
from py_vision.models.runtime import load, ModelError, RuntimeMissing
import pytest

FACE = 'face_detection_short_range.tflite'
TFLITE_MODULES = {'litert': 'ai_edge_litert', 'tflite_runtime': 'tflite_runtime'}
RUNTIME_NAMES = {'litert': 'LiteRT ', 'tflite_runtime': 'tflite_runtime ',
                 'onnxruntime': 'onnxruntime ', 'opencv': 'OpenCV DNN '}


def installed(module):
    """Return whether a module can be imported (without importing it)."""
    return importlib.util.find_spec(module) is not None


def needs(runtime):
    """Skip, saying so, where this run does not have the runtime (each one is optional)."""
    modules = dict(TFLITE_MODULES, onnxruntime='onnxruntime', opencv='cv2')
    module = modules[runtime]
    if not installed(module):
        pytest.skip('%s is not installed in this run (%s)' % (runtime, sys.executable))


def one_line_naming(error, path):
    """Assert the message is one line that names the file."""
    message = str(error)
    assert '\n' not in message, message
    assert os.path.basename(path) in message, message
    return message


@pytest.fixture
def tiny_onnx(tmp_path):
    return onnx_model.write(str(tmp_path / 'tiny.onnx'))


def test_this_run_has_a_tflite_runtime():
    # The main run installs LiteRT (requirements.txt), the board-version run tflite_runtime.
    model = load(shipped_model(FACE))
    assert model.runtime.split()[0] in ('LiteRT', 'tflite_runtime')


@pytest.mark.parametrize('runtime', ['litert', 'tflite_runtime'])
def test_tflite_runtime_loads_and_runs_the_face_model(runtime):
    needs(runtime)
    model = load(shipped_model(FACE), threads=2, runtime=runtime)
    assert model.runtime.startswith(RUNTIME_NAMES[runtime])
    assert re.search(r' \d+\.\d+', model.runtime), model.runtime
    assert model.threads == 2
    assert model.path.endswith(FACE)
    assert [(info.name, info.shape, info.dtype) for info in model.inputs] == [
        ('input', (1, 128, 128, 3), np.dtype(np.float32))]
    assert [info.shape for info in model.outputs] == [(1, 896, 16), (1, 896, 1)]
    regressors, scores = model.run(np.zeros((1, 128, 128, 3), np.float32))
    assert regressors.shape == (1, 896, 16) and scores.shape == (1, 896, 1)
    assert np.all(np.isfinite(regressors))
    # A grey picture has no face: every anchor's logit says so.
    assert scores.max() < 0


@pytest.mark.parametrize('runtime', ['litert', 'tflite_runtime'])
def test_tflite_runtimes_check_the_input(runtime):
    needs(runtime)
    model = load(shipped_model(FACE), runtime=runtime)
    with pytest.raises(ModelError) as raised:
        model.run(np.zeros((1, 100, 128, 3), np.float32))
    message = one_line_naming(raised.value, FACE)
    assert "input 0 'input' wants shape (1, 128, 128, 3), got (1, 100, 128, 3)" in message
    with pytest.raises(ModelError, match=r'takes 1 input\(s\), got 2'):
        model.run(np.zeros((1, 128, 128, 3), np.float32), np.zeros(1))
    with pytest.raises(ModelError, match='wants float32 values, got complex64'):
        model.run(np.zeros((1, 128, 128, 3), np.complex64))
    # A float64 array is converted: the caller need not know the model's precision.
    assert model.run(np.zeros((1, 128, 128, 3)))[0].dtype == np.float32


@pytest.mark.parametrize('runtime', ['opencv', 'onnxruntime'])
def test_onnx_model_runs_and_computes_what_it_should(runtime, tiny_onnx):
    needs(runtime)
    model = load(tiny_onnx, runtime=runtime)
    assert model.runtime.startswith(RUNTIME_NAMES[runtime])
    assert [(info.name, info.shape) for info in model.inputs] == [('x', (1, 3, 4, 4))]
    assert [(info.name, info.shape) for info in model.outputs] == [('y', (1, 3, 4, 4))]
    x = np.random.default_rng(7).normal(size=onnx_model.INPUT_SHAPE).astype(np.float32)
    (y,) = model.run(x)
    np.testing.assert_allclose(y, onnx_model.expected(x), rtol=1e-6, atol=1e-6)
    with pytest.raises(ModelError, match=r"input 0 'x' wants shape \(1, 3, 4, 4\), got"):
        model.run(np.zeros((1, 3, 5, 4), np.float32))


def test_onnx_auto_prefers_onnxruntime_then_opencv(tiny_onnx):
    model = load(tiny_onnx)
    want = 'onnxruntime ' if installed('onnxruntime') else 'OpenCV DNN '
    assert model.runtime.startswith(want)


def write(path, data):
    with open(path, 'wb') as out:
        out.write(data)
    return str(path)


def test_missing_file(tmp_path):
    path = str(tmp_path / 'palm.tflite')
    with pytest.raises(ModelError) as raised:
        load(path)
    assert 'no such model file' in one_line_naming(raised.value, path)


@pytest.mark.parametrize('name', ['empty.tflite', 'empty.onnx'])
def test_empty_file(tmp_path, name):
    path = write(tmp_path / name, b'')
    with pytest.raises(ModelError) as raised:
        load(path)
    assert 'empty file, not a model' in one_line_naming(raised.value, path)


def test_text_renamed_tflite(tmp_path):
    path = write(tmp_path / 'notes.tflite', b'these are my notes, not a model\n')
    with pytest.raises(ModelError) as raised:
        load(path)
    assert 'not a TensorFlow Lite model' in one_line_naming(raised.value, path)


@pytest.mark.parametrize('runtime', ['litert', 'tflite_runtime'])
@pytest.mark.parametrize('keep', [100, 0.5, -1000])
def test_truncated_tflite(tmp_path, runtime, keep):
    # tflite_runtime crashes on these (no verifier): load() must say so, not crash.
    needs(runtime)
    with open(shipped_model('palm_detection_lite.tflite'), 'rb') as model_file:
        data = model_file.read()
    end = int(len(data) * keep) if isinstance(keep, float) else keep
    path = write(tmp_path / 'palm.tflite', data[:end])
    with pytest.raises(ModelError) as raised:
        load(path, runtime=runtime)
    message = one_line_naming(raised.value, path)
    assert re.search('cannot load it|the file is truncated or damaged', message), message
    assert not isinstance(raised.value, RuntimeMissing)


@pytest.mark.parametrize('contents, why', [
    (b'these are my notes, not a model\n', 'not an ONNX model'),
    (onnx_model.model_bytes()[:60], 'not an ONNX model (the file is truncated)'),
])
def test_not_an_onnx_model(tmp_path, contents, why):
    path = write(tmp_path / 'model.onnx', contents)
    with pytest.raises(ModelError) as raised:
        load(path)
    assert why in one_line_naming(raised.value, path)


def test_unknown_extension(tmp_path):
    path = write(tmp_path / 'model.pb', b'x')
    with pytest.raises(ModelError) as raised:
        load(path)
    assert 'runs .onnx and .tflite' in one_line_naming(raised.value, path)


@pytest.mark.parametrize('threads', [0, -1, 1.5, 'two', True])
def test_bad_threads(threads):
    with pytest.raises(ModelError, match='threads must be a whole number of 1 or more'):
        load(shipped_model(FACE), threads=threads)


def test_runtime_that_does_not_run_the_extension(tiny_onnx):
    with pytest.raises(ModelError) as raised:
        load(tiny_onnx, runtime='litert')
    assert "runtime 'litert' does not run .onnx files (choose auto, onnxruntime, opencv)" \
        in one_line_naming(raised.value, tiny_onnx)


@pytest.mark.parametrize('runtime, package', [('litert', 'ai-edge-litert'),
                                              ('tflite_runtime', 'tflite-runtime')])
def test_forced_runtime_not_installed_names_the_package(monkeypatch, runtime, package):
    # A module set to None in sys.modules cannot be imported: the runtime is missing.
    monkeypatch.setitem(sys.modules, TFLITE_MODULES[runtime], None)
    monkeypatch.setitem(sys.modules, TFLITE_MODULES[runtime] + '.interpreter', None)
    with pytest.raises(RuntimeMissing) as raised:
        load(shipped_model(FACE), runtime=runtime)
    message = one_line_naming(raised.value, FACE)
    assert "runtime '%s' is not installed: pip install %s" % (runtime, package) in message


def test_no_tflite_runtime_at_all_names_both_packages(monkeypatch):
    for module in TFLITE_MODULES.values():
        monkeypatch.setitem(sys.modules, module, None)
        monkeypatch.setitem(sys.modules, module + '.interpreter', None)
    with pytest.raises(RuntimeMissing) as raised:
        load(shipped_model(FACE))
    assert 'no TensorFlow Lite runtime: pip install ai-edge-litert (PC) or tflite-runtime ' \
        '(aarch64 board)' in one_line_naming(raised.value, FACE)


def test_no_onnx_runtime_at_all(monkeypatch, tiny_onnx):
    monkeypatch.setitem(sys.modules, 'onnxruntime', None)
    monkeypatch.setitem(sys.modules, 'cv2', None)
    with pytest.raises(RuntimeMissing) as raised:
        load(tiny_onnx)
    message = one_line_naming(raised.value, tiny_onnx)
    assert 'no ONNX runtime: pip install onnxruntime' in message


def test_shipped_models_are_the_ones_the_readme_lists():
    readme = os.path.join(os.path.dirname(shipped_model(FACE)), 'README.md')
    with open(readme) as text:
        listed = dict(re.findall(r'^\| `([\w.]+)` \|.*\| `([0-9a-f]{64})` \|$', text.read(),
                                 re.MULTILINE))
    assert sorted(listed) == sorted(SHIPPED)
    for name in SHIPPED:
        with open(shipped_model(name), 'rb') as model_file:
            assert hashlib.sha256(model_file.read()).hexdigest() == listed[name], name
    assert os.path.isfile(os.path.join(os.path.dirname(readme), 'LICENSE'))


def test_a_model_not_shipped_is_a_model_error():
    with pytest.raises(ModelError) as raised:
        shipped_model('hand_landmark_full.tflite')
    message = one_line_naming(raised.value, 'hand_landmark_full.tflite')
    assert 'no such model shipped with py_vision' in message
