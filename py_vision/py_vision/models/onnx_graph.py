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
What an ONNX file says of its inputs and outputs, read without the onnx package.

OpenCV's DNN module runs an ONNX model but does not say what the model's inputs are; this reads
the graph's inputs and outputs (name, shape, element type) from the file's protobuf directly,
so that a model run through OpenCV is checked like one run through any other runtime. Only the
few fields needed are decoded (onnx.proto: ModelProto.graph, GraphProto.input/output/
initializer, ValueInfoProto, TypeProto.Tensor, TensorShapeProto); everything else is skipped.
"""

from typing import Dict, Iterator, List, Tuple

import numpy as np

__all__ = ['OnnxFormatError', 'read_signature', 'ELEMENT_TYPES']

# onnx.proto's TensorProto.DataType values for the types a camera model uses.
ELEMENT_TYPES: Dict[int, np.dtype] = {
    1: np.dtype(np.float32), 2: np.dtype(np.uint8), 3: np.dtype(np.int8),
    5: np.dtype(np.int16), 6: np.dtype(np.int32), 7: np.dtype(np.int64),
    9: np.dtype(np.bool_), 10: np.dtype(np.float16), 11: np.dtype(np.float64),
}

# A dimension the file leaves open (a symbolic one such as 'batch', or none at all).
OPEN = -1

Signature = List[Tuple[str, Tuple[int, ...], np.dtype]]


class OnnxFormatError(ValueError):
    """The bytes are not an ONNX model (not a protobuf, or one without a graph)."""


def _varint(data: bytes, pos: int) -> Tuple[int, int]:
    value = shift = 0
    while True:
        if pos >= len(data):
            raise OnnxFormatError('ends inside a number')
        byte = data[pos]
        pos += 1
        value |= (byte & 0x7F) << shift
        if not byte & 0x80:
            return value, pos
        shift += 7
        if shift > 63:
            raise OnnxFormatError('has a number longer than 64 bits')


def _fields(data: bytes) -> Iterator[Tuple[int, int, object]]:
    """Yield (field number, wire type, value) of one protobuf message; bytes for wire type 2."""
    pos = 0
    while pos < len(data):
        key, pos = _varint(data, pos)
        number, wire = key >> 3, key & 7
        if number == 0:
            raise OnnxFormatError('is not a protobuf message (field 0)')
        if wire == 0:
            value, pos = _varint(data, pos)
        elif wire == 1:
            value, pos = data[pos:pos + 8], pos + 8
        elif wire == 2:
            length, pos = _varint(data, pos)
            value, pos = data[pos:pos + length], pos + length
        elif wire == 5:
            value, pos = data[pos:pos + 4], pos + 4
        else:
            raise OnnxFormatError('is not a protobuf message (wire type %d)' % wire)
        if pos > len(data):
            raise OnnxFormatError('is truncated')
        yield number, wire, value


def _value_info(data: bytes) -> Tuple[str, Tuple[int, ...], np.dtype]:
    name, dims, element = '', [], 0
    for number, wire, value in _fields(data):
        if number == 1 and wire == 2:
            name = value.decode('utf-8', 'replace')
        elif number == 2 and wire == 2:
            for type_field, type_wire, tensor in _fields(value):
                if type_field != 1 or type_wire != 2:
                    continue
                for tensor_field, tensor_wire, item in _fields(tensor):
                    if tensor_field == 1 and tensor_wire == 0:
                        element = item
                    elif tensor_field == 2 and tensor_wire == 2:
                        for dim_field, dim_wire, dim in _fields(item):
                            if dim_field == 1 and dim_wire == 2:
                                size = OPEN
                                for part, part_wire, part_value in _fields(dim):
                                    if part == 1 and part_wire == 0 and part_value > 0:
                                        size = part_value
                                dims.append(size)
    return name, tuple(dims), ELEMENT_TYPES.get(element, np.dtype(np.float32))


def read_signature(data: bytes) -> Tuple[Signature, Signature]:
    """
    Return the graph's (inputs, outputs), each a list of (name, shape, dtype).

    An open dimension (symbolic or unstated) is -1. Inputs that are initializers (weights
    listed as inputs by older exporters) are left out. Raises OnnxFormatError.
    """
    graph = None
    for number, wire, value in _fields(data):
        if number == 7 and wire == 2:
            graph = value
    if graph is None:
        raise OnnxFormatError('has no graph')
    inputs, outputs, initializers = [], [], set()
    for number, wire, value in _fields(graph):
        if wire != 2:
            continue
        if number == 11:
            inputs.append(_value_info(value))
        elif number == 12:
            outputs.append(_value_info(value))
        elif number == 5:
            for tensor_field, tensor_wire, name in _fields(value):
                if tensor_field == 8 and tensor_wire == 2:
                    initializers.add(name.decode('utf-8', 'replace'))
    inputs = [item for item in inputs if item[0] not in initializers]
    if not inputs or not outputs:
        raise OnnxFormatError('has a graph without inputs or outputs')
    return inputs, outputs
