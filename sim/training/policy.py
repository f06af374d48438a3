"""The policy network of a model, its tensor-only file, and the driver that races it.

One network class serves training (wrapped by `sim.training.ppo.RacerPolicy`), evaluation
and races, so the weights in `policy.safetensors` are exactly what was trained. The
network is always rebuilt from `model_metadata.json` (sensors, action space, network size)
and only then filled with tensors: a policy file is data, never code. Every tensor name,
shape and dtype is checked, and the architecture facts written in the file's metadata
must match the rebuilt network.

Layout: each sensor is encoded (a small CNN for the camera, scaled values for lidar and
the vector state), the encodings are concatenated, and two MLPs read them: the policy
(logits over a discrete action space, or the mean of a Gaussian over the normalised
continuous one) and the value function.
"""

from __future__ import annotations

import functools
import hashlib
import itertools
import json
import math
import platform
import struct
import weakref
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
import torch
from numpy.typing import NDArray
from safetensors import SafetensorError
from safetensors.torch import load, save
from torch import nn

from sim.car_archive.archive import read_car_archive
from sim.car_archive.driver import CarArchiveDriver
from sim.car_archive.errors import CarModelError
from sim.deepracer.action_space import discrete_grid
from sim.deepracer.files import NEURAL_NETWORKS, ModelMetadata
from sim.foundation.atomic import write_bytes_atomic
from sim.foundation.remedies import Fix
from sim.garage.folder import ModelError
from sim.physics.simulation import TrackSimulation
from sim.race.driver import Driver, DriverAction
from sim.sensors.observations import VECTOR_SIZE, Observer, SensorOptions
from sim.training.errors import PolicyError

if TYPE_CHECKING:
    from sim.garage.bundle import Bundle
    from sim.garage.folder import ModelFolder

__all__ = [
    "NetworkSpec",
    "PolicyDriver",
    "PolicyError",
    "PolicyNetwork",
    "build_network",
    "driver_for_bundle",
    "driver_for_model",
    "load_policy",
    "policy_bytes",
    "save_policy",
]

POLICY_FORMAT = "racer-tui-policy/1"
MAX_POLICY_BYTES = 256_000_000
MAX_HEADER_BYTES = 1_000_000
SECTOR_COUNT = 8

# Hidden layers of the policy and value MLPs for DeepRacer's three network sizes.
HIDDEN_SIZES: dict[str, tuple[int, ...]] = {
    "DEEP_CONVOLUTIONAL_NETWORK_SHALLOW": (64, 64),
    "DEEP_CONVOLUTIONAL_NETWORK": (128, 128),
    "DEEP_CONVOLUTIONAL_NETWORK_DEEP": (256, 256),
}
# Camera CNN: (out channels, kernel, stride) per layer, after a 2x average pool. Much
# smaller than SB3's NatureCNN so camera training is practical on a laptop CPU.
CONV_LAYERS: dict[str, tuple[tuple[int, int, int], ...]] = {
    "DEEP_CONVOLUTIONAL_NETWORK_SHALLOW": ((16, 5, 2), (32, 3, 2), (32, 3, 2)),
    "DEEP_CONVOLUTIONAL_NETWORK": ((32, 5, 2), (32, 3, 2), (64, 3, 2)),
    "DEEP_CONVOLUTIONAL_NETWORK_DEEP": ((32, 5, 2), (64, 3, 2), (64, 3, 2), (64, 3, 1)),
}
CAMERA_FEATURES = 128
CAMERA_POOL = 2

Observation = torch.Tensor | dict[str, torch.Tensor]


