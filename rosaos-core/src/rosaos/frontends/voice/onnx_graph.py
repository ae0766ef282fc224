"""Moonshine's ORT-format models rewritten as ONNX, each weight dequantized where it is used.

Why: the weights in the moonshine-cpp wheel are int8, turned into float32 by ``Cast``/``Mul``/
``Add`` nodes at the top of each graph. In the merged decoder those nodes feed an ``If`` (cached
branch or not), so all 41 M weights (165 MB of float32) are alive at once on every decoder step,
and the arena keeps that much for good: most of the voice process's memory. Moved into the
branch, next to the ``MatMul`` that reads it, each float copy lives only until that product is
done, so the arena holds about one weight's worth instead of all of them. The arithmetic is the
same node for node, so the transcripts are too.

ORT format cannot be edited by onnxruntime itself, so this reads the flatbuffer with the reader
that ships in the onnxruntime wheel and writes the ONNX protobuf by hand (a few message types; no
``onnx`` package). It runs once, in a child process (the conversion holds the model three times
over for a moment, which the voice process should not), and the result is cached by the source
files' size and time.
"""

from __future__ import annotations

import hashlib
import math
import os
import struct
import subprocess
import sys
from collections.abc import Iterable, Iterator
from pathlib import Path
from typing import Any

import platformdirs

from rosaos.frontends.voice.sources import VoiceError

FORMAT_VERSION = 1
"""Part of the cache key: bump it when the rewrite changes."""
DEQUANTIZE_OPS = ("Cast", "Mul", "Add")
"""The chain that turns an int8 initializer into float32: ``Add(Mul(Cast(q), scale), offset)``."""


def _fbs() -> Any:
    """The ORT-format flatbuffer reader inside the onnxruntime wheel (not a public module)."""
    import onnxruntime

    folder = Path(onnxruntime.__file__).parent / "tools" / "ort_format_model"
    if str(folder) not in sys.path:
        sys.path.append(str(folder))  # appended: its types.py must not shadow the standard library's
    import ort_flatbuffers_py.fbs as fbs  # type: ignore[import-not-found]

    return fbs


# --- protobuf, by hand -------------------------------------------------------------------------


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


def _int(field: int, value: int) -> bytes:
    return _varint(field << 3) + _varint(value)


def _bytes(field: int, value: bytes | str) -> bytes:
    data = value.encode() if isinstance(value, str) else value
    return _varint(field << 3 | 2) + _varint(len(data)) + data


def _float(field: int, value: float) -> bytes:
    return _varint(field << 3 | 5) + struct.pack("<f", value)


def _tensor(tensor: Any) -> bytes:
    """An ORT ``Tensor`` as an ONNX ``TensorProto``."""
    out = b"".join(_int(1, tensor.Dims(j)) for j in range(tensor.DimsLength()))
    out += _int(2, tensor.DataType()) + _bytes(8, tensor.Name())
    out += b"".join(_bytes(6, tensor.StringData(j)) for j in range(tensor.StringDataLength()))
    if not tensor.RawDataIsNone():
        out += _bytes(9, tensor.RawDataAsNumpy().tobytes())
    return out


def _value_info(value: Any) -> bytes:
    """A graph input or output: name, element type and shape (fixed sizes and named ones)."""
    out = _bytes(1, value.Name())
    info = value.Type()
    if info is None or info.ValueType() != 1:  # only tensors cross these graphs' borders
        return out
    tensor = _fbs().TensorTypeAndShape.TensorTypeAndShape()
    table = info.Value()
    tensor.Init(table.Bytes, table.Pos)
    dims = b""
    shape = tensor.Shape()
    for j in range(shape.DimLength() if shape is not None else 0):
        dimension = shape.Dim(j).Value()
        if dimension is None or dimension.DimType() == 0:
            dims += _bytes(1, b"")
        elif dimension.DimType() == 1:
            dims += _bytes(1, _int(1, dimension.DimValue()))
        else:
            dims += _bytes(1, _bytes(2, dimension.DimParam()))
    kind = _int(1, tensor.ElemType()) + (_bytes(2, dims) if shape is not None else b"")
    return out + _bytes(2, _bytes(1, kind))


