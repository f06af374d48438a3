"""A trained network's deterministic actor in numpy: how races drive a policy.

For one car per step, torch's per-call overhead is most of the cost of a small network,
and oneDNN's convolutions at a batch of one run far below what the CPU can do. Here each
convolution is one copy of its patches into a buffer made once and one matrix product
(OpenBLAS), written into the buffer the next layer reads: a default camera network's
actor takes about a third of torch's time on a CPU core. It is the same function as
`PolicyNetwork.act`; the last bits differ (another order of sums), so camera races
driven this way are a policy runtime of their own (`sim.training.runtimes`).

Weights are copied once, so later training does not show here.
"""

from __future__ import annotations

import threading
from collections.abc import Mapping
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.lib.stride_tricks import as_strided
from numpy.typing import NDArray
from threadpoolctl import threadpool_limits
from torch import nn

from sim.training.policy import CAMERA_POOL

if TYPE_CHECKING:
    from sim.training.policy import PolicyNetwork

Array = NDArray[Any]
# Below this many input channels a convolution's patches are copied tap by tap (rows of
# output positions); above it, patch by patch (rows of channels). Measured on a default
# camera network: the first layer's one channel copies 3 times faster by taps.
_TAPS_FIRST_BELOW = 4


def one_blas_thread() -> None:
    """Hold numpy's BLAS to one thread in this process, as `PolicyDriver` holds torch's.
    A race's matrices are small: a second thread only adds hand-offs (three times slower
    on a busy 2-core machine), and a policy computes on one thread wherever it runs."""
    threadpool_limits(limits=1, user_api="blas")


class _Convolution:
    """One convolution and its ReLU over a channels-last buffer, into another.

    The ReLUs take their maximum against an array of zeros, not the scalar 0: the same
    values to the bit (-0.0 and NaN included), and numpy's array-against-array loop is
    four times quicker at these sizes (1.9 against 7.1 µs for the first layer's)."""

    def __init__(self, source: Array, layer: nn.Conv2d, scale: float) -> None:
        batch, height, width, channels = source.shape
        (kernel, _), (stride, _) = layer.kernel_size, layer.stride
        rows, columns = (height - kernel) // stride + 1, (width - kernel) // stride + 1
        weight = layer.weight.detach().numpy()  # (out, in, kernel, kernel)
        out = weight.shape[0]
        on_batch, on_row, on_column, on_channel = source.strides
        taps = channels < _TAPS_FIRST_BELOW
        strides: tuple[int, ...]
        if taps:  # (batch, tap row, tap column, channel, row, column)
            shape = (batch, kernel, kernel, channels, rows, columns)
            strides = (on_batch, on_row, on_column, on_channel, on_row * stride)
            strides += (on_column * stride,)
        else:  # (batch, row, column, tap row, tap column, channel)
            shape = (batch, rows, columns, kernel, kernel, channels)
            strides = (on_batch, on_row * stride, on_column * stride, on_row, on_column)
            strides += (on_channel,)
        self.patches_of_source = as_strided(source, shape, strides, writeable=False)
        size = kernel * kernel * channels
        # The matrix of patches has one more entry per patch, a constant 1 that meets the
        # bias in the weights' last row: the product adds the bias (a separate add of a
        # broadcast bias cost as much as the product in the first layer).
        if taps:
            matrix = np.ones((batch, size + 1, rows * columns), dtype=np.float32)
            self.patches = matrix[:, :size].reshape(shape)
            self.matrix = matrix.transpose(0, 2, 1)
        else:
            matrix = np.ones((batch, rows * columns, size + 1), dtype=np.float32)
            self.patches = matrix[:, :, :size].reshape(shape)
            self.matrix = matrix
        # The patches must be written into the matrix itself (reshape would copy silently).
        assert np.shares_memory(self.patches, matrix)
        # Rows in the patches' order (tap row, tap column, channel), then the bias.
        kernel_rows = weight.transpose(2, 3, 1, 0).reshape(size, out) * np.float32(scale)
        bias = layer.bias.detach().numpy()  # type: ignore[union-attr]
        self.weight = np.ascontiguousarray(np.vstack([kernel_rows, bias]), dtype=np.float32)
        self.output = np.empty((batch, rows, columns, out), dtype=np.float32)
        self._flat_output = self.output.reshape(batch, rows * columns, out)
        self._zeros = np.zeros_like(self._flat_output)

    def __call__(self) -> None:
        np.copyto(self.patches, self.patches_of_source)
        np.matmul(self.matrix, self.weight, out=self._flat_output)
        np.maximum(self._flat_output, self._zeros, out=self._flat_output)


