"""Moonshine's ORT-format models rewritten as ONNX, each weight dequantized where it is used.

Why: the weights in the moonshine-cpp wheel are int8, turned into float32 by ``Cast``/``Mul``/
``Add`` nodes at the top of each graph. In the merged decoder those nodes feed an ``If`` (cached
branch or not), so all 41 M weights (165 MB of float32) are alive at once on every decoder step,
and the arena keeps that much for good: most of the voice process's memory. Moved next to the
product that reads it, each weight is used as it is stored:

- in the decoder (one token a step, so its products are a row times a matrix, bound by how many
  bytes are read) ``DynamicQuantizeMatMul`` multiplies the int8 weights by the activations
  rounded to a byte: no float copy of any weight, and a step takes a fifth of the time it did
  with a float copy made per product (issue 25: the transcript has to be ready within the short
  end-of-turn pause). The embedding table the logits read transposed is transposed once, here;
- in the encoder (many rows at once, bound by arithmetic) each weight is cast to float just
  before its product and freed after it: byte-rounded activations there cost words.

ORT format cannot be edited by onnxruntime itself, so this reads the flatbuffer with the reader
that ships in the onnxruntime wheel and writes the ONNX protobuf by hand (:mod:`.onnx_proto`;
no ``onnx`` package). It runs once, in a child process (the conversion holds the model three
times over for a moment, which the voice process should not), and the result is cached by the
source files' size and time.
"""

from __future__ import annotations

import hashlib
import math
import os
import subprocess
import sys
from collections.abc import Iterable, Iterator
from pathlib import Path
from typing import Any

import platformdirs

from rosaos.frontends.voice.onnx_proto import (
    attribute_proto,
    bytes_field,
    int8_tensor_proto,
    int_field,
    ort_flatbuffers,
    plain_node,
    tensor_proto,
    value_info,
)
from rosaos.frontends.voice.sources import VoiceError