class _Writer:
    """Writes ORT flatbuffer tables as ONNX messages; ``chains`` are moved into the graphs that read them."""

    def __init__(self, fbs: Any, chains: list[list[Any]], scalar: set[bytes], branching: bool) -> None:
        self.fbs = fbs
        self.branching = branching
        """Whether the chains move into the top graph's branches (else they stay in it, reordered)."""
        self.chains = {chain[-1].Outputs(0): chain for chain in chains}
        self.scalar = scalar
        """Chains whose scale and offset are single numbers (per-tensor quantization)."""
        self.moved = {link.Outputs(0) for chain in chains for link in chain}

    def attribute(self, attribute: Any) -> bytes:
        """An ORT ``Attribute`` as an ONNX ``AttributeProto`` (the two enums number alike)."""
        kind = attribute.Type()
        types = self.fbs.AttributeType.AttributeType
        out = _bytes(1, attribute.Name()) + _int(20, kind)
        if kind == types.FLOAT:
            out += _float(2, attribute.F())
        elif kind == types.INT:
            out += _int(3, attribute.I())
        elif kind == types.STRING:
            out += _bytes(4, attribute.S())
        elif kind == types.TENSOR:
            out += _bytes(5, _tensor(attribute.T()))
        elif kind == types.GRAPH:
            out += _bytes(6, self.graph(attribute.G(), top=False))
        elif kind == types.FLOATS:
            out += b"".join(_float(7, attribute.Floats(j)) for j in range(attribute.FloatsLength()))
        elif kind == types.INTS:
            out += b"".join(_int(8, attribute.Ints(j)) for j in range(attribute.IntsLength()))
        elif kind == types.STRINGS:
            out += b"".join(_bytes(9, attribute.Strings(j)) for j in range(attribute.StringsLength()))
        else:
            raise VoiceError(
                f"attribute {attribute.Name()!r} has a type ({kind}) this conversion does not know"
            )
        return out

    def node(self, node: Any, inputs: list[bytes] | None = None, outputs: list[bytes] | None = None) -> bytes:
        """``node`` as a ``NodeProto``; ``inputs``/``outputs`` rename its values (and its name)."""
        inputs = inputs or [node.Inputs(j) for j in range(node.InputsLength())]
        outputs = outputs or [node.Outputs(j) for j in range(node.OutputsLength())]
        name = node.Name() + (b"" if outputs[0] == node.Outputs(0) else b"/" + outputs[0])
        out = b"".join(_bytes(1, value) for value in inputs) + b"".join(_bytes(2, value) for value in outputs)
        out += _bytes(3, name) + _bytes(4, node.OpType()) + _bytes(7, node.Domain() or b"")
        attributes = (node.Attributes(j) for j in range(node.AttributesLength()))
        return out + b"".join(_bytes(5, self.attribute(attribute)) for attribute in attributes)

    def dequantized(self, chain: list[Any], weights: bytes, result: bytes) -> list[bytes]:
        """``chain`` rewired to read ``weights`` and write ``result``."""
        nodes, value = [], weights
        for number, link in enumerate(chain):
            out = result if number == len(chain) - 1 else result + b"/" + link.OpType()
            rest = [link.Inputs(j) for j in range(1, link.InputsLength())]
            nodes.append(self.node(link, [value, *rest], [out]))
            value = out
        return nodes

    def graph(self, graph: Any, top: bool) -> bytes:
        """An ORT ``Graph`` as an ONNX ``GraphProto``.

        At the top, the moved chains are left out. In a branch, each chain is written just before
        the first node that reads its result, and made to wait for that node's other input
        (:class:`_Branch`): onnxruntime runs a node as soon as its inputs are there, and a chain
        that reads only an initializer would otherwise run at the start of the branch, all 81 of
        them, which is what this rewrite is for not doing.
        """
        values = {graph.NodeArgs(j).Name(): graph.NodeArgs(j) for j in range(graph.NodeArgsLength())}
        initializers = _initializers(graph)
        constant = {tensor.Name() for tensor in initializers}
        graph_nodes = [graph.Nodes(j) for j in range(graph.NodesLength())]
        if top:
            graph_nodes = [node for node in graph_nodes if node.Outputs(0) not in self.moved]
        if top and self.branching:
            nodes = [self.node(node) for node in graph_nodes]
        else:
            nodes = _Branch(self, graph_nodes).write()
        out = b"".join(_bytes(1, node) for node in nodes) + _bytes(2, "g")
        out += b"".join(_bytes(5, _tensor(tensor)) for tensor in initializers)
        inputs = [graph.Inputs(j) for j in range(graph.InputsLength())]
        out += b"".join(_bytes(11, _value_info(values[name])) for name in inputs if name not in constant)
        outputs = (values[graph.Outputs(j)] for j in range(graph.OutputsLength()))
        return out + b"".join(_bytes(12, _value_info(value)) for value in outputs)