@dataclass(frozen=True)
class NetworkSpec:
    """Everything that fixes the network's tensors; written into the policy file."""

    sensors: tuple[str, ...]
    input_shapes: tuple[tuple[int, ...], ...]  # one per sensor, as the Observer makes them
    action_kind: str  # "discrete" or "continuous"
    action_count: int  # discrete: number of actions; continuous: 2 (steering, speed)
    network: str  # DeepRacer's neural_network name
    hidden: tuple[int, ...]
    conv: tuple[tuple[int, int, int], ...]  # empty without a camera
    lidar_range: float

    def facts(self) -> dict[str, str]:
        """Safetensors metadata (string to string)."""
        return {
            "format": POLICY_FORMAT,
            "sensors": json.dumps(list(self.sensors)),
            "input_shapes": json.dumps([list(shape) for shape in self.input_shapes]),
            "action_kind": self.action_kind,
            "action_count": str(self.action_count),
            "neural_network": self.network,
            "hidden": json.dumps(list(self.hidden)),
            "conv": json.dumps([list(layer) for layer in self.conv]),
            "lidar_range": repr(self.lidar_range),
        }


def network_spec(
    metadata: ModelMetadata, sensor_options: SensorOptions | None = None
) -> NetworkSpec:
    """The network a model's metadata calls for."""
    options = sensor_options or SensorOptions()
    shapes: list[tuple[int, ...]] = []
    for sensor in metadata.sensors:
        if sensor == "camera":
            shapes.append((options.camera_height, options.camera_width, 1))
        elif sensor == "lidar":
            shapes.append((options.lidar_rays,))
        elif sensor == "sector_lidar":
            shapes.append((SECTOR_COUNT,))
        else:
            shapes.append((VECTOR_SIZE,))
    space = metadata.action_space
    network = metadata.neural_network if metadata.neural_network in NEURAL_NETWORKS else ""
    network = network or NEURAL_NETWORKS[0]
    return NetworkSpec(
        sensors=tuple(metadata.sensors),
        input_shapes=tuple(shapes),
        action_kind=space.kind,
        action_count=len(space.actions) if space.kind == "discrete" else 2,
        network=network,
        hidden=HIDDEN_SIZES[network],
        conv=CONV_LAYERS[network] if "camera" in metadata.sensors else (),
        lidar_range=float(options.lidar_range),
    )


def _mlp(inputs: int, hidden: tuple[int, ...]) -> nn.Sequential:
    layers: list[nn.Module] = []
    for size in hidden:
        layers += [nn.Linear(inputs, size), nn.Tanh()]
        inputs = size
    return nn.Sequential(*layers)


def _camera_encoder(
    shape: tuple[int, ...], conv: tuple[tuple[int, int, int], ...]
) -> tuple[nn.Sequential, int]:
    height, width = shape[0] // CAMERA_POOL, shape[1] // CAMERA_POOL
    layers: list[nn.Module] = [nn.AvgPool2d(CAMERA_POOL)]
    channels = shape[2]
    for out_channels, kernel, stride in conv:
        layers += [nn.Conv2d(channels, out_channels, kernel, stride), nn.ReLU()]
        channels = out_channels
        height = (height - kernel) // stride + 1
        width = (width - kernel) // stride + 1
    if height < 1 or width < 1:
        raise PolicyError("the camera image is too small for the camera network.")
    layers += [nn.Flatten(), nn.Linear(channels * height * width, CAMERA_FEATURES), nn.ReLU()]
    return nn.Sequential(*layers), CAMERA_FEATURES