FORMAT_VERSION = 4
"""Part of the cache key: bump it when the rewrite changes."""
DEQUANTIZE_OPS = ("Cast", "Mul", "Add")
"""The chain that turns an int8 initializer into float32: ``Add(Mul(Cast(q), scale), offset)``."""


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
        self.tensors: dict[bytes, Any] = {}
        """The top graph's initializers, by name."""
        self.extra: dict[bytes, bytes] = {}
        """Initializers this rewrite adds (``TensorProto`` s by name): int8 weights transposed once."""

    def transposed(self, weights: bytes, reader: Any) -> bytes | None:
        """``reader`` (a ``Transpose``) of the int8 initializer ``weights``, done once here rather
        than at every decoder step (the 13 M-weight embedding table, read again for the logits)."""
        tensor = self.tensors.get(weights)
        if reader.OpType() != b"Transpose" or tensor is None or tensor.DataType() != 3:  # int8
            return None
        name = weights + b"/transposed"
        if name not in self.extra:
            perm = [
                reader.Attributes(j).Ints(k)
                for j in range(reader.AttributesLength())
                if reader.Attributes(j).Name() == b"perm"
                for k in range(reader.Attributes(j).IntsLength())
            ]
            dims = [tensor.Dims(j) for j in range(tensor.DimsLength())]
            values = tensor.RawDataAsNumpy().view("int8").reshape(dims).transpose(perm or None)
            self.extra[name] = int8_tensor_proto(name, values)
        return name

    def attribute(self, attribute: Any) -> bytes:
        """An ORT ``Attribute`` as an ONNX ``AttributeProto``; a branch's graph is rewritten too."""
        return attribute_proto(attribute, lambda graph: self.graph(graph, top=False))

    def node(self, node: Any, inputs: list[bytes] | None = None, outputs: list[bytes] | None = None) -> bytes:
        """``node`` as a ``NodeProto``; ``inputs``/``outputs`` rename its values (and its name)."""
        inputs = inputs or [node.Inputs(j) for j in range(node.InputsLength())]
        outputs = outputs or [node.Outputs(j) for j in range(node.OutputsLength())]
        name = node.Name() + (b"" if outputs[0] == node.Outputs(0) else b"/" + outputs[0])
        out = b"".join(bytes_field(1, value) for value in inputs) + b"".join(
            bytes_field(2, value) for value in outputs
        )
        out += bytes_field(3, name) + bytes_field(4, node.OpType()) + bytes_field(7, node.Domain() or b"")
        attributes = (node.Attributes(j) for j in range(node.AttributesLength()))
        return out + b"".join(bytes_field(5, self.attribute(attribute)) for attribute in attributes)

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
        out = b"".join(bytes_field(1, node) for node in nodes) + bytes_field(2, "g")
        out += b"".join(bytes_field(5, tensor_proto(tensor)) for tensor in initializers)
        if top:
            out += b"".join(bytes_field(5, tensor) for tensor in self.extra.values())
        inputs = [graph.Inputs(j) for j in range(graph.InputsLength())]
        out += b"".join(bytes_field(11, value_info(values[name])) for name in inputs if name not in constant)
        outputs = (values[graph.Outputs(j)] for j in range(graph.OutputsLength()))
        return out + b"".join(bytes_field(12, value_info(value)) for value in outputs)


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
        if reader is not None and anchor is None and (once := self.writer.transposed(weights, reader)):
            weights = once
        elif reader is not None:
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
        _cast, mul, add = chain
        result = node.Outputs(0)
        step = result + b"/"
        if self.writer.branching:  # the decoder: one token a step, int8 products
            weights = self.int8(name, None)  # no float copy is made: nothing to put off
            product = [
                plain_node(
                    "DynamicQuantizeMatMul",
                    [x, weights, mul.Inputs(1)],
                    [step + b"scaled"],
                    domain="com.microsoft",
                )
            ]
        else:
            weights = self.int8(name, anchor)
            product = [
                self.writer.node(_cast, [weights], [step + b"weights"]),
                plain_node("MatMul", [x, step + b"weights"], [step + b"product"]),
                plain_node("Mul", [step + b"product", mul.Inputs(1)], [step + b"scaled"]),
            ]
        del self.lazy[name]
        self.out += [
            *product,
            plain_node(
                "Constant",
                [],
                [step + b"last_axis"],
                bytes_field(5, bytes_field(1, "value_ints") + int_field(20, 7) + int_field(8, -1)),
            ),
            plain_node("ReduceSum", [x, step + b"last_axis"], [step + b"sum"]),  # keepdims: [..., 1]
            plain_node("Mul", [step + b"sum", add.Inputs(1)], [step + b"offset"]),
            plain_node("Add", [step + b"scaled", step + b"offset"], [result]),
        ]
        return True

    def after(self, weights: bytes, anchor: bytes, name: bytes) -> bytes:
        """``weights`` as a value that exists only once ``anchor`` does."""
        if anchor not in self.zeros:
            zero = anchor + b"/zero"
            self.out += [
                plain_node("Shape", [anchor], [zero + b"/shape"]),
                plain_node("Sub", [zero + b"/shape", zero + b"/shape"], [zero + b"/zeros"]),
                plain_node("ReduceSum", [zero + b"/zeros"], [zero]),  # keepdims: shape [1]
            ]
            self.zeros[anchor] = zero
        waited = name + b"/q"
        self.out += [
            plain_node("Shape", [weights], [waited + b"/shape"]),
            plain_node("Add", [waited + b"/shape", self.zeros[anchor]], [waited + b"/target"]),
            plain_node("Reshape", [weights, waited + b"/target"], [waited]),
        ]
        return waited


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
    fbs = ort_flatbuffers()
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
    writer.tensors = {tensor.Name(): tensor for tensor in _initializers(graph)}
    opsets = [model.OpsetImport(j) for j in range(model.OpsetImportLength())]
    out = int_field(1, model.IrVersion()) + bytes_field(2, "rosaos")
    out += b"".join(
        bytes_field(8, bytes_field(1, o.Domain() or b"") + int_field(2, o.Version())) for o in opsets
    )
    out += bytes_field(7, writer.graph(graph, top=True))
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