class _Branch:
    """The nodes of one branch, with the moved chains put where they are needed.

    A weight ``q`` is made to wait for an activation ``x`` by reshaping it to its own shape plus
    zeros computed from ``x``'s shape: ``Reshape(q, Shape(q) + ReduceSum(Shape(x) - Shape(x)))``.
    A row ``Gather`` or a ``Transpose`` of a weight with a scalar scale and offset runs on the
    int8 values before dequantizing (the same numbers): one token's embedding is dequantized, not
    the 54 MB table, and the transposed table only when the logits need it.
    """

    def __init__(self, writer: _Writer, nodes: list[Any]) -> None:
        self.writer = writer
        self.nodes = nodes
        self.out: list[bytes] = []
        self.zeros: dict[bytes, bytes] = {}
        self.lazy: dict[bytes, tuple[list[Any], Any | None]] = {
            name: (chain, None) for name, chain in writer.chains.items()
        }
        """Value → (its dequantizing chain, the int8 ``Gather``/``Transpose`` to run before it)."""
        readers_of_weights = {
            node.Inputs(j): node
            for node in nodes
            for j in range(node.InputsLength())
            if node.Inputs(j) in self.lazy
        }
        not_swappable = {
            node.Inputs(j)
            for node in nodes
            for j in range(node.InputsLength())
            if j > 0 or not _commutes_with_dequantizing(node)
        }
        self.swap = {
            name for name in readers_of_weights if name in writer.scalar and name not in not_swappable
        }

    def write(self) -> list[bytes]:
        for node in self.nodes:
            inputs = [node.Inputs(j) for j in range(node.InputsLength())]
            if inputs and inputs[0] in self.swap:
                chain = self.lazy[inputs[0]][0]
                if node.OpType() == b"Gather":  # waits for the token ids anyway
                    picked = node.Outputs(0) + b"/int8"
                    self.out.append(self.writer.node(node, [chain[0].Inputs(0), *inputs[1:]], [picked]))
                    self.out += self.writer.dequantized(chain, picked, node.Outputs(0))
                else:
                    self.lazy[node.Outputs(0)] = (chain, node)
                continue
            anchor = next((name for name in inputs if name and name not in self.lazy), None)
            if node.OpType() == b"MatMul" and len(inputs) == 2 and self.scaled_after(node, inputs, anchor):
                continue
            for name in inputs:
                if name in self.lazy:
                    self.out += self.writer.dequantized(self.lazy[name][0], self.int8(name, anchor), name)
                    del self.lazy[name]
            self.out.append(self.writer.node(node))
        return self.out

    def int8(self, name: bytes, anchor: bytes | None) -> bytes:
        """The int8 weights behind ``name``, once ``anchor`` exists (and transposed if they were)."""
        chain, reader = self.lazy[name]
        weights = chain[0].Inputs(0)
        if anchor is not None:
            weights = self.after(weights, anchor, name)
        if reader is not None:
            moved = name + b"/int8"
            rest = [reader.Inputs(j) for j in range(1, reader.InputsLength())]
            self.out.append(self.writer.node(reader, [weights, *rest], [moved]))
            weights = moved
        return weights

    def scaled_after(self, node: Any, inputs: list[bytes], anchor: bytes | None) -> bool:
        """``x @ (q·s + b)`` written as ``(x @ q)·s + sum(x)·b``, when the weights are per-tensor.

        The same product without a scaled float copy of the weights: one ``Cast`` of them instead
        of ``Cast``, ``Mul`` and ``Add``, each as large as the weights (three passes over 165 MB
        per decoder step before), and only one weight-sized buffer alive, not two.
        """
        x, name = inputs
        if (
            name not in self.lazy
            or x in self.lazy
            or self.lazy[name][0][-1].Outputs(0) not in self.writer.scalar
        ):
            return False
        chain = self.lazy[name][0]
        cast, mul, add = chain
        result = node.Outputs(0)
        weights = self.int8(name, anchor)
        del self.lazy[name]
        step = result + b"/"
        self.out += [
            self.writer.node(cast, [weights], [step + b"weights"]),
            _plain("MatMul", [x, step + b"weights"], [step + b"product"]),
            _plain("Mul", [step + b"product", mul.Inputs(1)], [step + b"scaled"]),
            _plain(
                "Constant",
                [],
                [step + b"last_axis"],
                _bytes(5, _bytes(1, "value_ints") + _int(20, 7) + _int(8, -1)),
            ),
            _plain("ReduceSum", [x, step + b"last_axis"], [step + b"sum"]),  # keepdims: [..., 1]
            _plain("Mul", [step + b"sum", add.Inputs(1)], [step + b"offset"]),
            _plain("Add", [step + b"scaled", step + b"offset"], [result]),
        ]
        return True

    def after(self, weights: bytes, anchor: bytes, name: bytes) -> bytes:
        """``weights`` as a value that exists only once ``anchor`` does."""
        if anchor not in self.zeros:
            zero = anchor + b"/zero"
            self.out += [
                _plain("Shape", [anchor], [zero + b"/shape"]),
                _plain("Sub", [zero + b"/shape", zero + b"/shape"], [zero + b"/zeros"]),
                _plain("ReduceSum", [zero + b"/zeros"], [zero]),  # keepdims: shape [1]
            ]
            self.zeros[anchor] = zero
        waited = name + b"/q"
        self.out += [
            _plain("Shape", [weights], [waited + b"/shape"]),
            _plain("Add", [waited + b"/shape", self.zeros[anchor]], [waited + b"/target"]),
            _plain("Reshape", [weights, waited + b"/target"], [waited]),
        ]
        return waited


