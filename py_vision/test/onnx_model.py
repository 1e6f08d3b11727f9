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
A tiny ONNX model written byte by byte (no onnx package): y = Relu(x * scale + shift).

x is (1, 3, 4, 4) float32, scale (1, 3, 1, 1) one factor per channel, shift one number: two
nodes and two initializers, what every ONNX runtime (OpenCV's DNN 4.6 and 5, onnxruntime)
loads. `expected(x)` is the same computation in numpy. The field numbers are onnx.proto's.
"""


import numpy as np

SCALE = np.array([1.0, -2.0, 0.5], np.float32).reshape(1, 3, 1, 1)
SHIFT = np.array([0.25], np.float32)
INPUT_SHAPE = (1, 3, 4, 4)
FLOAT = 1  # TensorProto.DataType FLOAT


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
        return _varint(number << 3) + _varint(value)
    if isinstance(value, str):
        value = value.encode()
    return _varint(number << 3 | 2) + _varint(len(value)) + value


def _tensor(name, array):
    dims = b''.join(_field(1, size) for size in array.shape)
    return dims + _field(2, FLOAT) + _field(8, name) + _field(9, array.tobytes())


def _value_info(name, shape):
    dims = b''.join(_field(1, _field(1, size)) for size in shape)
    tensor_type = _field(1, FLOAT) + _field(2, dims)
    return _field(1, name) + _field(2, _field(1, tensor_type))


def _node(inputs, outputs, op_type, name):
    return (b''.join(_field(1, item) for item in inputs)
            + b''.join(_field(2, item) for item in outputs)
            + _field(3, name) + _field(4, op_type))


def model_bytes(input_shape=INPUT_SHAPE):
    """Return the model's file contents."""
    graph = (_field(1, _node(['x', 'scale'], ['scaled'], 'Mul', 'mul'))
             + _field(1, _node(['scaled', 'shift'], ['shifted'], 'Add', 'add'))
             + _field(1, _node(['shifted'], ['y'], 'Relu', 'relu'))
             + _field(2, 'tiny')
             + _field(5, _tensor('scale', SCALE))
             + _field(5, _tensor('shift', SHIFT))
             + _field(11, _value_info('x', input_shape))
             + _field(12, _value_info('y', input_shape)))
    opset = _field(1, '') + _field(2, 11)
    return (_field(1, 7) + _field(2, 'py_vision test') + _field(7, graph)
            + _field(8, opset))


def expected(x):
    """Return what the model computes for x."""
    return np.maximum(x * SCALE + SHIFT, 0).astype(np.float32)


def write(path):
    """Write the model to path; return path."""
    with open(path, 'wb') as model_file:
        model_file.write(model_bytes())
    return path