class PolicyNetwork(nn.Module):
    """Actor and critic over a model's sensors. Observations are what `Observer` makes:
    one array for a single sensor, or a dict keyed by sensor name."""

    def __init__(self, spec: NetworkSpec) -> None:
        super().__init__()
        self.spec = spec
        self.camera = None
        flat = 0
        for sensor, shape in zip(spec.sensors, spec.input_shapes, strict=True):
            if sensor == "camera":
                self.camera, size = _camera_encoder(shape, spec.conv)
                flat += size
            else:
                flat += int(np.prod(shape))
        self.features_dim = flat
        self.policy_mlp = _mlp(flat, spec.hidden)
        self.value_mlp = _mlp(flat, spec.hidden)
        last = spec.hidden[-1] if spec.hidden else flat
        self.action_head = nn.Linear(last, spec.action_count)
        self.value_head = nn.Linear(last, 1)
        self.log_std = (
            nn.Parameter(torch.zeros(spec.action_count))
            if spec.action_kind == "continuous"
            else None
        )
        # Camera observations come as `pooled_frames` made them (a training's), not as the
        # Observer's uint8 frames.
        self.frames_prepared = False
        # The convolutions in bfloat16 (a training's forward passes, on CPUs with bf16 in
        # hardware: `native_bf16`); evaluations and races always run float32.
        self.bf16_convolutions = False

    # --- the forward pieces the trainer and the driver share --------------------------------
    def camera_frames(self, frames: torch.Tensor) -> torch.Tensor:
        """The camera network's weightless first steps: the Observer's uint8 frames
        (channels last) as floats in [0, 1], channels first, pooled. Races and evaluations
        take them on every call, and their replays hold to these last bits; a training
        takes `pooled_frames` instead (`frames_prepared`)."""
        assert self.camera is not None
        image = frames.float().permute(0, 3, 1, 2) / 255.0
        pooled: torch.Tensor = self.camera[0](image)
        return pooled

    def features(self, obs: Observation) -> torch.Tensor:
        parts: list[torch.Tensor] = []
        for sensor in self.spec.sensors:
            value = obs[sensor] if isinstance(obs, Mapping) else obs
            if sensor == "camera":
                assert self.camera is not None
                pooled = (
                    value.permute(0, 3, 1, 2) if self.frames_prepared else self.camera_frames(value)
                )
                layers = list(self.camera)[1:]
                if self.bf16_convolutions:
                    dense = 3  # Flatten, Linear, ReLU: float32 from there on
                    with torch.autocast("cpu", dtype=torch.bfloat16):
                        for layer in layers[:-dense]:
                            pooled = layer(pooled)
                    pooled = pooled.float()
                    layers = layers[-dense:]
                for layer in layers:
                    pooled = layer(pooled)
                parts.append(pooled)
            elif sensor == "lidar":
                parts.append(value.float().flatten(1) / self.spec.lidar_range)
            else:
                parts.append(value.float().flatten(1))
        return parts[0] if len(parts) == 1 else torch.cat(parts, dim=1)

    def action_parameters(self, features: torch.Tensor) -> torch.Tensor:
        """Logits (discrete) or Gaussian means in [-1, 1] units (continuous)."""
        out: torch.Tensor = self.action_head(self.policy_mlp(features))
        return out

    def value(self, features: torch.Tensor) -> torch.Tensor:
        out: torch.Tensor = self.value_head(self.value_mlp(features))
        return out

    def forward(self, obs: Observation) -> tuple[torch.Tensor, torch.Tensor]:
        features = self.features(obs)
        return self.action_parameters(features), self.value(features)

    def act(self, obs: Observation) -> torch.Tensor:
        """Deterministic actions: the most likely discrete action, or the Gaussian mean."""
        params = self.action_parameters(self.features(obs))
        if self.spec.action_kind == "discrete":
            return params.argmax(dim=1)
        return params.clamp(-1.0, 1.0)


