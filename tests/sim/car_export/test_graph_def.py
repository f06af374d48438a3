"""The GraphDef reader: TensorFlow's wire format read by hand, bad graphs refused in one
sentence, constants decoded as TensorFlow defines them."""

from __future__ import annotations

import numpy as np
import pytest

from sim.car_archive.errors import CarModelError
from sim.car_archive.graph_def import read_graph
from sim.car_archive.protobuf_wire import fields, read_varint, signed64
from tests.sim.car_export.graphs import (
    CAMERA_INPUT,
    POLICY_OUTPUT,
    GraphWriter,
    attr_s,
    bytes_field,
    camera_policy_graph,
    node_proto,
    one_sentence,
    varint,
)


def test_varints_round_trip_including_negative_int64() -> None:
    for value in (0, 1, 127, 128, 300, 2**35, 2**63 - 1, -1, -(2**40)):
        decoded, end = read_varint(memoryview(varint(value)), 0)
        assert signed64(decoded) == value
        assert end == len(varint(value))


def test_a_camera_policy_graph_is_read_with_its_nodes_attributes_and_constants() -> None:
    graph = read_graph(camera_policy_graph(actions=3))
    conv = graph.node("conv")
    assert conv.op == "Conv2D"
    assert conv.inputs == ("scaled", "kernel")
    assert conv.ints("strides") == (1, 4, 4, 1)
    assert conv.text("padding") == "SAME"
    assert graph.node("kernel").constant().shape == (5, 5, 1, 4)
    assert graph.node(CAMERA_INPUT).attrs["shape"].shape == (-1, 120, 160, 1)
    order = [node.name for node in graph.plan([POLICY_OUTPUT])]
    assert order.index(CAMERA_INPUT) < order.index("conv") < order.index(POLICY_OUTPUT)


def test_constants_given_as_value_lists_fill_their_shape_with_the_last_value() -> None:
    g = GraphWriter()
    g.const("floats", np.array([1.5, 2.5, 2.5, 2.5], np.float32), packed_values=True)
    g.const("ints", np.array([[7, -3], [-3, -3]], np.int32), packed_values=True)
    graph = read_graph(bytes(g))
    np.testing.assert_array_equal(graph.node("floats").constant(), [1.5, 2.5, 2.5, 2.5])
    np.testing.assert_array_equal(graph.node("ints").constant(), [[7, -3], [-3, -3]])


def test_an_unknown_op_is_refused_in_one_sentence_naming_it() -> None:
    g = GraphWriter()
    x = g.placeholder("x", [-1, 4])
    g.op("loop", "While", x)
    with pytest.raises(CarModelError) as caught:
        read_graph(bytes(g), "car.tar.gz: agent/model.pb")
    message = str(caught.value)
    assert "'While'" in message and "'loop'" in message
    assert message.startswith("car.tar.gz: agent/model.pb: ")
    assert one_sentence(message)


@pytest.mark.parametrize("cut", [1, 7, 100, 1000])
def test_a_truncated_graph_is_refused_in_one_sentence(cut: int) -> None:
    data = camera_policy_graph()
    with pytest.raises(CarModelError) as caught:
        read_graph(data[:-cut])
    assert "truncated" in str(caught.value)
    assert one_sentence(str(caught.value))


def test_garbage_and_empty_files_are_not_graphs() -> None:
    for data in (b"", b"\x00\x01\x02", b"hello, this is not a graph"):
        with pytest.raises(CarModelError) as caught:
            read_graph(data)
        assert one_sentence(str(caught.value))


def test_a_constant_whose_bytes_do_not_match_its_shape_is_refused() -> None:
    tensor = varint(1 << 3) + varint(1)  # dtype float
    tensor += bytes_field(2, bytes_field(2, varint(1 << 3) + varint(4)))  # shape [4]
    tensor += bytes_field(4, b"\x00" * 12)  # 3 floats
    value = bytes_field(8, tensor)
    node = node_proto("c", "Const", (), {"value": value})
    with pytest.raises(CarModelError, match="not the 16 its shape needs"):
        read_graph(bytes_field(1, node))


def test_a_tiny_constant_cannot_expand_to_gigabytes() -> None:
    tensor = varint(1 << 3) + varint(1)
    tensor += bytes_field(2, bytes_field(2, varint(1 << 3) + varint(1 << 40)))
    tensor += bytes_field(5, b"\x00\x00\x80\x3f")  # one float: 1.0
    node = node_proto("c", "Const", (), {"value": bytes_field(8, tensor)})
    with pytest.raises(CarModelError, match="would fill more than"):
        read_graph(bytes_field(1, node))


def test_missing_inputs_and_cycles_are_refused_when_planning() -> None:
    g = GraphWriter()
    g.op("a", "Identity", "b")
    g.op("b", "Identity", "a")
    g.op("c", "Relu", "nowhere:0")
    graph = read_graph(bytes(g))
    with pytest.raises(CarModelError, match="cycle"):
        graph.plan(["a"])
    with pytest.raises(CarModelError, match="'nowhere', which is not in the graph"):
        graph.plan(["c"])


def test_wire_fields_keep_unknown_fields_out_of_the_way() -> None:
    # A GraphDef with a versions field (4) and a node: only the node is read.
    data = bytes_field(4, varint(1 << 3) + varint(27)) + bytes_field(
        1, node_proto("x", "Placeholder", (), {"padding": attr_s("SAME")})
    )
    assert [number for number, _, _ in fields(memoryview(data))] == [4, 1]
    assert list(read_graph(data).nodes) == ["x"]
