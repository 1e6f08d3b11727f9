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
Model runtimes: load a model file and run it, whichever runtime is installed.

`load(path)` picks the runtime by the file's extension: `.tflite` through LiteRT
(`ai_edge_litert`, pip install ai-edge-litert on a PC) or `tflite_runtime` (on the boards: the
image's python3-tflite-runtime, which petalinux/enable_ros.py adds); `.onnx` through
onnxruntime where installed, else OpenCV's DNN module (the boards' OpenCV 4.6 has it). Every
runtime is optional: a missing one is a `RuntimeMissing` naming the package to install. A file
that is missing, empty, truncated or not a model is a `ModelError` whose one-line message names
the file and what is wrong.

The loaded `Model` says what it is (`runtime`, `inputs`, `outputs`: each a `TensorInfo`, with
its name in the file) and checks the arrays it is given against its inputs before running. A
Model is not thread-safe: one thread runs it.

Quantised models: an input or output with a scale (int8, uint8: `TensorInfo.scale` and
`zero_point`) is fed and read in float, here, whatever the runtime: `run()` (`RuntimeModel`,
which every runtime's model shares) quantises float values for such an input (`quantize`:
round(x / scale) + zero point, to the nearest, half to even, clipped to the type's range;
values already of the input's own type go in as they are) and returns such an output
dequantised to float32 (`dequantize`: (q - zero point) * scale). So the steps' pre- and
post-processing is the same for a float and a quantised model. A .tflite file's scale and zero
point are its tensors' (per tensor; an input or output quantised per channel is refused); an
.onnx file's are read by onnx_graph (its QDQ convention).

Each run's model proper (the interpreter's invoke, the session's run, the network's forward
pass) is timed for the thread that runs it (`model_time`): vision_step splits a frame's time
into its models' and the rest with it.

`find_outputs` checks that a model is the one a step expects and finds the outputs it reads by
their names, in whatever order the file lists them (by position where the names are unknown).

`threads` above 1 pays only on cores nothing else needs: on this project's 2-core test machine
at a load of about 10, tflite_runtime 2.14 ran the palm model in 169 ms (p50) with 2 threads
against 11 ms with 1 (its threads wait for each other); LiteRT 2.3 took about 10 ms either way
(bench/bench_models.py).
"""

from dataclasses import dataclass
import importlib
import os
import subprocess
import sys
from typing import Callable, Dict, List, Optional, Protocol, Sequence, Tuple

import numpy as np
from py_vision.models.model_time import timing
from py_vision.models.onnx_graph import OnnxFormatError, read_signature, without_edge_quantization

__all__ = ['dequantize', 'find_outputs', 'load', 'Model', 'ModelError', 'quantize', 'RUNTIMES',
           'RuntimeMissing', 'TensorInfo']


class ModelError(Exception):
    """A model that cannot be loaded or run; the message is one line naming the file."""


class RuntimeMissing(ModelError):
    """The runtime a model needs is not installed; the message names the package to install."""


@dataclass(frozen=True)
class TensorInfo:
    """
    One input or output of a model, as its file says.

    name; shape (-1 where open); dtype, the element type in the model; scale and zero_point of
    a quantised tensor (value = (q - zero_point) * scale), None and 0 where it is not one.
    """

    name: str
    shape: Tuple[int, ...]
    dtype: np.dtype
    scale: Optional[float] = None
    zero_point: int = 0


class Model(Protocol):
    """A loaded model: what it is, and `run`, which checks its inputs and returns its outputs."""

    path: str
    runtime: str
    threads: int
    inputs: Tuple[TensorInfo, ...]
    outputs: Tuple[TensorInfo, ...]

    def run(self, *arrays: np.ndarray) -> List[np.ndarray]:
        """
        Run on one array per input (checked); return one array per output, in order.

        A quantised input takes float values (quantised with its scale and zero point) or
        values of its own type (as they are); a quantised output comes back dequantised, as
        float32.
        """


def quantize(values: np.ndarray, info: TensorInfo) -> np.ndarray:
    """Return float values as a quantised tensor's integers: round(x / scale) + zero point."""
    limits = np.iinfo(info.dtype)
    steps = np.round(np.asarray(values, np.float32) / np.float32(info.scale))
    return np.clip(steps + info.zero_point, limits.min, limits.max).astype(info.dtype)


