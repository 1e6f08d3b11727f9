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
A tiny quantised TensorFlow Lite model written byte by byte (no TensorFlow, no flatbuffers).

int8 input 'xq' (X_QUANT) -> DEQUANTIZE -> float 'x' -> QUANTIZE -> uint8 output 'yq'
(Y_QUANT), shape INPUT_SHAPE: what load() gives for float values x is x quantised, then
requantised, then dequantised (`expected(x)`). The FlatBuffer is laid out front to back, each
object before what it refers to; the table and field numbers are those of TensorFlow Lite's
schema.fbs (Model, OperatorCode, SubGraph, Tensor, QuantizationParameters, Operator, Buffer).
"""

import struct

import numpy as np
from onnx_model import dequantize, quantize, X_QUANT, Y_QUANT  # the ONNX model's numbers

INPUT_SHAPE = (1, 4, 6)
INT8, UINT8, FLOAT32 = 9, 3, 0  # TensorType
DEQUANTIZE, QUANTIZE = 6, 114  # BuiltinOperator


class _Writer:
    """A FlatBuffer written front to back: every offset points forward."""

    def __init__(self):
        self.data = bytearray(b'\0\0\0\0TFL3')  # the root's offset, then the file identifier

    def _align(self, size, before=0):
        """Pad so that the next `before` bytes end where a `size`-aligned value starts."""
        while (len(self.data) + before) % size:
            self.data.append(0)

    def table(self, fields):
        """Write a table: fields[i] is None, (format, value), or a function writing a child."""
        layout, size, widest = [], 4, 4
        for number, field in enumerate(fields):
            if field is None:
                continue
            width = 4 if callable(field) else struct.calcsize('<' + field[0])
            size = -(-size // width) * width
            layout.append((number, size, field))
            size += width
            widest = max(widest, width)
        offsets = {number: where for number, where, _ in layout}
        vtable = struct.pack('<HH', 4 + 2 * len(fields), size) + b''.join(
            struct.pack('<H', offsets.get(number, 0)) for number in range(len(fields)))
        self._align(2)
        vtable_at = len(self.data)
        self.data += vtable
        self._align(widest)
        start = len(self.data)
        self.data += bytes(size)
        struct.pack_into('<i', self.data, start, start - vtable_at)
        for _, where, field in layout:
            if not callable(field):
                struct.pack_into('<' + field[0], self.data, start + where, field[1])
        for _, where, field in layout:
            if callable(field):
                self._refer(start + where, field())
        return start

    def _refer(self, at, target):
        struct.pack_into('<I', self.data, at, target - at)

    def vector(self, fmt, values):
        width = struct.calcsize('<' + fmt)
        self._align(max(width, 4), 4)
        start = len(self.data)
        self.data += struct.pack('<I%d%s' % (len(values), fmt), len(values), *values)
        return start

    def string(self, text):
        start = self.vector('B', list(text.encode()))
        self.data.append(0)
        return start

    def tables(self, writers):
        """Write a vector of tables, each written by one of writers."""
        self._align(4)
        start = len(self.data)
        self.data += struct.pack('<I', len(writers)) + bytes(4 * len(writers))
        for number, write in enumerate(writers):
            self._refer(start + 4 + 4 * number, write())
        return start


def model_bytes(channels=1):
    """Return the model's file contents; channels > 1: its input quantised per channel."""
    out = _Writer()

    def tensor(name, kind, quant=None, channels=1):
        def write():
            quantization = None if quant is None else lambda: out.table(
                [None, None, lambda: out.vector('f', [quant[0]] * channels),
                 lambda: out.vector('q', [quant[1]] * channels), None, None,
                 ('i', 1 if channels > 1 else 0)])
            return out.table([lambda: out.vector('i', list(INPUT_SHAPE)), ('b', kind),
                              ('I', 0), lambda: out.string(name), quantization])
        return write

    def operator(code, inputs, outputs):
        return lambda: out.table([('I', code), lambda: out.vector('i', inputs),
                                  lambda: out.vector('i', outputs)])

    def code(builtin):
        return lambda: out.table([('b', builtin), None, ('i', 1), ('i', builtin)])

    def subgraph():
        return out.table([
            lambda: out.tables([tensor('xq', INT8, X_QUANT, channels), tensor('x', FLOAT32),
                                tensor('yq', UINT8, Y_QUANT)]),
            lambda: out.vector('i', [0]), lambda: out.vector('i', [2]),
            lambda: out.tables([operator(0, [0], [1]), operator(1, [1], [2])]),
            lambda: out.string('main')])

    root = out.table([('I', 3), lambda: out.tables([code(DEQUANTIZE), code(QUANTIZE)]),
                      lambda: out.tables([subgraph]), lambda: out.string('py_vision test'),
                      lambda: out.tables([lambda: out.table([])])])
    struct.pack_into('<I', out.data, 0, root)
    return bytes(out.data)


def _half_away_from_zero(values):
    return np.sign(values) * np.floor(np.abs(values) + 0.5)


def expected(x):
    """Return what load() gives for float values x: quantised in, requantised, dequantised."""
    # load() rounds half to even (np.round); TensorFlow Lite's QUANTIZE half away from zero.
    x = dequantize(quantize(x, X_QUANT, np.int8), X_QUANT)
    return dequantize(quantize(x, Y_QUANT, np.uint8, _half_away_from_zero), Y_QUANT)


def write(path, channels=1):
    """Write the model to path; return path."""
    with open(path, 'wb') as model_file:
        model_file.write(model_bytes(channels))
    return path