def pooled_frames(frames: NDArray[Any]) -> NDArray[np.float32]:
    """The camera network's weightless first steps as a training takes them, in numpy:
    frames (..., height, width, channels) of 0-255 values (the Observer's uint8, or float32
    copies of them) as floats in [0, 1], pooled as the network's
    first layer pools, channels last. Within a float32 unit of `PolicyNetwork.camera_frames`
    (it sums each pool's pixels exactly, then scales once), and about 20 times faster on a
    CPU core than torch's conversion and pooling, which were a fifth of a camera training.
    Races and evaluations keep `camera_frames`, whose last bits their replays hold to."""
    *lead, height, width, channels = frames.shape
    rows, columns = height // CAMERA_POOL, width // CAMERA_POOL
    cropped = frames[..., : rows * CAMERA_POOL, : columns * CAMERA_POOL, :]
    # Strided views added one by one (numpy's sum over the pools' axes is ten times slower),
    # in whole numbers for the Observer's bytes: exact either way.
    exact = np.uint16 if frames.dtype == np.uint8 else np.float32
    sums = np.zeros((*lead, rows, columns, channels), dtype=exact)
    for row, column in itertools.product(range(CAMERA_POOL), repeat=2):
        sums += cropped[..., row::CAMERA_POOL, column::CAMERA_POOL, :]
    scale = np.float32(1.0 / (255.0 * CAMERA_POOL * CAMERA_POOL))
    pooled: NDArray[np.float32] = sums.astype(np.float32) * scale
    return pooled


def native_bf16() -> bool:
    """Whether this CPU computes bfloat16 in hardware (AVX512-BF16 or AMX). Elsewhere oneDNN
    emulates it, slower than float32, so a training keeps float32 there."""
    checks = ("_is_avx512_bf16_supported", "_is_amx_tile_supported")
    # Private to torch.cpu, so looked up with a default: a torch without them says no.
    return any(bool(getattr(torch.cpu, name, lambda: False)()) for name in checks)


def init_weights(network: PolicyNetwork) -> None:
    """Orthogonal initialisation as in SB3/baselines PPO: small policy outputs at first."""
    gains: list[tuple[nn.Module, float]] = [
        (network.policy_mlp, math.sqrt(2.0)),
        (network.value_mlp, math.sqrt(2.0)),
        (network.action_head, 0.01),
        (network.value_head, 1.0),
    ]
    if network.camera is not None:
        gains.append((network.camera, math.sqrt(2.0)))
    for module, gain in gains:
        for layer in module.modules():
            if isinstance(layer, nn.Linear | nn.Conv2d):
                nn.init.orthogonal_(layer.weight, gain=gain)
                if layer.bias is not None:
                    nn.init.zeros_(layer.bias)


def build_network(
    metadata: ModelMetadata, sensor_options: SensorOptions | None = None
) -> PolicyNetwork:
    """A freshly initialised network for a model."""
    network = PolicyNetwork(network_spec(metadata, sensor_options))
    init_weights(network)
    return network


# --- the policy file ----------------------------------------------------------------------


def policy_bytes(network: PolicyNetwork) -> bytes:
    """The network as safetensors bytes, architecture facts in the metadata."""

    tensors = {
        name: tensor.detach().to(torch.float32).contiguous().clone()
        for name, tensor in network.state_dict().items()
    }
    return bytes(save(tensors, metadata=network.spec.facts()))


def save_policy(path: Path, network: PolicyNetwork) -> None:
    """Write `policy.safetensors` atomically: readers see the old file or the new one."""
    write_bytes_atomic(path, policy_bytes(network))


def _read_policy_bytes(path: Path) -> bytes:
    try:
        size = path.stat().st_size
        if size > MAX_POLICY_BYTES:
            raise PolicyError(f"{path} is {size:,} bytes, too large to be a policy file.")
        return path.read_bytes()
    except FileNotFoundError:
        raise PolicyError(f"{path} does not exist; train the model first.") from None
    except OSError as error:
        raise PolicyError(f"cannot read {path} ({error.strerror}).") from None


def read_policy_header(data: bytes, where: str = "policy") -> dict[str, Any]:
    """The safetensors JSON header, parsed by hand so non-safetensors data fails clearly."""
    not_policy = f"{where} is not a safetensors policy file; retrain or re-export the model."
    if len(data) < 8:
        raise PolicyError(not_policy)
    (length,) = struct.unpack("<Q", data[:8])
    if length > MAX_HEADER_BYTES or 8 + length > len(data):
        raise PolicyError(not_policy)
    try:
        header = json.loads(data[8 : 8 + length].decode("utf-8"))
    except (UnicodeDecodeError, json.JSONDecodeError):
        raise PolicyError(not_policy) from None
    if not isinstance(header, dict):
        raise PolicyError(not_policy)
    return header