def dequantize(values: np.ndarray, info: TensorInfo) -> np.ndarray:
    """Return a quantised tensor's integers as the float32 values they stand for."""
    return ((np.asarray(values).astype(np.int32) - info.zero_point)
            * np.float32(info.scale)).astype(np.float32)


# The runtimes by the extension they load, in the order 'auto' tries them.
RUNTIMES: Dict[str, Tuple[str, ...]] = {
    '.tflite': ('litert', 'tflite_runtime'),
    '.onnx': ('onnxruntime', 'opencv'),
}

_PACKAGES = {
    'litert': 'ai-edge-litert',
    'tflite_runtime': 'tflite-runtime',
    'onnxruntime': 'onnxruntime',
    'opencv': "opencv-python-headless (or the distribution's OpenCV)",
}

_NONE_INSTALLED = {
    '.tflite': 'no TensorFlow Lite runtime: pip install ai-edge-litert (PC), or on a board '
               "the image's python3-tflite-runtime (petalinux/enable_ros.py)",
    '.onnx': 'no ONNX runtime: pip install onnxruntime, or install OpenCV with its DNN module',
}


def _one_line(error: BaseException) -> str:
    """Return a runtime's exception as one line: its last line (OpenCV's is the reason)."""
    lines = [line.strip() for line in str(error).splitlines() if line.strip()]
    return lines[-1] if lines else type(error).__name__


def _check_arrays(model: 'Model', arrays: Sequence[np.ndarray]) -> List[np.ndarray]:
    """Return the arrays, cast where safe, or raise ModelError saying which one is wrong."""
    name = os.path.basename(model.path)
    if len(arrays) != len(model.inputs):
        raise ModelError('%s: takes %d input(s), got %d'
                         % (name, len(model.inputs), len(arrays)))
    checked = []
    for number, (array, info) in enumerate(zip(arrays, model.inputs)):
        array = np.asarray(array)
        shape = tuple(array.shape)
        fits = len(shape) == len(info.shape) and all(
            want < 0 or want == got for want, got in zip(info.shape, shape))
        if not fits:
            raise ModelError("%s: input %d '%s' wants shape %s, got %s"
                             % (name, number, info.name, _shape_text(info.shape), shape))
        if array.dtype != info.dtype:
            if info.scale is not None and array.dtype.kind in 'biuf':
                array = quantize(array, info)
            elif not np.can_cast(array.dtype, info.dtype, 'same_kind'):
                raise ModelError("%s: input %d '%s' wants %s values, got %s"
                                 % (name, number, info.name, info.dtype, array.dtype))
            else:
                array = array.astype(info.dtype)
        checked.append(np.ascontiguousarray(array))
    return checked


def find_outputs(model: Model, inputs: Sequence[Tuple[int, ...]],
                 outputs: Sequence[Tuple[Sequence[str], Tuple[int, ...]]]) -> Tuple[int, ...]:
    """
    Check that the model is the one expected; return where each wanted output is in its outputs.

    inputs: the input shapes; outputs: (names, shape) of each output to be read, names being
    what it is called in the files known. By name where each wanted output has one of its
    names among the model's outputs (a model exported again may list them in another order);
    else, as for a file whose names are unknown, by position: the first len(outputs). Raises
    ModelError unless the inputs and the outputs found have these shapes.
    """
    got_in = tuple(tuple(info.shape) for info in model.inputs)
    got_out = tuple(tuple(info.shape) for info in model.outputs)
    want_in = tuple(map(tuple, inputs))
    want_out = tuple(tuple(shape) for _, shape in outputs)
    where = {info.name: index for index, info in enumerate(model.outputs)}
    by_name = [next((where[name] for name in names if name in where), None)
               for names, _ in outputs]
    if None in by_name or len(set(by_name)) != len(by_name):
        by_name = list(range(min(len(outputs), len(got_out))))
    found = tuple(got_out[index] for index in by_name)
    if got_in != want_in or found != want_out:
        raise ModelError('%s: not the model expected here: its inputs are %s and outputs %s, '
                         'expected %s and %s' % (model.path, got_in, got_out, want_in, want_out))
    return tuple(by_name)