def _plain(op: str, inputs: list[bytes], outputs: list[bytes], attributes: bytes = b"") -> bytes:
    """A ``NodeProto`` of the default domain, named after its first output."""
    out = b"".join(_bytes(1, value) for value in inputs) + b"".join(_bytes(2, value) for value in outputs)
    return out + _bytes(3, outputs[0] + b"/" + op.encode()) + _bytes(4, op) + attributes


def _initializers(graph: Any) -> list[Any]:
    return [graph.Initializers(j) for j in range(graph.InitializersLength())]


def _commutes_with_dequantizing(node: Any) -> bool:
    """A ``Gather`` of rows or a ``Transpose``: the same whether it reads int8 or float weights."""
    if node.OpType() == b"Transpose":
        return True
    axes = [
        node.Attributes(j).I() for j in range(node.AttributesLength()) if node.Attributes(j).Name() == b"axis"
    ]
    return node.OpType() == b"Gather" and axes in ([], [0])


def _dequantize_chains(graph: Any) -> Iterator[list[Any]]:
    """``Cast → Mul → Add`` chains that turn an initializer into float32, in node order."""
    constant = {graph.Initializers(j).Name() for j in range(graph.InitializersLength())}
    nodes = [graph.Nodes(j) for j in range(graph.NodesLength())]
    made_by = {node.Outputs(0): node for node in nodes if node.OutputsLength() == 1}
    for node in nodes:
        chain = [node]
        while len(chain) < len(DEQUANTIZE_OPS) and chain[0].Inputs(0) in made_by:
            chain.insert(0, made_by[chain[0].Inputs(0)])
        ops = tuple(link.OpType().decode() for link in chain)
        if ops == DEQUANTIZE_OPS and chain[0].Inputs(0) in constant:
            yield chain


