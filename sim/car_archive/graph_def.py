"""A frozen TensorFlow graph (`GraphDef`, the car's agent/model.pb) read without TensorFlow.

Field numbers follow TensorFlow's public .proto files (tensorflow/core/framework/):
GraphDef.node = 1; NodeDef name = 1, op = 2, input = 3, attr = 5 (a map: entries of key = 1,
value = 2); AttrValue list = 1, s = 2, i = 3, f = 4, b = 5, type = 6, shape = 7, tensor = 8
(tensors and shapes as `sim.car_archive.tensor_proto` reads them). Fields a frozen inference
graph does not need (devices, debug info, function libraries) are skipped, as protobuf skips
unknown fields.

Only the ops in `SUPPORTED_OPS` load: the graph is data, and an op nobody here implements
could not be run faithfully anyway. Nothing in this module imports torch.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray

from sim.car_archive.errors import CarModelError
from sim.car_archive.protobuf_wire import (
    WireFormatError,
    as_bytes,
    as_float32,
    as_int,
    as_text,
    fields,
    packed_varints,
)
from sim.car_archive.tensor_proto import (
    DTYPES,
    ExpansionBudget,
    read_floats,
    read_shape,
    read_tensor,
)

# The ops `sim.car_archive.graph_runner` implements (a test keeps the two lists equal): those
# DeepRacer's networks use, plus the plain arithmetic and shape ops other exporters emit for
# the same layers.
SUPPORTED_OPS = frozenset(
    {
        # Graph plumbing.
        "Const",
        "Identity",
        "NoOp",
        "Placeholder",
        "StopGradient",
        # Arithmetic (NumPy broadcasting, as TensorFlow's).
        "Add",
        "AddV2",
        "Maximum",
        "Minimum",
        "Mul",
        "RealDiv",
        "Rsqrt",
        "Sub",
        # Layers.
        "AvgPool",
        "BiasAdd",
        "Conv2D",
        "FusedBatchNorm",
        "FusedBatchNormV3",
        "MatMul",
        "MaxPool",
        "Relu",
        "Sigmoid",
        "Softmax",
        "Tanh",
        # Shapes (tf.layers' Flatten is Shape -> StridedSlice -> Pack -> Reshape).
        "Cast",
        "ConcatV2",
        "ExpandDims",
        "Pack",
        "Reshape",
        "Shape",
        "Squeeze",
        "StridedSlice",
    }
)

MAX_NODES = 100_000


@dataclass(frozen=True)
class AttrValue:
    """One attribute of a node; exactly the field its type uses is set. Lists are tuples."""

    s: bytes | None = None
    i: int | None = None
    f: float | None = None
    b: bool | None = None
    dtype: int | None = None
    shape: tuple[int, ...] | None = None
    tensor: NDArray[Any] | None = None
    list_s: tuple[bytes, ...] = ()
    list_i: tuple[int, ...] = ()
    list_f: tuple[float, ...] = ()
    list_type: tuple[int, ...] = ()


@dataclass(frozen=True)
class GraphNode:
    """One NodeDef: its data inputs as "node" or "node:k"; "^node" control inputs apart."""

    name: str
    op: str
    inputs: tuple[str, ...]
    control_inputs: tuple[str, ...] = ()
    attrs: Mapping[str, AttrValue] = field(default_factory=dict)

    def attr(self, key: str) -> AttrValue:
        value = self.attrs.get(key)
        if value is None:
            raise CarModelError(f"node {self.name!r} ({self.op}) has no attribute {key!r}.")
        return value

    def ints(self, key: str, default: tuple[int, ...] | None = None) -> tuple[int, ...]:
        if key not in self.attrs and default is not None:
            return default
        return self.attr(key).list_i

    def text(self, key: str, default: str | None = None) -> str:
        if key not in self.attrs and default is not None:
            return default
        value = self.attr(key).s
        if value is None:
            raise CarModelError(f"node {self.name!r} ({self.op}): {key!r} is not a string.")
        return value.decode("utf-8", errors="replace")

    def integer(self, key: str, default: int | None = None) -> int:
        if key not in self.attrs and default is not None:
            return default
        value = self.attr(key).i
        if value is None:
            raise CarModelError(f"node {self.name!r} ({self.op}): {key!r} is not an integer.")
        return value

    def flag(self, key: str, default: bool = False) -> bool:
        value = self.attrs.get(key)
        return default if value is None or value.b is None else value.b

    def dtype(self, key: str) -> np.dtype[Any]:
        number = self.attr(key).dtype
        if number not in DTYPES:
            raise CarModelError(
                f"node {self.name!r} ({self.op}) uses TensorFlow data type {number}, "
                "which a policy graph does not need."
            )
        return DTYPES[number]

    def constant(self) -> NDArray[Any]:
        value = self.attr("value").tensor
        if value is None:
            raise CarModelError(f"node {self.name!r} (Const) holds no tensor.")
        return value


@dataclass(frozen=True)
class FrozenGraph:
    """A GraphDef's nodes by name, in file order."""

    nodes: Mapping[str, GraphNode]

    @property
    def ops(self) -> frozenset[str]:
        return frozenset(node.op for node in self.nodes.values())

    def node(self, name: str) -> GraphNode:
        found = self.nodes.get(name)
        if found is None:
            raise CarModelError(f"the graph has no node named {name!r}.")
        return found

    def plan(self, outputs: Iterable[str]) -> list[GraphNode]:
        """The nodes `outputs` depend on, each after its inputs (control inputs ignored: a
        frozen graph's control edges only order side effects an inference graph lacks)."""
        order: list[GraphNode] = []
        state: dict[str, int] = {}  # 1 = being visited, 2 = done
        for output in outputs:
            stack: list[tuple[str, bool]] = [(node_name(output), False)]
            while stack:
                name, expanded = stack.pop()
                if expanded:
                    state[name] = 2
                    order.append(self.nodes[name])
                    continue
                seen = state.get(name)
                if seen == 2:
                    continue
                if seen == 1:
                    raise CarModelError(f"the graph has a cycle through node {name!r}.")
                node = self.node(name)
                state[name] = 1
                stack.append((name, True))
                for source in reversed(node.inputs):
                    source_name = node_name(source)
                    if source_name not in self.nodes:
                        raise CarModelError(
                            f"node {name!r} reads {source_name!r}, which is not in the graph."
                        )
                    if state.get(source_name) == 1:
                        raise CarModelError(f"the graph has a cycle through node {name!r}.")
                    if state.get(source_name) != 2:
                        stack.append((source_name, False))
        return order


