"""The graph runner against TensorFlow's numbers and against a float64 NumPy runtime:
the DeepRacer-trained model's probabilities for DeepRacer's own camera frame, and each op's
NHWC semantics (SAME/VALID padding, strides, dilations) on small graphs."""

from __future__ import annotations

from collections.abc import Iterator

import numpy as np
import pytest
import torch

from sim.car_archive.archive import CarArchive
from sim.car_archive.errors import CarModelError
from sim.car_archive.graph_def import SUPPORTED_OPS, read_graph
from sim.car_archive.graph_runner import RUNNER_OPS, GraphRunner
from tests.sim.car_export.graphs import (
    CAMERA_INPUT,
    POLICY_OUTPUT,
    GraphWriter,
    attr_b,
    attr_f,
    attr_i,
    attr_ints,
    attr_s,
    attr_type,
    camera_policy_graph,
    flatten,
)
from tests.sim.car_export.reference import run_reference

# What DeepRacer's runtime (TensorFlow) gives for dr-demo-1.png: ../shared/deepracer/README.md.
TENSORFLOW_PROBABILITIES = np.array(
    [0.0059, 0.0070, 0.0519, 0.0149, 0.0715, 0.0073, 0.3912, 0.0326, 0.1142, 0.0164, 0.2474,
     0.0397]
)  # fmt: skip


@pytest.fixture(autouse=True)
def one_thread() -> Iterator[None]:
    before = torch.get_num_threads()
    torch.set_num_threads(1)
    yield
    torch.set_num_threads(before)


def test_the_runner_implements_exactly_the_ops_the_reader_accepts() -> None:
    assert RUNNER_OPS == SUPPORTED_OPS


def test_the_deepracer_model_gives_tensorflow_s_probabilities_for_its_demo_frame(
    sample_archive: CarArchive, demo_frame: np.ndarray
) -> None:
    runner = GraphRunner(sample_archive.graph, sample_archive.output_node)
    probabilities = runner.run({sample_archive.input_node: demo_frame[..., np.newaxis]})[0]
    # The README gives 4 decimals: every value rounds to TensorFlow's (|error| <= 5e-5).
    np.testing.assert_array_equal(
        np.round(probabilities.astype(float), 4), TENSORFLOW_PROBABILITIES
    )
    assert np.abs(probabilities - TENSORFLOW_PROBABILITIES).max() < 1e-4
    assert int(probabilities.argmax()) == 6  # 0 degrees, 2 m/s


def test_the_deepracer_model_agrees_with_a_float64_runtime_to_1e_6(
    sample_archive: CarArchive, demo_frame: np.ndarray
) -> None:
    rng = np.random.default_rng(3)
    frames = np.concatenate([demo_frame, rng.uniform(0, 255, (2, 120, 160))])[..., np.newaxis]
    runner = GraphRunner(sample_archive.graph, sample_archive.output_node)
    ours = runner.run({sample_archive.input_node: frames})
    exact = run_reference(
        sample_archive.graph, sample_archive.output_node, {sample_archive.input_node: frames}
    )
    assert ours.shape == exact.shape == (3, 12)
    assert np.abs(ours - exact).max() < 1e-6


def test_a_camera_policy_with_same_padding_and_max_pooling_matches_the_reference() -> None:
    graph = read_graph(camera_policy_graph(actions=5, seed=2))
    frames = np.random.default_rng(0).uniform(0, 255, (3, 120, 160, 1))
    ours = GraphRunner(graph, POLICY_OUTPUT).run({CAMERA_INPUT: frames})
    exact = run_reference(graph, POLICY_OUTPUT, {CAMERA_INPUT: frames})
    np.testing.assert_allclose(ours, exact, atol=1e-6)
    np.testing.assert_allclose(ours.sum(axis=1), 1.0, atol=1e-6)


@pytest.mark.parametrize(
    ("size", "kernel", "strides", "dilations", "padding"),
    [
        ((7, 9), (3, 3), (1, 1), (1, 1), "SAME"),
        ((7, 9), (4, 2), (2, 3), (1, 1), "SAME"),  # even kernel: the odd pad goes after
        ((8, 8), (3, 3), (2, 2), (1, 1), "SAME"),
        ((9, 11), (3, 3), (1, 1), (2, 2), "SAME"),
        ((9, 11), (3, 2), (1, 1), (2, 3), "VALID"),
        ((10, 12), (5, 5), (3, 2), (1, 1), "VALID"),
    ],
)
def test_conv2d_follows_tensorflow_s_nhwc_padding_strides_and_dilations(
    size: tuple[int, int],
    kernel: tuple[int, int],
    strides: tuple[int, int],
    dilations: tuple[int, int],
    padding: str,
) -> None:
    rng = np.random.default_rng(1)
    g = GraphWriter()
    x = g.placeholder("x", [-1, *size, 2])
    weights = g.const("k", rng.normal(size=(*kernel, 2, 3)).astype(np.float32))
    g.op(
        "conv", "Conv2D", x, weights,
        strides=attr_ints([1, *strides, 1]), dilations=attr_ints([1, *dilations, 1]),
        padding=attr_s(padding), data_format=attr_s("NHWC"),
    )  # fmt: skip
    graph = read_graph(bytes(g))
    feed = {"x": rng.normal(size=(2, *size, 2))}
    np.testing.assert_allclose(
        GraphRunner(graph, "conv").run(feed), run_reference(graph, "conv", feed), atol=1e-5
    )


