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
few fields needed are decoded (onnx.proto: ModelProto.graph, GraphProto.node/input/output/
initializer, NodeProto, ValueInfoProto, TypeProto.Tensor, TensorShapeProto, TensorProto);
everything else is skipped.

Quantised inputs and outputs (QDQ, as onnxruntime's quantisation writes them at a model's
edges): an integer graph input is quantised when its one reader is a DequantizeLinear, an
integer graph output when it is written by a QuantizeLinear, in both cases with a constant
(an initializer or a Constant node) scalar scale and zero point (none: 0); those are the
tensor's scale and zero point. Any other integer input or output is plain integers.
`without_edge_quantization` gives the same model with those edge nodes taken out (float in,
float out), for a runtime that runs the float part only (OpenCV's DNN 4.6 reads a
QuantizeLinear's output as garbage, and shifts a uint8 input's zero point).
"""

from typing import Dict, Iterator, List, Optional, Sequence, Tuple

import numpy as np

__all__ = ['OnnxFormatError', 'read_signature', 'ELEMENT_TYPES', 'without_edge_quantization']

# onnx.proto's TensorProto.DataType values for the types a camera model uses.
ELEMENT_TYPES: Dict[int, np.dtype] = {
    1: np.dtype(np.float32), 2: np.dtype(np.uint8), 3: np.dtype(np.int8),
    5: np.dtype(np.int16), 6: np.dtype(np.int32), 7: np.dtype(np.int64),
    9: np.dtype(np.bool_), 10: np.dtype(np.float16), 11: np.dtype(np.float64),
}

# A dimension the file leaves open (a symbolic one such as 'batch', or none at all).
OPEN = -1

# One input or output: name, shape, element type, and scale and zero point (None and 0 where it
# is not quantised).
Tensor = Tuple[str, Tuple[int, ...], np.dtype, Optional[float], int]
Signature = List[Tensor]


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


def _text(value: bytes) -> str:
    return value.decode('utf-8', 'replace')


def _signed(value: int) -> int:
    """Return a varint's int64 (negative numbers are sent as 64-bit two's complement)."""
    return value - (1 << 64) if value >= 1 << 63 else value


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


def _scalar(data: bytes) -> Optional[float]:
    """Return the one number a TensorProto holds, or None when it holds another count."""
    dims, element, stored = [], 0, []
    for number, wire, value in _fields(data):
        if number == 1 and wire == 0:
            dims.append(value)
        elif number == 2 and wire == 0:
            element = value
        elif number in (4, 5, 7, 9):  # float_data, int32_data, int64_data, raw_data
            stored.append((number, wire, value))
    if any(size != 1 for size in dims) or element not in ELEMENT_TYPES or len(stored) != 1:
        return None  # a weight, not a scale or a zero point: not decoded
    number, wire, value = stored[0]
    if number == 9 and wire == 2:
        dtype = ELEMENT_TYPES[element].newbyteorder('<')
        return np.frombuffer(value, dtype)[0].item() if len(value) == dtype.itemsize else None
    if number == 4 and wire in (2, 5):  # one float, packed or not
        return float(np.frombuffer(value, '<f4')[0]) if len(value) == 4 else None
    if number in (5, 7) and wire == 0:
        return _signed(value)
    if number in (5, 7) and wire == 2:  # packed varints
        item, end = _varint(value, 0)
        return _signed(item) if end == len(value) else None
    return None


class _Graph:
    """The parts of a GraphProto read here: nodes, constants, inputs and outputs."""

    def __init__(self, graph: bytes):
        self.nodes: List[Tuple[str, List[str], List[str]]] = []  # op_type, inputs, outputs
        self.constants: Dict[str, Optional[float]] = {}  # scalar constants by name
        self.inputs, self.outputs, self.initializers = [], [], set()
        for number, wire, value in _fields(graph):
            if wire != 2:
                continue
            if number == 1:
                self._node(value)
            elif number == 11:
                self.inputs.append(_value_info(value))
            elif number == 12:
                self.outputs.append(_value_info(value))
            elif number == 5:
                for tensor_field, tensor_wire, name in _fields(value):
                    if tensor_field == 8 and tensor_wire == 2:
                        self.initializers.add(_text(name))
                        self.constants[_text(name)] = _scalar(value)

    def _node(self, data: bytes) -> None:
        op_type, inputs, outputs, value = '', [], [], None
        for number, wire, item in _fields(data):
            if number == 1 and wire == 2:
                inputs.append(_text(item))
            elif number == 2 and wire == 2:
                outputs.append(_text(item))
            elif number == 4 and wire == 2:
                op_type = _text(item)
            elif number == 5 and wire == 2:  # an attribute: a Constant's 'value' tensor
                name = tensor = None
                for attribute_field, attribute_wire, part in _fields(item):
                    if attribute_field == 1 and attribute_wire == 2:
                        name = _text(part)
                    elif attribute_field == 5 and attribute_wire == 2:
                        tensor = part
                if name == 'value' and tensor is not None:
                    value = _scalar(tensor)
        self.nodes.append((op_type, inputs, outputs))
        if op_type == 'Constant' and len(outputs) == 1:
            self.constants[outputs[0]] = value

    def edge_node(self, name: str, is_input: bool) -> Optional[Tuple[str, List[str], List[str]]]:
        """Return the DequantizeLinear reading input `name` or QuantizeLinear writing output."""
        if is_input:
            found = [node for node in self.nodes if name in node[1]]
            wanted = 'DequantizeLinear'
        else:
            found = [node for node in self.nodes if name in node[2]]
            wanted = 'QuantizeLinear'
        if len(found) != 1 or found[0][0] != wanted or len(found[0][1]) < 2:
            return None
        node = found[0]
        if (node[1][0] if is_input else node[2][0]) != name:
            return None
        return node

    def quantization(self, tensor, is_input: bool) -> Tuple[Optional[float], int]:
        """Return the (scale, zero point) of an integer input or output, or (None, 0)."""
        name, _, dtype = tensor
        node = self.edge_node(name, is_input) if dtype.kind in 'iu' else None
        if node is None:
            return None, 0
        scale = self.constants.get(node[1][1])
        zero = self.constants.get(node[1][2], None) if len(node[1]) > 2 and node[1][2] else 0
        if scale is None or zero is None or not scale > 0:
            return None, 0
        return float(scale), int(zero)


def _graph_of(data: bytes) -> bytes:
    graph = None
    for number, wire, value in _fields(data):
        if number == 7 and wire == 2:
            graph = value
    if graph is None:
        raise OnnxFormatError('has no graph')
    return graph


def read_signature(data: bytes) -> Tuple[Signature, Signature]:
    """
    Return the graph's (inputs, outputs), each a list of (name, shape, dtype, scale, zero point).

    An open dimension (symbolic or unstated) is -1. Inputs that are initializers (weights
    listed as inputs by older exporters) are left out. The scale and zero point of a quantised
    input or output (the module's docstring), else None and 0. Raises OnnxFormatError.
    """
    return _signature(_Graph(_graph_of(data)))


def _signature(graph: _Graph) -> Tuple[Signature, Signature]:
    inputs = [item for item in graph.inputs if item[0] not in graph.initializers]
    if not inputs or not graph.outputs:
        raise OnnxFormatError('has a graph without inputs or outputs')
    return ([item + graph.quantization(item, True) for item in inputs],
            [item + graph.quantization(item, False) for item in graph.outputs])


def _key(number: int, wire: int) -> bytes:
    return _encode_varint(number << 3 | wire)


def _encode_varint(value: int) -> bytes:
    out = bytearray()
    while True:
        byte = value & 0x7F
        value >>= 7
        if value:
            out.append(byte | 0x80)
        else:
            out.append(byte)
            return bytes(out)


def _encode(number: int, wire: int, value) -> bytes:
    """Return one field as it was read by _fields."""
    if wire == 0:
        return _key(number, 0) + _encode_varint(value)
    if wire == 2:
        return _key(number, 2) + _encode_varint(len(value)) + value
    return _key(number, wire) + value


def _float_value_info(name: str, shape: Sequence[int]) -> bytes:
    """Return a ValueInfoProto: a float32 tensor of this shape (-1: an open dimension)."""
    dims = b''.join(_encode(1, 2, _encode(1, 0, size) if size >= 0 else b'') for size in shape)
    tensor_type = _encode(1, 0, 1) + _encode(2, 2, dims)
    return _encode(1, 2, name.encode()) + _encode(2, 2, _encode(1, 2, tensor_type))


def without_edge_quantization(data: bytes) -> Tuple[bytes, Dict[str, str]]:
    """
    Return the model without its quantised inputs' and outputs' edge nodes, and the renaming.

    Each quantised input's DequantizeLinear and each quantised output's QuantizeLinear is
    taken out: the model's input is then the DequantizeLinear's float output, its output the
    QuantizeLinear's float input. The renaming maps each such input or output's name to the
    float tensor that takes its place. Raises OnnxFormatError.
    """
    model_graph = _graph_of(data)
    graph = _Graph(model_graph)
    inputs, outputs = _signature(graph)
    dropped, renamed, replaced = [], {}, {}
    for items, is_input in ((inputs, True), (outputs, False)):
        for name, shape, _, scale, _ in items:
            if scale is None:
                continue
            node = graph.edge_node(name, is_input)
            dropped.append(graph.nodes.index(node))
            renamed[name] = node[2][0] if is_input else node[1][0]
            replaced[name] = _float_value_info(renamed[name], shape)
    if not renamed:
        return data, {}
    parts, node_index = [], 0
    for number, wire, value in _fields(model_graph):
        if number == 1 and wire == 2:
            keep = node_index not in dropped
            node_index += 1
            if not keep:
                continue
        elif number in (11, 12) and wire == 2:
            name = _value_info(value)[0]
            if name in replaced:
                value = replaced[name]
        parts.append(_encode(number, wire, value))
    new_graph = b''.join(parts)
    model = b''.join(_encode(number, wire, new_graph if number == 7 and wire == 2 else value)
                     for number, wire, value in _fields(data))
    return model, renamed