def _shape_text(shape: Tuple[int, ...]) -> str:
    return '(%s)' % ', '.join('?' if size < 0 else str(size) for size in shape)


class RuntimeModel(Model):
    """
    What every runtime shares: run() checks and quantises the inputs, dequantises the outputs.

    A runtime sets Model's path, runtime, threads, inputs and outputs, and implements
    `_invoke`: run once on one array per input, each of that input's shape and own type, and
    return the outputs as the model gives them, in order.
    """

    def run(self, *arrays: np.ndarray) -> List[np.ndarray]:
        results = self._invoke(_check_arrays(self, arrays))
        return [result if info.scale is None else dequantize(result, info)
                for info, result in zip(self.outputs, results)]

    def _invoke(self, arrays: List[np.ndarray]) -> List[np.ndarray]:
        raise NotImplementedError


class _TfliteModel(RuntimeModel):
    """A .tflite model in LiteRT's or tflite_runtime's interpreter (the same Python API)."""

    def __init__(self, path: str, threads: int, interpreter_module, runtime: str):
        self.path = path
        self.runtime = runtime
        self.threads = threads
        try:
            self._interpreter = interpreter_module.Interpreter(model_path=path,
                                                               num_threads=threads)
            self._interpreter.allocate_tensors()
        except (ValueError, RuntimeError) as error:
            raise ModelError('%s: %s cannot load it: %s'
                             % (path, runtime, _one_line(error))) from None
        self._input_details = self._interpreter.get_input_details()
        self._output_details = self._interpreter.get_output_details()
        self.inputs = tuple(_tflite_info(path, detail) for detail in self._input_details)
        self.outputs = tuple(_tflite_info(path, detail) for detail in self._output_details)

    def _invoke(self, arrays: List[np.ndarray]) -> List[np.ndarray]:
        for detail, array in zip(self._input_details, arrays):
            self._interpreter.set_tensor(detail['index'], array)
        with timing():
            self._interpreter.invoke()
        # get_tensor returns a copy of its own (LiteRT and tflite_runtime alike): not copied
        # again (the palm detector's 150 kB a frame).
        return [self._interpreter.get_tensor(detail['index'])
                for detail in self._output_details]


def _tflite_info(path: str, detail: dict) -> TensorInfo:
    signature = detail.get('shape_signature')
    shape = signature if signature is not None and len(signature) else detail['shape']
    dtype = np.dtype(detail['dtype'])
    scales = detail.get('quantization_parameters', {}).get('scales', ())
    if len(scales) > 1:
        raise ModelError("%s: '%s' is quantised per channel (%d scales): py_vision feeds and "
                         'reads inputs and outputs quantised per tensor only'
                         % (path, detail['name'], len(scales)))
    scale, zero_point = detail.get('quantization', (0.0, 0))
    if dtype.kind not in 'iu' or not scale > 0:
        scale, zero_point = None, 0
    return TensorInfo(detail['name'], tuple(int(size) for size in shape), dtype,
                      None if scale is None else float(scale), int(zero_point))


def _signature(path: str) -> Tuple[Tuple[TensorInfo, ...], Tuple[TensorInfo, ...], bytes]:
    """Return an .onnx file's inputs and outputs, and its contents."""
    with open(path, 'rb') as model_file:
        data = model_file.read()
    try:
        inputs, outputs = read_signature(data)
    except OnnxFormatError as error:
        raise ModelError('%s: not an ONNX model (the file %s)' % (path, error)) from None
    return (tuple(TensorInfo(*item) for item in inputs),
            tuple(TensorInfo(*item) for item in outputs), data)