def convert(source: Path, target: Path) -> None:
    """Write ``source`` (ORT format) to ``target`` (ONNX).

    When the graph branches (the merged decoder), the dequantizing chains whose results only the
    branches read move into them; in a graph without a branch (the encoder) they stay, put off
    until they are needed. Either way a product with a per-tensor weight is rescaled afterwards.
    """
    fbs = _fbs()
    data = bytearray(source.read_bytes())
    model = fbs.InferenceSession.InferenceSession.GetRootAsInferenceSession(data, 0).Model()
    graph = model.Graph()
    nodes = [graph.Nodes(j) for j in range(graph.NodesLength())]
    top_reads = {
        node.Inputs(j) for node in nodes if node.OpType() != b"If" for j in range(node.InputsLength())
    }
    branches = any(node.OpType() == b"If" for node in nodes)
    chains = [c for c in _dequantize_chains(graph) if not branches or c[-1].Outputs(0) not in top_reads]
    sizes = {t.Name(): math.prod(t.Dims(j) for j in range(t.DimsLength())) for t in _initializers(graph)}
    scalar = {c[-1].Outputs(0) for c in chains if all(sizes.get(link.Inputs(1)) == 1 for link in c[1:])}
    writer = _Writer(fbs, chains, scalar, branches)
    opsets = [model.OpsetImport(j) for j in range(model.OpsetImportLength())]
    out = _int(1, model.IrVersion()) + _bytes(2, "rosaos")
    out += b"".join(_bytes(8, _bytes(1, o.Domain() or b"") + _int(2, o.Version())) for o in opsets)
    out += _bytes(7, writer.graph(graph, top=True))
    partial = target.with_suffix(".partial")
    partial.write_bytes(out)
    partial.replace(target)


def cache_folder(sources: Iterable[Path]) -> Path:
    """Where the converted models of ``sources`` live: keyed by their paths, sizes and times."""
    key = hashlib.sha256(str(FORMAT_VERSION).encode())
    for source in sources:
        stat = source.stat()
        key.update(f"{source.resolve()}:{stat.st_size}:{stat.st_mtime_ns}".encode())
    root = Path(os.environ.get("ROSAOS_CACHE_DIR") or platformdirs.user_cache_dir("rosaos", appauthor=False))
    return root / "moonshine-onnx" / key.hexdigest()[:16]


def converted(sources: list[Path]) -> list[Path]:
    """The ONNX rewrite of each ORT-format source, made in a child process the first time."""
    folder = cache_folder(sources)
    targets = [folder / source.with_suffix(".onnx").name for source in sources]
    if all(target.is_file() for target in targets):
        return targets
    try:
        folder.mkdir(parents=True, exist_ok=True)
    except OSError as error:
        raise VoiceError(
            f"cannot make {folder} for the rewritten Moonshine models ({error.strerror}): "
            "set ROSAOS_CACHE_DIR to a writable folder"
        ) from None
    args = [str(path) for pair in zip(sources, targets, strict=True) for path in pair]
    done = subprocess.run(
        [sys.executable, "-m", "rosaos.frontends.voice.onnx_graph", *args],
        capture_output=True,
        text=True,
        check=False,
    )
    if done.returncode != 0 or not all(target.is_file() for target in targets):
        raise VoiceError(
            f"could not rewrite the Moonshine models into {folder}: {done.stderr.strip()[-400:]}. "
            "check that the folder is writable (or set ROSAOS_CACHE_DIR), or reinstall moonshine-cpp"
        )
    return targets


if __name__ == "__main__":
    pairs = sys.argv[1:]
    for source_arg, target_arg in zip(pairs[::2], pairs[1::2], strict=True):
        convert(Path(source_arg), Path(target_arg))