def _facts(header: Mapping[str, Any], where: str) -> dict[str, str]:
    facts = header.get("__metadata__")
    if (
        not isinstance(facts, dict)
        or facts.get("format") != POLICY_FORMAT
        or not all(isinstance(v, str) for v in facts.values())
    ):
        raise PolicyError(
            f"{where} was not written by racer-tui (format {POLICY_FORMAT} expected); "
            "retrain or re-export the model."
        )
    return dict(facts)


def load_policy(
    path_or_bytes: Path | bytes,
    metadata: ModelMetadata,
    sensor_options: SensorOptions | None = None,
) -> PolicyNetwork:
    """Rebuild the network from `metadata` and fill it with the file's tensors.

    Raises PolicyError when the data is not a racer-tui safetensors policy, was made for a
    different car (sensors, action space, network size), or has any tensor missing, extra,
    of another shape or of another dtype. Nothing in the file is ever executed.
    """
    data, where = policy_data(path_or_bytes)
    facts, tensors = open_tensors(data, where)
    network = PolicyNetwork(network_spec(metadata, sensor_options))
    fill_network(network, facts, tensors, where)
    return network


def policy_data(path_or_bytes: Path | bytes) -> tuple[bytes, str]:
    """The bytes of a policy (read with a size limit) and how to name them in errors."""
    if isinstance(path_or_bytes, bytes | bytearray):
        if len(path_or_bytes) > MAX_POLICY_BYTES:
            raise PolicyError("the policy data is too large to be a policy file.")
        return bytes(path_or_bytes), "the policy data"
    return _read_policy_bytes(Path(path_or_bytes)), str(path_or_bytes)


def open_tensors(data: bytes, where: str) -> tuple[dict[str, str], dict[str, torch.Tensor]]:
    """(architecture facts, tensors) of racer-tui safetensors data, or PolicyError."""
    facts = _facts(read_policy_header(data, where), where)

    try:
        tensors = load(data)
    except (SafetensorError, ValueError, RuntimeError):
        raise PolicyError(f"{where} is damaged; retrain or re-export the model.") from None
    return facts, tensors


def fill_network(
    network: PolicyNetwork,
    facts: Mapping[str, str],
    tensors: Mapping[str, torch.Tensor],
    where: str,
) -> None:
    """Load `tensors` into `network` after checking the facts and every name, shape, dtype."""
    for key, value in network.spec.facts().items():
        if facts.get(key) != value:
            raise PolicyError(
                f"{where} was trained for a different car ({key} is {facts.get(key)!r}, "
                f"the model needs {value!r}); retrain the model or use the matching metadata."
            )
    wanted = network.state_dict()
    missing = sorted(set(wanted) - set(tensors))
    extra = sorted(set(tensors) - set(wanted))
    if missing or extra:
        names = ", ".join((missing or extra)[:3])
        problem = "lacks" if missing else "has unexpected"
        raise PolicyError(f"{where} {problem} tensors ({names}); retrain the model.")
    check_tensors(tensors, {name: tuple(t.shape) for name, t in wanted.items()}, where)
    network.load_state_dict(dict(tensors))
    network.eval()


def check_tensors(
    tensors: Mapping[str, torch.Tensor], shapes: Mapping[str, tuple[int, ...]], where: str
) -> None:
    """Every tensor named in `shapes` is float32, of that shape, and finite."""
    for name, shape in shapes.items():
        tensor = tensors[name]
        if tensor.dtype != torch.float32 or tuple(tensor.shape) != shape:
            raise PolicyError(
                f"{where}: tensor {name} is {tensor.dtype} {tuple(tensor.shape)}, the model "
                f"needs float32 {shape}; retrain the model."
            )
        if not bool(torch.isfinite(tensor).all()):
            raise PolicyError(f"{where}: tensor {name} holds NaN or infinite values.")