class _OnnxruntimeModel(RuntimeModel):
    """An .onnx model in an onnxruntime session on the CPU."""

    def __init__(self, path: str, threads: int, onnxruntime):
        self.path = path
        self.runtime = 'onnxruntime %s' % onnxruntime.__version__
        self.threads = threads
        self.inputs, self.outputs, _ = _signature(path)
        options = onnxruntime.SessionOptions()
        options.intra_op_num_threads = threads
        options.inter_op_num_threads = 1
        try:
            self._session = onnxruntime.InferenceSession(
                path, sess_options=options, providers=['CPUExecutionProvider'])
        except Exception as error:  # onnxruntime's own exception classes, not importable alike
            raise ModelError('%s: onnxruntime cannot load it: %s'
                             % (path, _one_line(error))) from None

    def _invoke(self, arrays: List[np.ndarray]) -> List[np.ndarray]:
        feed = {info.name: array for info, array in zip(self.inputs, arrays)}
        with timing():
            return list(self._session.run([info.name for info in self.outputs], feed))


class _OpencvModel(RuntimeModel):
    """
    An .onnx model in OpenCV's DNN module.

    OpenCV's DNN runs on OpenCV's own thread pool, which the whole process shares
    (cv2.setNumThreads): the model does not change it, and `threads` says what it is.

    A model with quantised inputs or outputs runs without its edge DequantizeLinear and
    QuantizeLinear nodes (onnx_graph.without_edge_quantization), which are done here with the
    same numbers: OpenCV 4.6 returns garbage for a QuantizeLinear's output and shifts a uint8
    input's zero point by 128 (measured with the tests' quantised model), OpenCV 5 does not.
    """

    def __init__(self, path: str, threads: int, cv2):
        self.path = path
        self.runtime = 'OpenCV DNN %s' % cv2.__version__
        self.inputs, self.outputs, data = _signature(path)
        self._renamed: Dict[str, str] = {}
        try:
            if any(info.scale is not None for info in self.inputs + self.outputs):
                data, self._renamed = without_edge_quantization(data)
                self._net = cv2.dnn.readNetFromONNX(np.frombuffer(data, np.uint8))
            else:
                self._net = cv2.dnn.readNetFromONNX(path)
        except cv2.error as error:
            raise ModelError('%s: OpenCV DNN cannot load it: %s'
                             % (path, _one_line(error))) from None
        self.threads = max(1, cv2.getNumThreads())
        self._error = cv2.error

    def _invoke(self, arrays: List[np.ndarray]) -> List[np.ndarray]:
        for info, array in zip(self.inputs, arrays):
            if info.name in self._renamed:
                self._net.setInput(dequantize(array, info), self._renamed[info.name])
            else:
                self._net.setInput(array, info.name)
        try:
            with timing():
                results = self._net.forward([self._renamed.get(info.name, info.name)
                                             for info in self.outputs])
        except self._error as error:
            raise ModelError('%s: OpenCV DNN cannot run it: %s'
                             % (self.path, _one_line(error))) from None
        return [quantize(result, info) if info.name in self._renamed else np.asarray(result)
                for info, result in zip(self.outputs, results)]


def _import(module: str):
    try:
        return importlib.import_module(module)
    except ImportError:
        return None


def _version(distribution: str, module) -> str:
    version = getattr(module, '__version__', None)
    if version is None:
        try:
            from importlib.metadata import version as installed_version
            version = installed_version(distribution)
        except Exception:  # no metadata (a source install): say so rather than fail
            version = '(version unknown)'
    return version


def _litert(path: str, threads: int) -> Optional[Model]:
    interpreter = _import('ai_edge_litert.interpreter')
    if interpreter is None:
        return None
    package = _import('ai_edge_litert')
    return _TfliteModel(path, threads, interpreter,
                        'LiteRT %s' % _version('ai-edge-litert', package))


# tflite_runtime (2.14) does not verify a model file before using it: a truncated or damaged
# one crashes the process (SIGSEGV) instead of raising. So the file is loaded once in a
# process of its own first; LiteRT verifies, and needs no such probe.
_PROBE = ('import sys\n'
          'from tflite_runtime.interpreter import Interpreter\n'
          'Interpreter(model_path=sys.argv[1]).allocate_tensors()\n')
