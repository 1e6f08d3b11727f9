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
Small ONNX models written byte by byte (no onnx package), and what they compute in numpy.

- `model_bytes()`: y = Relu(x * scale + shift); x is (1, 3, 4, 4) float32, scale (1, 3, 1, 1)
  one factor per channel, shift one number; `expected(x)`.
- `quantized_model_bytes()`: the same computation between an int8 input and a uint8 output,
  in the QDQ form py_vision reads quantisation from: the input goes into a DequantizeLinear
  with constant scale and zero point (X_QUANT), the output comes out of a QuantizeLinear
  (Y_QUANT); `expected_quantized(x)` is what load() gives for float values x.
- `constant_model_bytes(input_name, input_shape, outputs)`: a model of another's signature
  (MediaPipe's, say) whose outputs, in the order given, are the constants given, whatever the
  input: each is a slice of the flattened input times 0 plus the constant; `one_detection`
  makes an SSD detector's two outputs for it.

Every one loads in OpenCV's DNN 4.6 and 5 and in onnxruntime. The field numbers are onnx.proto's.
"""

import numpy as np

SCALE = np.array([1.0, -2.0, 0.5], np.float32).reshape(1, 3, 1, 1)
SHIFT = np.array([0.25], np.float32)
INPUT_SHAPE = (1, 3, 4, 4)
# (scale, zero point) of the quantised model's int8 input and uint8 output.
X_QUANT = (0.04, -5)
Y_QUANT = (0.03, 12)
# TensorProto.DataType by numpy type.
DATA_TYPES = {np.dtype(np.float32): 1, np.dtype(np.uint8): 2, np.dtype(np.int8): 3,
              np.dtype(np.int64): 7}


def _varint(value):
    out = bytearray()
    while True:
        byte = value & 0x7F
        value >>= 7
        if value:
            out.append(byte | 0x80)
        else:
            out.append(byte)
            return bytes(out)


def _field(number, value):
    """Encode one field: an int as a varint, bytes or str as length-delimited."""
    if isinstance(value, int):
        return _varint(number << 3) + _varint(value & (1 << 64) - 1)
    if isinstance(value, str):
        value = value.encode()
    return _varint(number << 3 | 2) + _varint(len(value)) + value


def _tensor(name, array, typed=False):
    """Encode a TensorProto: its bytes in raw_data, or (typed) in float_data or int32_data."""
    array = np.asarray(array)
    dims = b''.join(_field(1, size) for size in array.shape)
    if not typed:
        data = _field(9, array.astype(array.dtype.newbyteorder('<')).tobytes())
    elif array.dtype == np.float32:
        data = _field(4, array.astype('<f4').tobytes())
    else:
        data = _field(5, b''.join(_varint(int(value) & (1 << 64) - 1)
                                  for value in array.ravel()))
    return dims + _field(2, DATA_TYPES[array.dtype]) + _field(8, name) + data


def _value_info(name, shape, dtype=np.float32):
    dims = b''.join(_field(1, _field(1, size)) for size in shape)
    tensor_type = _field(1, DATA_TYPES[np.dtype(dtype)]) + _field(2, dims)
    return _field(1, name) + _field(2, _field(1, tensor_type))


def _int_attribute(name, value):
    # AttributeProto: name 1, i 3, type 20 (INT = 2).
    return _field(1, name) + _field(3, value) + _field(20, 2)


def _tensor_attribute(name, array):
    # AttributeProto: name 1, t 5, type 20 (TENSOR = 4).
    return _field(1, name) + _field(5, _tensor(name, array)) + _field(20, 4)


def _node(inputs, outputs, op_type, name, attributes=()):
    return (b''.join(_field(1, item) for item in inputs)
            + b''.join(_field(2, item) for item in outputs)
            + _field(3, name) + _field(4, op_type)
            + b''.join(_field(5, attribute) for attribute in attributes))


def _model(nodes, initializers, inputs, outputs, opset=11, typed=False):
    graph = (b''.join(_field(1, node) for node in nodes)
             + _field(2, 'py_vision_test')
             + b''.join(_field(5, _tensor(name, array, typed)) for name, array in initializers)
             + b''.join(_field(11, _value_info(*item)) for item in inputs)
             + b''.join(_field(12, _value_info(*item)) for item in outputs))
    return (_field(1, 7) + _field(2, 'py_vision test') + _field(7, graph)
            + _field(8, _field(1, '') + _field(2, opset)))


def model_bytes(input_shape=INPUT_SHAPE):
    """Return the float model's file contents."""
    return _model([_node(['x', 'scale'], ['scaled'], 'Mul', 'mul'),
                   _node(['scaled', 'shift'], ['shifted'], 'Add', 'add'),
                   _node(['shifted'], ['y'], 'Relu', 'relu')],
                  [('scale', SCALE), ('shift', SHIFT)],
                  [('x', input_shape)], [('y', input_shape)])


def expected(x):
    """Return what the float model computes for x."""
    return np.maximum(x * SCALE + SHIFT, 0).astype(np.float32)


def quantized_model_bytes(form='raw'):
    """
    Return the quantised model's file contents: int8 in, uint8 out (QDQ).

    form: where the scales and zero points are: 'raw' (initializers' raw_data, as most
    exporters write them), 'typed' (initializers' float_data and int32_data) or 'constants'
    (Constant nodes).
    """
    quantization = [('x_scale', np.float32(X_QUANT[0])), ('x_zero', np.int8(X_QUANT[1])),
                    ('y_scale', np.float32(Y_QUANT[0])), ('y_zero', np.uint8(Y_QUANT[1]))]
    nodes = []
    if form == 'constants':
        nodes = [_node([], [name], 'Constant', name, [_tensor_attribute('value', value)])
                 for name, value in quantization]
        quantization = []
    nodes += [_node(['xq', 'x_scale', 'x_zero'], ['x'], 'DequantizeLinear', 'dequantize'),
              _node(['x', 'scale'], ['scaled'], 'Mul', 'mul'),
              _node(['scaled', 'shift'], ['shifted'], 'Add', 'add'),
              _node(['shifted'], ['y'], 'Relu', 'relu'),
              _node(['y', 'y_scale', 'y_zero'], ['yq'], 'QuantizeLinear', 'quantize')]
    return _model(nodes, [('scale', SCALE), ('shift', SHIFT)] + quantization,
                  [('xq', INPUT_SHAPE, np.int8)], [('yq', INPUT_SHAPE, np.uint8)], opset=13,
                  typed=form == 'typed')


def integer_input_model_bytes():
    """Return a model whose int8 input is plain integers: Cast to float, not dequantised."""
    return _model([_node(['xq'], ['y'], 'Cast', 'cast', [_int_attribute('to', 1)])], [],
                  [('xq', INPUT_SHAPE, np.int8)], [('y', INPUT_SHAPE)], opset=13)


def quantize(values, quant, dtype, rounding=np.round):
    """Return float values quantised as the ONNX kernels do (rounding: half to even)."""
    scale, zero = quant
    info = np.iinfo(dtype)
    return np.clip(rounding(np.asarray(values, np.float32) / np.float32(scale)) + zero,
                   info.min, info.max).astype(dtype)


def dequantize(values, quant):
    """Return quantised values as the floats they stand for."""
    scale, zero = quant
    return ((values.astype(np.int32) - zero) * np.float32(scale)).astype(np.float32)


def expected_quantized(x):
    """Return what load() gives from the quantised model for float values x."""
    xq = quantize(x, X_QUANT, np.int8)
    y = expected(dequantize(xq, X_QUANT))
    return dequantize(quantize(y, Y_QUANT, np.uint8), Y_QUANT)


def constant_model_bytes(input_name, input_shape, outputs):
    """Return a model with this input whose outputs [(name, array)] are those constants."""
    nodes = [_node([input_name], ['flat'], 'Flatten', 'flatten')]
    initializers = [('zero', np.float32(0)), ('starts', np.array([0], np.int64)),
                    ('axes', np.array([1], np.int64))]
    for name, value in outputs:
        value = np.asarray(value, np.float32)
        nodes += [_node(['flat', 'starts', name + '_end', 'axes'], [name + '_slice'], 'Slice',
                        name + '_slice'),
                  _node([name + '_slice', name + '_shape'], [name + '_shaped'], 'Reshape',
                        name + '_reshape'),
                  _node([name + '_shaped', 'zero'], [name + '_zeros'], 'Mul', name + '_mul'),
                  _node([name + '_zeros', name + '_value'], [name], 'Add', name + '_add')]
        initializers += [(name + '_end', np.array([value.size], np.int64)),
                         (name + '_shape', np.array(value.shape, np.int64)),
                         (name + '_value', value)]
    return _model(nodes, initializers, [(input_name, input_shape)],
                  [(name, np.shape(value)) for name, value in outputs])


def one_detection(anchors, width, index, size, keypoint, logit=3.0):
    """
    Return an SSD detector's (regressors, scores) with one anchor scoring: logit there, -10.

    Its box is `size` input pixels square around the anchor, its first keypoint `keypoint`
    (dx, dy) input pixels from it, the others on it.
    """
    regressors = np.zeros((1, len(anchors), width), np.float32)
    regressors[0, index, 2:4] = size
    regressors[0, index, 4:6] = keypoint
    scores = np.full((1, len(anchors), 1), -10.0, np.float32)
    scores[0, index, 0] = logit
    return regressors, scores


def write(path, data=None):
    """Write a model (by default the float one) to path; return path."""
    with open(path, 'wb') as model_file:
        model_file.write(model_bytes() if data is None else data)
    return path
