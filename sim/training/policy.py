"""The policy network of a model and its tensor-only file.

One network class serves training (wrapped by `sim.training.ppo.RacerPolicy`), evaluation
and races (`sim.training.policy_driver`), so the weights in `policy.safetensors` are
exactly what was trained. The network is always rebuilt from `model_metadata.json`
(sensors, action space, network size) and only then filled with tensors: a policy file is
data, never code. Every tensor name, shape and dtype is checked, and the architecture
facts written in the file's metadata must match the rebuilt network.

Layout: each sensor is encoded (a small CNN for the camera, scaled values for lidar and
the vector state), the encodings are concatenated, and two MLPs read them: the policy
(logits over a discrete action space, or the mean of a Gaussian over the normalised
continuous one) and the value function.
"""

from __future__ import annotations

import itertools
import json
import math
import struct
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import torch
from numpy.typing import NDArray
from safetensors import SafetensorError
from safetensors.torch import load, save
from torch import nn

from sim.deepracer.files import NEURAL_NETWORKS, ModelMetadata
from sim.foundation.atomic import write_bytes_atomic
from sim.sensors.observations import VECTOR_SIZE, SensorOptions
from sim.training.errors import PolicyError

__all__ = [
    "NetworkSpec",
    "PolicyError",
    "PolicyNetwork",
    "build_network",
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


def pooled_frame_shape(frame_shape: tuple[int, ...]) -> tuple[int, ...]:
    """The shape `pooled_frames` gives one frame of `frame_shape` (height, width, channels)."""
    return tuple(pooled_frames(np.zeros((1, *frame_shape), dtype=np.uint8)).shape[1:])


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


# --- observations as tensors --------------------------------------------------------------


def observation_tensors(obs: Any) -> Observation:
    """Observer output (an array or a dict of arrays) as tensors, without copying."""
    if isinstance(obs, dict):
        return {key: torch.as_tensor(value) for key, value in obs.items()}
    return torch.as_tensor(obs)