_PROBE_TIMEOUT = 300.0


def _probe_tflite_runtime(path: str) -> None:
    """Raise ModelError when loading the file crashes tflite_runtime in a process of its own."""
    try:
        result = subprocess.run([sys.executable, '-c', _PROBE, path], stdin=subprocess.DEVNULL,
                                stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                                timeout=_PROBE_TIMEOUT)
    except (OSError, subprocess.TimeoutExpired):
        return  # no verdict: the load in this process says what it says
    if result.returncode < 0:
        raise ModelError('%s: tflite_runtime crashes loading it (signal %d): the file is '
                         'truncated or damaged' % (path, -result.returncode))


def _tflite_runtime(path: str, threads: int) -> Optional[Model]:
    interpreter = _import('tflite_runtime.interpreter')
    if interpreter is None:
        return None
    _probe_tflite_runtime(path)
    package = _import('tflite_runtime')
    return _TfliteModel(path, threads, interpreter,
                        'tflite_runtime %s' % _version('tflite-runtime', package))


def _onnxruntime(path: str, threads: int) -> Optional[Model]:
    onnxruntime = _import('onnxruntime')
    return None if onnxruntime is None else _OnnxruntimeModel(path, threads, onnxruntime)


def _opencv(path: str, threads: int) -> Optional[Model]:
    cv2 = _import('cv2')
    if cv2 is None or not hasattr(cv2, 'dnn'):
        return None
    return _OpencvModel(path, threads, cv2)


_LOADERS: Dict[str, Callable[[str, int], Optional[Model]]] = {
    'litert': _litert,
    'tflite_runtime': _tflite_runtime,
    'onnxruntime': _onnxruntime,
    'opencv': _opencv,
}

# A .tflite file is a FlatBuffer with this identifier at bytes 4 to 8.
_TFLITE_IDENTIFIER = b'TFL3'


def _check_file(path: str, extension: str) -> None:
    if not os.path.exists(path):
        raise ModelError('%s: no such model file' % path)
    if not os.path.isfile(path):
        raise ModelError('%s: not a file' % path)
    size = os.path.getsize(path)
    if size == 0:
        raise ModelError('%s: empty file, not a model' % path)
    if extension == '.tflite':
        with open(path, 'rb') as model_file:
            head = model_file.read(8)
        if len(head) < 8 or head[4:8] != _TFLITE_IDENTIFIER:
            raise ModelError('%s: not a TensorFlow Lite model (no TFL3 identifier at its start)'
                             % path)


def load(path: str, threads: int = 1, runtime: str = 'auto') -> Model:
    """
    Load the model in `path` (.tflite or .onnx) with `threads` CPU threads.

    `runtime` is 'auto' (the first installed of RUNTIMES[extension]) or one of them by name
    ('litert', 'tflite_runtime' for .tflite; 'onnxruntime', 'opencv' for .onnx). Raises
    ModelError (RuntimeMissing when the runtime is not installed) with a one-line message.
    """
    path = os.fspath(path)
    extension = os.path.splitext(path)[1].lower()
    if extension not in RUNTIMES:
        raise ModelError('%s: not a model file py_vision can run (it runs %s)'
                         % (path, ' and '.join(sorted(RUNTIMES))))
    if isinstance(threads, bool) or not isinstance(threads, int) or threads < 1:
        raise ModelError('%s: threads must be a whole number of 1 or more, not %r'
                         % (path, threads))
    choices = RUNTIMES[extension]
    if runtime != 'auto' and runtime not in choices:
        raise ModelError("%s: runtime '%s' does not run %s files (choose auto, %s)"
                         % (path, runtime, extension, ', '.join(choices)))
    _check_file(path, extension)
    for name in choices if runtime == 'auto' else (runtime,):
        model = _LOADERS[name](path, threads)
        if model is not None:
            return model
    if runtime == 'auto':
        raise RuntimeMissing('%s: %s' % (path, _NONE_INSTALLED[extension]))
    raise RuntimeMissing("%s: runtime '%s' is not installed: pip install %s"
                         % (path, runtime, _PACKAGES[runtime]))