# --- driving -------------------------------------------------------------------------------


def observation_tensors(obs: Any) -> Observation:
    """Observer output (an array or a dict of arrays) as tensors, without copying."""
    if isinstance(obs, dict):
        return {key: torch.as_tensor(value) for key, value in obs.items()}
    return torch.as_tensor(obs)


class NumpyActor:
    """The deterministic actor of a camera-free network as a few numpy matrix products.

    For one car per step, torch's per-call overhead is most of the cost of a tiny MLP;
    this is the same arithmetic as `PolicyNetwork.act` (a test holds them equal) at a
    fraction of the time. Weights are copied once, so later training does not show here.
    """

    def __init__(self, network: PolicyNetwork) -> None:
        if network.camera is not None:
            raise ValueError("camera networks run in torch")
        self.spec = network.spec
        self.layers = [
            (layer.weight.detach().numpy().T.astype(np.float64), layer.bias.detach().numpy())
            for layer in network.policy_mlp
            if isinstance(layer, nn.Linear)
        ]
        head = network.action_head
        self.head = (head.weight.detach().numpy().T.astype(np.float64), head.bias.detach().numpy())

    def act(self, obs: Any) -> NDArray[Any]:
        parts = []
        for sensor in self.spec.sensors:
            value = np.asarray(obs[sensor] if isinstance(obs, dict) else obs, dtype=np.float64)
            value = value.reshape(len(value), -1)
            parts.append(value / self.spec.lidar_range if sensor == "lidar" else value)
        x = parts[0] if len(parts) == 1 else np.concatenate(parts, axis=1)
        for weight, bias in self.layers:
            x = np.tanh(x @ weight + bias)
        out = x @ self.head[0] + self.head[1]
        if self.spec.action_kind == "discrete":
            return np.asarray(out.argmax(axis=1))
        return np.asarray(np.clip(out, -1.0, 1.0), dtype=np.float32)


def _batched(parts: Sequence[NDArray[Any]]) -> NDArray[Any]:
    """Several cars' observations as one batch, laid out as one car's is. A one-channel
    camera's frames come with their channel axis added last (`Observer`: stride 0), which
    torch pools as a plain NCHW image; concatenated whole, their channel axis had stride 1,
    torch took the batch for channels-last and pooled it 8 times slower (0.34 ms against
    0.04 ms a step in a two-car race)."""
    if parts[0].ndim == 4 and parts[0].shape[-1] == 1:
        return np.concatenate([part[..., 0] for part in parts])[..., None]
    return np.concatenate(parts)


