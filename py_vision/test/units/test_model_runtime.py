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
The model runtimes: both .tflite runtimes where installed, ONNX through OpenCV, each error.

Also the outputs found by name (find_outputs), and quantised models, fed and read in float:
an ONNX one (onnx_model: QDQ at its edges) through OpenCV's DNN and onnxruntime, a .tflite one
(tflite_model) through LiteRT and tflite_runtime, against the same computation in numpy.
"""

import hashlib
import importlib.util
import os
import re
import sys
from types import SimpleNamespace

import numpy as np
import onnx_model
from py_vision.models import faces, hands, palm
from py_vision.models.files import SHIPPED, shipped_model
from py_vision.models.onnx_graph import read_signature
from py_vision.models.runtime import find_outputs, load, ModelError, RuntimeMissing, TensorInfo
import pytest
import tflite_model

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
    assert model.inputs == (TensorInfo('input', (1, 128, 128, 3), np.dtype(np.float32)),)
    assert [info.shape for info in model.outputs] == [(1, 896, 16), (1, 896, 1)]
    # A float model: no scale, zero point 0.
    assert all(info.scale is None and info.zero_point == 0 for info in model.outputs)
    regressors, scores = model.run(np.zeros((1, 128, 128, 3), np.float32))
    assert regressors.shape == (1, 896, 16) and scores.shape == (1, 896, 1)
    assert np.all(np.isfinite(regressors))
    # A grey picture has no face: every anchor's logit says so.
    assert scores.max() < 0
    # A run's outputs are the caller's: the next run (another picture) leaves them as they were.
    kept = [output.copy() for output in (regressors, scores)]
    model.run(np.ones((1, 128, 128, 3), np.float32))
    assert all(np.array_equal(output, copy) for output, copy in zip((regressors, scores), kept))


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
    assert model.inputs == (TensorInfo('x', (1, 3, 4, 4), np.dtype(np.float32)),)
    assert model.outputs == (TensorInfo('y', (1, 3, 4, 4), np.dtype(np.float32)),)
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
    assert 'no TensorFlow Lite runtime: pip install ai-edge-litert (PC), or on a board ' \
        "the image's python3-tflite-runtime (petalinux/enable_ros.py)" in one_line_naming(
            raised.value, FACE)


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


# The shipped models' outputs, as the runtimes read them: the names the steps look them up by.
SHIPPED_OUTPUTS = {
    'palm_detection_lite.tflite': [('Identity', (1, 2016, 18)), ('Identity_1', (1, 2016, 1))],
    'hand_landmark_lite.tflite': [('Identity', (1, 63)), ('Identity_1', (1, 1)),
                                  ('Identity_2', (1, 1)), ('Identity_3', (1, 63))],
    'face_detection_short_range.tflite': [('regressors', (1, 896, 16)),
                                          ('classificators', (1, 896, 1))],
}


# What the steps look for in each file: (names, shape) of each output they read.
STEPS_WANT = {palm.MODEL_FILE: palm._MODEL.outputs, hands.LANDMARK_FILE: hands._OUTPUTS,
              faces.MODEL_FILE: faces._MODEL.outputs}


@pytest.mark.parametrize('name', SHIPPED)
def test_the_shipped_models_outputs_have_the_names_the_steps_read(name):
    model = load(shipped_model(name))
    assert [(info.name, info.shape) for info in model.outputs] == SHIPPED_OUTPUTS[name]
    assert all(info.dtype == np.float32 and info.scale is None for info in model.outputs)
    # Each output a step reads is found by one of its names, not by position.
    names = [info.name for info in model.outputs]
    assert all(set(wanted) & set(names) for wanted, _ in STEPS_WANT[name]), names


def fake_model(*outputs):
    """Return a model of one (1, 8) input and these (name, shape) outputs, for find_outputs."""
    return SimpleNamespace(path='fake.onnx', inputs=(TensorInfo('x', (1, 8), np.float32),),
                           outputs=tuple(TensorInfo(name, shape, np.float32)
                                         for name, shape in outputs))


WANTED = [(('presence', 'flag'), (1, 1)), (('handedness',), (1, 1)), (('points',), (1, 9))]


def test_find_outputs_by_name_in_any_order():
    model = fake_model(('points', (1, 9)), ('handedness', (1, 1)), ('flag', (1, 1)))
    assert find_outputs(model, [(1, 8)], WANTED) == (2, 1, 0)


def test_find_outputs_by_position_where_the_names_are_unknown():
    model = fake_model(('a', (1, 1)), ('b', (1, 1)), ('c', (1, 9)), ('d', (1, 4)))
    assert find_outputs(model, [(1, 8)], WANTED) == (0, 1, 2)
    # Some names known, not all: by position too.
    model = fake_model(('presence', (1, 1)), ('b', (1, 1)), ('c', (1, 9)))
    assert find_outputs(model, [(1, 8)], WANTED) == (0, 1, 2)


@pytest.mark.parametrize('outputs', [
    [('presence', (1, 1)), ('handedness', (1, 1)), ('points', (1, 10))],  # by name, wrong shape
    [('a', (1, 9)), ('b', (1, 1)), ('c', (1, 1))],  # by position, wrong order of shapes
    [('a', (1, 1)), ('b', (1, 1))],  # too few
])
def test_find_outputs_refuses_another_model(outputs):
    with pytest.raises(ModelError, match='fake.onnx: not the model expected here'):
        find_outputs(fake_model(*outputs), [(1, 8)], WANTED)


def test_find_outputs_refuses_another_input():
    model = fake_model(('presence', (1, 1)), ('handedness', (1, 1)), ('points', (1, 9)))
    with pytest.raises(ModelError, match=r'fake.onnx: not the model expected here: its inputs '
                                         r'are \(\(1, 8\),\)'):
        find_outputs(model, [(1, 9)], WANTED)


@pytest.mark.parametrize('form', ['raw', 'typed', 'constants'])
def test_an_onnx_models_quantization_is_read_from_its_edge_nodes(form):
    inputs, outputs = read_signature(onnx_model.quantized_model_bytes(form))
    assert [(name, dtype, zero) for name, _, dtype, _, zero in inputs + outputs] == [
        ('xq', np.int8, -5), ('yq', np.uint8, 12)]
    assert [scale for *_, scale, _ in inputs + outputs] == pytest.approx([0.04, 0.03])


@pytest.mark.parametrize('runtime', ['opencv', 'onnxruntime'])
@pytest.mark.parametrize('form', ['raw', 'typed', 'constants'])
def test_a_quantized_onnx_model_is_fed_and_read_in_float(tmp_path, runtime, form):
    needs(runtime)
    path = onnx_model.write(str(tmp_path / 'quantized.onnx'),
                            onnx_model.quantized_model_bytes(form))
    model = load(path, runtime=runtime)
    (xq,), (yq,) = model.inputs, model.outputs
    assert (xq.name, xq.dtype, xq.zero_point) == ('xq', np.int8, onnx_model.X_QUANT[1])
    assert (yq.name, yq.dtype, yq.zero_point) == ('yq', np.uint8, onnx_model.Y_QUANT[1])
    assert (xq.scale, yq.scale) == pytest.approx((onnx_model.X_QUANT[0], onnx_model.Y_QUANT[0]))
    # Wide enough to reach both ends of int8 in and uint8 out.
    x = np.random.default_rng(5).normal(scale=3, size=onnx_model.INPUT_SHAPE).astype(np.float32)
    want = onnx_model.expected_quantized(x)
    assert want.min() == 0 and want.max() == pytest.approx((255 - 12) * 0.03)
    (y,) = model.run(x)
    assert y.dtype == np.float32
    np.testing.assert_allclose(y, want, rtol=0, atol=1e-6)
    # Integers of the input's own type go in as they are: already quantised.
    (again,) = model.run(onnx_model.quantize(x, onnx_model.X_QUANT, np.int8))
    np.testing.assert_allclose(again, want, rtol=0, atol=1e-6)


@pytest.mark.parametrize('runtime', ['opencv', 'onnxruntime'])
def test_an_integer_input_without_a_scale_takes_integers(tmp_path, runtime):
    # An int8 input read by a Cast, not a DequantizeLinear: plain integers, not quantised.
    needs(runtime)
    path = onnx_model.write(str(tmp_path / 'integers.onnx'),
                            onnx_model.integer_input_model_bytes())
    model = load(path, runtime=runtime)
    assert model.inputs[0].scale is None and model.inputs[0].dtype == np.int8
    with pytest.raises(ModelError, match="input 0 'xq' wants int8 values, got float32"):
        model.run(np.zeros(onnx_model.INPUT_SHAPE, np.float32))
    values = np.arange(-24, 24, dtype=np.int8).reshape(onnx_model.INPUT_SHAPE)
    np.testing.assert_array_equal(model.run(values)[0], values.astype(np.float32))


@pytest.mark.parametrize('runtime', ['litert', 'tflite_runtime'])
def test_a_quantized_tflite_model_is_fed_and_read_in_float(tmp_path, runtime):
    needs(runtime)
    model = load(tflite_model.write(str(tmp_path / 'quantized.tflite')), runtime=runtime)
    (xq,), (yq,) = model.inputs, model.outputs
    assert (xq.name, xq.shape, xq.dtype, xq.zero_point) == (
        'xq', tflite_model.INPUT_SHAPE, np.int8, tflite_model.X_QUANT[1])
    assert (yq.name, yq.dtype, yq.zero_point) == ('yq', np.uint8, tflite_model.Y_QUANT[1])
    assert (xq.scale, yq.scale) == pytest.approx((tflite_model.X_QUANT[0],
                                                  tflite_model.Y_QUANT[0]))
    x = np.random.default_rng(6).normal(scale=3, size=tflite_model.INPUT_SHAPE)
    want = tflite_model.expected(x)
    # Both ends reached: the input's int8 at 127, the output's uint8 at 0.
    assert (want.min(), want.max()) == pytest.approx(((0 - 12) * 0.03, (127 + 5) * 0.04))
    (y,) = model.run(x)
    assert y.dtype == np.float32
    np.testing.assert_allclose(y, want, rtol=0, atol=1e-6)


@pytest.mark.parametrize('runtime', ['litert', 'tflite_runtime'])
def test_a_tflite_input_quantized_per_channel_is_refused(tmp_path, runtime):
    needs(runtime)
    path = tflite_model.write(str(tmp_path / 'per_channel.tflite'), channels=4)
    with pytest.raises(ModelError) as raised:
        load(path, runtime=runtime)
    assert "'xq' is quantised per channel (4 scales)" in one_line_naming(raised.value, path)