@pytest.mark.parametrize("padding", ["SAME", "VALID"])
def test_max_pool_never_picks_a_padded_cell(padding: str) -> None:
    g = GraphWriter()
    x = g.placeholder("x", [-1, 5, 7, 1])
    g.op(
        "pool", "MaxPool", x,
        ksize=attr_ints([1, 2, 2, 1]), strides=attr_ints([1, 2, 2, 1]), padding=attr_s(padding),
    )  # fmt: skip
    graph = read_graph(bytes(g))
    feed = {"x": -1.0 - np.random.default_rng(0).uniform(size=(1, 5, 7, 1))}  # all negative
    ours = GraphRunner(graph, "pool").run(feed)
    np.testing.assert_allclose(ours, run_reference(graph, "pool", feed), atol=1e-6)
    assert ours.shape == ((1, 3, 4, 1) if padding == "SAME" else (1, 2, 3, 1))
    assert (ours < 0).all()


def test_flatten_keeps_tensorflow_s_nhwc_element_order() -> None:
    g = GraphWriter()
    x = g.placeholder("x", [-1, 2, 3, 4])
    flatten(g, "flat", x)
    feed = {"x": np.arange(2 * 24, dtype=np.float32).reshape(2, 2, 3, 4)}
    out = GraphRunner(read_graph(bytes(g)), "flat/Reshape").run(feed)
    np.testing.assert_array_equal(out, feed["x"].reshape(2, 24))


def test_dense_layers_batch_norm_and_shape_ops() -> None:
    rng = np.random.default_rng(4)
    g = GraphWriter()
    x = g.placeholder("x", [-1, 3])
    mm = g.op(
        "mm", "MatMul", x, g.const("w", rng.normal(size=(4, 3))),
        transpose_b=attr_b(True),
    )  # fmt: skip
    bn_args = [g.const(name, rng.uniform(0.5, 1.5, 4)) for name in ("s", "o", "m", "v")]
    bn = g.op(
        "bn", "FusedBatchNormV3", mm, *bn_args,
        epsilon=attr_f(0.001), is_training=attr_b(False), data_format=attr_s("NHWC"),
    )  # fmt: skip
    tanh = g.op("tanh", "Tanh", bn)
    both = g.op("cat", "ConcatV2", tanh, tanh, g.const("axis", np.int32(1)), N=attr_i(2))
    expanded = g.op("ex", "ExpandDims", both, g.const("at", np.int32(0)))
    g.op("sq", "Squeeze", expanded, squeeze_dims=attr_ints([0]))
    g.op("cast", "Cast", "sq", DstT=attr_type(np.int32), SrcT=attr_type(np.float32))
    graph = read_graph(bytes(g))
    feed = rng.normal(size=(2, 3))
    scale, offset, mean, var = (graph.node(n).constant().astype(float) for n in "somv")
    expected = np.tanh((feed @ graph.node("w").constant().T - mean) / np.sqrt(var + 0.001)
                       * scale + offset)  # fmt: skip
    out = GraphRunner(graph, "sq").run({"x": feed})
    np.testing.assert_allclose(out, np.concatenate([expected, expected], axis=1), atol=1e-5)
    assert GraphRunner(graph, "cast").run({"x": feed}).dtype == np.int32


def test_a_wrongly_shaped_input_is_refused_in_one_sentence() -> None:
    graph = read_graph(camera_policy_graph())
    runner = GraphRunner(graph, POLICY_OUTPUT)
    with pytest.raises(
        CarModelError, match=r"takes shape \['\?', 120, 160, 1\], not \[1, 60, 80, 1\]"
    ):
        runner.run({CAMERA_INPUT: np.zeros((1, 60, 80, 1))})
    with pytest.raises(CarModelError, match="needs a value for its input"):
        runner.run({})


def test_batch_norm_in_training_mode_is_refused() -> None:
    g = GraphWriter()
    x = g.placeholder("x", [-1, 2])
    args = [g.const(name, np.ones(2)) for name in ("s", "o", "m", "v")]
    g.op("bn", "FusedBatchNorm", x, *args, is_training=attr_b(True))
    runner = GraphRunner(read_graph(bytes(g)), "bn")
    with pytest.raises(CarModelError, match="training mode"):
        runner.run({"x": np.ones((1, 2))})