class _CameraPass:
    """A camera encoder for one batch size: its buffers are made once and reused."""

    def __init__(self, camera: nn.Sequential, batch: int, shape: tuple[int, ...]) -> None:
        pool = CAMERA_POOL  # the camera network's first layer, an average pool
        height, width, channels = shape
        self.rows, self.columns, self.pool = height // pool, width // pool, pool
        # The pool's sum, in float32 (exact: at most 255 * pool * pool); its mean's scale
        # goes into the first convolution's weights.
        self.sums = np.empty((batch, self.rows, self.columns, channels), dtype=np.float32)
        # The pools' rows summed first: whole image rows at a time, the fast way through
        # memory; then the row sums' neighbouring columns (1.5 times faster than adding a
        # pool's four cells, each every other pixel).
        self.row_sums = np.empty((batch, self.rows, self.columns * pool, channels), np.float32)
        self.layers: list[_Convolution] = []
        source, scale = self.sums, 1.0 / (255.0 * pool * pool)
        for layer in camera:
            if isinstance(layer, nn.Conv2d):
                self.layers.append(_Convolution(source, layer, scale))
                source, scale = self.layers[-1].output, 1.0
        dense = next(layer for layer in camera if isinstance(layer, nn.Linear))
        _, rows, columns, last = source.shape
        # torch flattens channels first (channel, row, column); the buffers are channels
        # last, so the dense weights' columns are put in that order instead.
        weight = dense.weight.detach().numpy()
        weight = weight.reshape(-1, last, rows, columns).transpose(2, 3, 1, 0)
        self.dense = weight.reshape(rows * columns * last, -1).copy()  # its own, C order
        self.dense_bias = dense.bias.detach().numpy().astype(np.float32)
        self.flat = source.reshape(batch, -1)
        self.features = np.empty((batch, self.dense.shape[1]), dtype=np.float32)
        self._zeros = np.zeros_like(self.features)

    def __call__(self, frames: Array) -> Array:
        pool, rows, columns = self.pool, self.rows, self.columns
        # The frames come as the Observer makes them (any strides); sums are exact.
        image = frames[:, : rows * pool, : columns * pool, :]
        np.add(image[:, 0::pool], image[:, 1::pool], out=self.row_sums, dtype=np.float32)
        for row in range(2, pool):
            np.add(self.row_sums, image[:, row::pool], out=self.row_sums, dtype=np.float32)
        np.add(self.row_sums[:, :, 0::pool], self.row_sums[:, :, 1::pool], out=self.sums)
        for column in range(2, pool):
            np.add(self.sums, self.row_sums[:, :, column::pool], out=self.sums)
        for layer in self.layers:
            layer()
        np.matmul(self.flat, self.dense, out=self.features)
        np.add(self.features, self.dense_bias, out=self.features)
        np.maximum(self.features, self._zeros, out=self.features)
        return self.features


class NumpyActor:
    """The deterministic actor of a network (`PolicyNetwork.act`) in numpy.

    Camera-free networks compute in float64 (the same function as torch's, a test holds
    them equal); a camera's encoder in float32 as above, then the same float64 layers.
    One actor serves one driver: its buffers are reused, so calls take turns.
    """

    def __init__(self, network: PolicyNetwork) -> None:
        self.spec = network.spec
        self.layers = [
            (layer.weight.detach().numpy().T.astype(np.float64), layer.bias.detach().numpy().copy())
            for layer in network.policy_mlp
            if isinstance(layer, nn.Linear)
        ]
        head = network.action_head
        self.head = (
            head.weight.detach().numpy().T.astype(np.float64),
            head.bias.detach().numpy().copy(),
        )
        self._camera = network.camera
        self._camera_shape = next(
            (
                shape
                for sensor, shape in zip(self.spec.sensors, self.spec.input_shapes, strict=True)
                if sensor == "camera"
            ),
            (),
        )
        self._passes: dict[int, _CameraPass] = {}  # by batch size
        self._turn = threading.Lock()

    def _camera_features(self, frames: Array) -> Array:
        assert self._camera is not None
        batch = len(frames)
        if batch not in self._passes:
            self._passes[batch] = _CameraPass(self._camera, batch, self._camera_shape)
        return self._passes[batch](frames)

    def act(self, obs: Array | Mapping[str, Array]) -> Array:
        """Deterministic actions: the most likely discrete action, or the Gaussian mean."""
        out = self.action_parameters(obs)
        if self.spec.action_kind == "discrete":
            return np.asarray(out.argmax(axis=1))
        return np.asarray(np.clip(out, -1.0, 1.0), dtype=np.float32)

    def action_parameters(self, obs: Array | Mapping[str, Array]) -> NDArray[np.float64]:
        """Logits (discrete) or Gaussian means (continuous), as `PolicyNetwork`'s."""
        with self._turn:
            parts = []
            for sensor in self.spec.sensors:
                value = obs[sensor] if isinstance(obs, Mapping) else obs
                if sensor == "camera":
                    parts.append(self._camera_features(np.asarray(value)).astype(np.float64))
                    continue
                value = np.asarray(value, dtype=np.float64)
                value = value.reshape(len(value), -1)
                parts.append(value / self.spec.lidar_range if sensor == "lidar" else value)
        x = parts[0] if len(parts) == 1 else np.concatenate(parts, axis=1)
        for weight, bias in self.layers:
            x = x @ weight
            x += bias
            np.tanh(x, out=x)
        out: NDArray[np.float64] = x @ self.head[0]
        out += self.head[1]
        return out