def node_name(reference: str) -> str:
    """The node an input reference ("name", "name:1", "^name") points at."""
    name = reference.removeprefix("^")
    base, colon, index = name.rpartition(":")
    return base if colon and index.isdigit() else name


def output_index(reference: str) -> int:
    """Which output of its node an input reference reads (0 when not given)."""
    _, colon, index = reference.rpartition(":")
    return int(index) if colon and index.isdigit() else 0


def read_graph(data: bytes | memoryview, where: str = "agent/model.pb") -> FrozenGraph:
    """Parse a serialized GraphDef; every problem is one `CarModelError` naming `where`."""
    try:
        graph = _graph(memoryview(data))
    except WireFormatError as error:
        raise CarModelError(
            f"{where}: not a frozen TensorFlow graph ({str(error).rstrip('.')}); give the model "
            "as DeepRacer or racer-tui exported it."
        ) from None
    except CarModelError as error:
        raise CarModelError(f"{where}: {error}") from None
    unsupported = sorted(graph.ops - SUPPORTED_OPS)
    if unsupported:
        nodes = [node.name for node in graph.nodes.values() if node.op == unsupported[0]]
        raise CarModelError(
            f"{where}: the graph uses the TensorFlow op {unsupported[0]!r} (node {nodes[0]!r}), "
            "which racer-tui cannot run."
        )
    return graph


def _graph(data: memoryview) -> FrozenGraph:
    nodes: dict[str, GraphNode] = {}
    budget = ExpansionBudget()
    for number, _, value in fields(data):
        if number != 1:
            continue  # versions, library: nothing an inference graph needs
        if len(nodes) >= MAX_NODES:
            raise CarModelError(f"the graph has more than {MAX_NODES:,} nodes.")
        node = _node(as_bytes(value, "a graph node"), budget)
        if node.name in nodes:
            raise CarModelError(f"two nodes are named {node.name!r}.")
        nodes[node.name] = node
    if not nodes:
        raise CarModelError("the file holds no graph nodes; it is not a frozen TensorFlow graph.")
    return FrozenGraph(nodes)


def _node(data: memoryview, budget: ExpansionBudget) -> GraphNode:
    name = op = ""
    inputs: list[str] = []
    controls: list[str] = []
    attrs: dict[str, AttrValue] = {}
    for number, _, value in fields(data):
        if number == 1:
            name = as_text(value, "a node name")
        elif number == 2:
            op = as_text(value, "a node's op")
        elif number == 3:
            source = as_text(value, "a node input")
            (controls if source.startswith("^") else inputs).append(source)
        elif number == 5:
            key, attr = _attr_entry(as_bytes(value, "a node attribute"), budget)
            attrs[key] = attr
    if not name or not op:
        raise CarModelError("a graph node has no name or no op.")
    return GraphNode(name, op, tuple(inputs), tuple(controls), attrs)


def _attr_entry(data: memoryview, budget: ExpansionBudget) -> tuple[str, AttrValue]:
    key = ""
    attr = AttrValue()
    for number, _, value in fields(data):
        if number == 1:
            key = as_text(value, "an attribute name")
        elif number == 2:
            attr = _attr_value(as_bytes(value, "an attribute value"), budget)
    return key, attr


def _attr_value(data: memoryview, budget: ExpansionBudget) -> AttrValue:
    values: dict[str, Any] = {}
    for number, _, value in fields(data):
        if number == 1:
            values.update(_list_value(as_bytes(value, "an attribute list")))
        elif number == 2:
            values["s"] = bytes(as_bytes(value, "a string attribute"))
        elif number == 3:
            values["i"] = as_int(value, "an integer attribute")
        elif number == 4:
            values["f"] = as_float32(value)
        elif number == 5:
            values["b"] = bool(as_int(value, "a boolean attribute"))
        elif number == 6:
            values["dtype"] = as_int(value, "a type attribute")
        elif number == 7:
            values["shape"] = read_shape(as_bytes(value, "a shape attribute"))
        elif number == 8:
            values["tensor"] = read_tensor(as_bytes(value, "a tensor attribute"), budget)
    return AttrValue(**values)


def _list_value(data: memoryview) -> dict[str, Any]:
    strings: list[bytes] = []
    ints: list[int] = []
    floats: list[float] = []
    types: list[int] = []
    for number, wire, value in fields(data):
        if number == 2:
            strings.append(bytes(as_bytes(value, "a string list")))
        elif number == 3:
            ints.extend(packed_varints(value))
        elif number == 4:
            floats.extend(read_floats(wire, value, "<f4").tolist())
        elif number == 6:
            types.extend(packed_varints(value))
    return {
        "list_s": tuple(strings),
        "list_i": tuple(ints),
        "list_f": tuple(floats),
        "list_type": tuple(types),
    }