class PolicyDriver:
    """A trained policy as a race `Driver`: deterministic, one action per car.

    Inference calls the network directly (no SB3 `predict` loop; numpy for camera-free
    networks), so a 4-minute race with a vector or lidar model simulates in well under a
    second. `live=True` keeps reading the torch network (the trainer's evaluations, while
    its weights change); otherwise the weights are fixed when the driver is made.
    """

    def __init__(
        self,
        network: PolicyNetwork,
        metadata: ModelMetadata,
        *,
        name: str,
        content_hash: str,
        sensor_options: SensorOptions | None = None,
        live: bool = False,
    ) -> None:
        # A batch of one observation is too small to share between cores: extra torch
        # threads only add synchronisation (several times slower on a busy 2-core machine),
        # wherever the race runs (the CLI, the app's workers, a league night).
        torch.set_num_threads(1)
        self.network = network.eval()
        self._fast = None if live or network.camera is not None else NumpyActor(network)
        self.metadata = metadata
        self.name = name
        self.content_hash = content_hash
        self._options = sensor_options or SensorOptions()
        # The numerics it drives with: recorded on its races, which verification by replay
        # judges only under the same (`policy_runtime`).
        self.runtime = policy_runtime()
        # One Observer per simulation it drives in: a head-to-head race gives each car a
        # simulation of its own, and one model may drive several of them.
        self._observers: weakref.WeakKeyDictionary[TrackSimulation, Observer] = (
            weakref.WeakKeyDictionary()
        )

    def reset(self, sim: TrackSimulation) -> None:
        self._observers[sim] = Observer(sim, self.metadata.sensors, self._options)

    def _observe(self, sim: TrackSimulation) -> Any:
        observer = self._observers.get(sim)
        if observer is None:
            self.reset(sim)
            observer = self._observers[sim]
        return observer.observe()

    def _actions_of(self, obs: Any) -> NDArray[Any]:
        if self._fast is not None:
            return self._fast.act(obs)
        with torch.inference_mode():
            actions = self.network.act(observation_tensors(obs))
        return actions.numpy()

    def actions(self, sim: TrackSimulation) -> NDArray[Any]:
        """Raw policy actions for every car: indices, or (N, 2) normalised values."""
        return self._actions_of(self._observe(sim))

    def act(self, sim: TrackSimulation) -> DriverAction:
        return self._driver_action(self.actions(sim))

    def act_many(self, sims: Sequence[TrackSimulation]) -> list[DriverAction]:
        """`act` for several simulations (a head-to-head race's cars of this model), their
        observations in one batch: one forward pass for all of them."""
        observed = [self._observe(sim) for sim in sims]
        if isinstance(observed[0], dict):
            obs: Any = {key: _batched([part[key] for part in observed]) for key in observed[0]}
        else:
            obs = _batched(observed)
        whole = self._driver_action(self._actions_of(obs))
        ends = list(itertools.accumulate(sim.n for sim in sims))
        return [
            DriverAction(
                steering_deg=whole.steering_deg[start:end],
                speed=whole.speed[start:end],
                action_index=whole.action_index[start:end],
            )
            for start, end in itertools.pairwise([0, *ends])
        ]

    def _driver_action(self, actions: NDArray[Any]) -> DriverAction:
        space = self.metadata.action_space
        steering, speed = space.targets(actions)
        if space.kind == "discrete":
            index = np.asarray(actions, dtype=np.int64).reshape(-1)
        else:
            index = np.full(len(actions), -1, dtype=np.int64)
        return DriverAction(
            steering_deg=np.asarray(steering, dtype=np.float64),
            speed=np.asarray(speed, dtype=np.float64),
            action_index=index,
        )


def driver_for_model(folder: ModelFolder) -> Driver:
    """The driver for a garage model's `policy.safetensors`, or for the car archive it was
    imported from (`sim.car_export`)."""
    if folder.drives_with_car_archive():
        try:
            archive = read_car_archive(folder.car_archive_file)
            return CarArchiveDriver(archive, name=folder.name, content_hash=folder.content_hash())
        except CarModelError as error:
            raise ModelError(f"model {folder.name!r}: {error}") from None
    if not folder.has_policy():
        problem = f"model {folder.name!r} has no trained policy yet"
        raise PolicyError(
            f"{problem}; train it first with `racer-tui train {folder.name}`.",
            problem=problem,
            fix=Fix.TRAIN_MODEL,
        )
    metadata = folder.metadata()
    network = load_policy(folder.policy_file, metadata)
    return PolicyDriver(network, metadata, name=folder.name, content_hash=folder.content_hash())


def driver_for_bundle(bundle: Bundle) -> PolicyDriver:
    """The driver for an exported model bundle (its tensors only; nothing is executed)."""
    network = load_policy(bundle.policy_bytes, bundle.metadata)
    return PolicyDriver(
        network, bundle.metadata, name=bundle.name, content_hash=bundle.content_hash
    )


