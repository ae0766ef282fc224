"""ONNX protobuf messages written by hand, from onnxruntime's ORT-format flatbuffer tables.

:mod:`rosaos.frontends.voice.onnx_graph` needs only a few message types (model, graph, node,
attribute, tensor, value info), so it writes their wire format itself instead of depending on the
``onnx`` package. Field numbers are ONNX's (``onnx.proto``); the ``*_field`` helpers write one field.
"""

from __future__ import annotations

import struct
import sys
from collections.abc import Callable
from pathlib import Path
from typing import Any

from rosaos.frontends.voice.sources import VoiceError


def ort_flatbuffers() -> Any:
    """The ORT-format flatbuffer reader inside the onnxruntime wheel (not a public module)."""
    import onnxruntime

    folder = Path(onnxruntime.__file__).parent / "tools" / "ort_format_model"
    if str(folder) not in sys.path:
        sys.path.append(str(folder))  # appended: its types.py must not shadow the standard library's
    import ort_flatbuffers_py.fbs as fbs  # type: ignore[import-not-found]

    return fbs


def _varint(value: int) -> bytes:
    value &= (1 << 64) - 1  # negative int64s are ten bytes of two's complement
    out = bytearray()
    while True:
        byte = value & 0x7F
        value >>= 7
        if value:
            out.append(byte | 0x80)
        else:
            out.append(byte)
            return bytes(out)


def int_field(field: int, value: int) -> bytes:
    return _varint(field << 3) + _varint(value)


def bytes_field(field: int, value: bytes | str) -> bytes:
    data = value.encode() if isinstance(value, str) else value
    return _varint(field << 3 | 2) + _varint(len(data)) + data


def float_field(field: int, value: float) -> bytes:
    return _varint(field << 3 | 5) + struct.pack("<f", value)


def tensor_proto(tensor: Any) -> bytes:
    """An ORT ``Tensor`` as an ONNX ``TensorProto``."""
    out = b"".join(int_field(1, tensor.Dims(j)) for j in range(tensor.DimsLength()))
    out += int_field(2, tensor.DataType()) + bytes_field(8, tensor.Name())
    out += b"".join(bytes_field(6, tensor.StringData(j)) for j in range(tensor.StringDataLength()))
    if not tensor.RawDataIsNone():
        out += bytes_field(9, tensor.RawDataAsNumpy().tobytes())
    return out


def value_info(value: Any) -> bytes:
    """A graph input or output: name, element type and shape (fixed sizes and named ones)."""
    out = bytes_field(1, value.Name())
    info = value.Type()
    if info is None or info.ValueType() != 1:  # only tensors cross these graphs' borders
        return out
    tensor = ort_flatbuffers().TensorTypeAndShape.TensorTypeAndShape()
    table = info.Value()
    tensor.Init(table.Bytes, table.Pos)
    dims = b""
    shape = tensor.Shape()
    for j in range(shape.DimLength() if shape is not None else 0):
        dimension = shape.Dim(j).Value()
        if dimension is None or dimension.DimType() == 0:
            dims += bytes_field(1, b"")
        elif dimension.DimType() == 1:
            dims += bytes_field(1, int_field(1, dimension.DimValue()))
        else:
            dims += bytes_field(1, bytes_field(2, dimension.DimParam()))
    kind = int_field(1, tensor.ElemType()) + (bytes_field(2, dims) if shape is not None else b"")
    return out + bytes_field(2, bytes_field(1, kind))


def plain_node(
    op: str, inputs: list[bytes], outputs: list[bytes], attributes: bytes = b"", domain: str = ""
) -> bytes:
    """A ``NodeProto`` named after its first output (of the default domain unless ``domain``)."""
    out = b"".join(bytes_field(1, value) for value in inputs) + b"".join(
        bytes_field(2, value) for value in outputs
    )
    out += bytes_field(3, outputs[0] + b"/" + op.encode()) + bytes_field(4, op)
    return out + (bytes_field(7, domain) if domain else b"") + attributes


def attribute_proto(attribute: Any, graph: Callable[[Any], bytes]) -> bytes:
    """An ORT ``Attribute`` as an ONNX ``AttributeProto`` (the two enums number alike); ``graph``
    writes a subgraph (an ``If`` node's branches)."""
    kind = attribute.Type()
    types = ort_flatbuffers().AttributeType.AttributeType
    out = bytes_field(1, attribute.Name()) + int_field(20, kind)
    if kind == types.FLOAT:
        out += float_field(2, attribute.F())
    elif kind == types.INT:
        out += int_field(3, attribute.I())
    elif kind == types.STRING:
        out += bytes_field(4, attribute.S())
    elif kind == types.TENSOR:
        out += bytes_field(5, tensor_proto(attribute.T()))
    elif kind == types.GRAPH:
        out += bytes_field(6, graph(attribute.G()))
    elif kind == types.FLOATS:
        out += b"".join(float_field(7, attribute.Floats(j)) for j in range(attribute.FloatsLength()))
    elif kind == types.INTS:
        out += b"".join(int_field(8, attribute.Ints(j)) for j in range(attribute.IntsLength()))
    elif kind == types.STRINGS:
        out += b"".join(bytes_field(9, attribute.Strings(j)) for j in range(attribute.StringsLength()))
    else:
        raise VoiceError(f"attribute {attribute.Name()!r} has a type ({kind}) this conversion does not know")
    return out


def int8_tensor_proto(name: bytes, values: Any) -> bytes:
    """A ``TensorProto`` of int8 ``values`` (a numpy array) called ``name``."""
    return (
        b"".join(int_field(1, size) for size in values.shape)
        + int_field(2, 3)  # TensorProto.INT8
        + bytes_field(8, name)
        + bytes_field(9, values.astype("int8").tobytes())
    )