# --- the policy runtime ------------------------------------------------------------------
# The policy runtime: the numerics this machine's policies compute with.
#
# A race replays exactly only where its policy computes exactly as it did. The libraries
# pick their kernels by the CPU: oneDNN's convolutions by its instruction set, OpenBLAS's
# matrix products by core type, numpy's ufuncs by its SIMD level, and an ARM machine takes
# other kernels again. Their results differ in the last bits (measured on this project's
# AMD EPYC: a camera network's outputs under oneDNN's SSE4.1 against AVX2, and a vector
# network's under OpenBLAS's Prescott kernels against Haswell's, and under numpy without
# AVX2), and a last bit can turn a near tie between two actions, and the race with it.
# (Torch's own capability level, DEFAULT against AVX2, changed a fresh network's random
# weights here, not a loaded network's outputs.)
#
# So the runtime is named by what it computes: a fixed camera network and a fixed vector
# network (the paths races take: torch for a camera, numpy for the rest), run on fixed
# inputs laid out as races lay them out, and the bits of their outputs hashed. Two machines
# with the same name compute a race's policy the same; a race is recorded with the name,
# and verification by replay judges a race only under the runtime that drove it.

# The camera races use: some kernels are picked by the size of what they work on.
_PROBE_CAMERA = SensorOptions()
_PROBE_ACTIONS = discrete_grid(30.0, 5, 3.0, 2)


def _fill(network: torch.nn.Module) -> None:
    """Fixed weights, the same on every machine: numpy's PCG64 gives the same doubles
    everywhere (torch's own generator does not: its CPU capability changes them)."""
    rng = np.random.Generator(np.random.PCG64(47))
    with torch.no_grad():
        for parameter in network.parameters():
            values = (rng.random(parameter.numel()) - 0.5) * 0.4
            parameter.copy_(torch.from_numpy(values).reshape(parameter.shape).to(parameter.dtype))


def _camera_bits() -> bytes:
    network = build_network(ModelMetadata(_PROBE_ACTIONS, ("camera",)), _PROBE_CAMERA).eval()
    _fill(network)
    height, width = _PROBE_CAMERA.camera_height, _PROBE_CAMERA.camera_width
    pattern = (np.arange(2 * height * width, dtype=np.int64) * 37 % 251).astype(np.uint8)
    # As the Observer gives them: frames with their one channel added last (stride 0); one
    # car's (a time trial) and two cars' (a head-to-head race's batch).
    bits = b""
    for cars in (1, 2):
        frames = pattern[: cars * height * width].reshape(cars, height, width)[..., None]
        with torch.inference_mode():
            params, values = network(observation_tensors(frames))
        bits += params.numpy().tobytes() + values.numpy().tobytes()
    return bits


def _vector_bits() -> bytes:
    network = build_network(ModelMetadata(_PROBE_ACTIONS, ("vector",))).eval()
    _fill(network)
    actor = NumpyActor(network)
    size = int(actor.layers[0][0].shape[0])
    x = np.sin(np.arange(4 * size, dtype=np.float64)).reshape(4, size)
    for weight, bias in actor.layers:
        x = np.tanh(x @ weight + bias)
    out = x @ actor.head[0] + actor.head[1]
    return np.ascontiguousarray(out).tobytes()


@functools.cache
def policy_runtime() -> str:
    """This machine's policy runtime: `torch 2.13.0 x86_64 <12 hex digits>`, the digits a
    hash of the probe networks' output bits, worked out on one thread as policies drive
    (`PolicyDriver`): the thread count is part of the numerics too."""
    threads = torch.get_num_threads()
    torch.set_num_threads(1)
    try:
        # Building the probes draws torch's random weights: the generator is put back, so
        # a seeded training draws the same numbers whether or not a probe ran first.
        with torch.random.fork_rng(devices=[]):
            digest = hashlib.sha256(_camera_bits() + _vector_bits()).hexdigest()[:12]
    finally:
        torch.set_num_threads(threads)
    return f"torch {torch.__version__.split('+')[0]} {platform.machine()} {digest}"
