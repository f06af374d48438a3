"""Resumable training state in `checkpoints/`: tensors only, one atomic file each.

A checkpoint is a safetensors file holding the policy network's tensors (`policy.*`), the
Adam optimizer's moments and step counts (`optimizer.<param>.<key>`), and the training
counters as JSON in the metadata. One file per checkpoint means a kill mid-write leaves
either the old checkpoint or the new one: never a policy from one moment and an optimizer
from another. `latest.safetensors` is what `racer-tui train` resumes from;
`best.safetensors` is the best policy by evaluation progress (also in policy.safetensors).
"""

from __future__ import annotations

import json
import math
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

import torch
from safetensors.torch import save

from sim.foundation.atomic import write_bytes_atomic
from sim.training.errors import PolicyError
from sim.training.policy import (
    PolicyNetwork,
    check_tensors,
    fill_network,
    open_tensors,
    policy_data,
)

LATEST = "latest.safetensors"
BEST = "best.safetensors"
_POLICY = "policy."
_OPTIMIZER = "optimizer."
_ADAM_KEYS = ("step", "exp_avg", "exp_avg_sq")


@dataclass(frozen=True)
class Progress:
    """The counters a run resumes from."""

    iteration: int = 0
    total_steps: int = 0
    episodes: int = 0
    elapsed_seconds: float = 0.0  # training time over all runs of this model
    best_progress: float = -1.0  # mean evaluation progress of the best policy; -1: none yet
    best_lap: float | None = None  # its mean lap time when every trial completed

    def to_json(self) -> str:
        return json.dumps(asdict(self))

    @classmethod
    def from_json(cls, text: str, where: str) -> Progress:
        try:
            data = json.loads(text)
            counts = [data[name] for name in ("iteration", "total_steps", "episodes")]
            elapsed, best = data["elapsed_seconds"], data["best_progress"]
            best_lap = data.get("best_lap")
        except (json.JSONDecodeError, TypeError, KeyError):
            raise PolicyError(f"{where} has unreadable training counters.") from None
        numbers = [elapsed, best] + ([] if best_lap is None else [best_lap])
        if not all(isinstance(c, int) and not isinstance(c, bool) and c >= 0 for c in counts) or (
            not all(
                isinstance(x, int | float) and not isinstance(x, bool) and math.isfinite(x)
                for x in numbers
            )
        ):
            raise PolicyError(f"{where} has unreadable training counters.")
        return cls(
            counts[0],
            counts[1],
            counts[2],
            float(elapsed),
            float(best),
            None if best_lap is None else float(best_lap),
        )


def checkpoint_bytes(
    network: PolicyNetwork, optimizer: torch.optim.Optimizer, progress: Progress
) -> bytes:

    tensors: dict[str, torch.Tensor] = {
        _POLICY + name: tensor.detach().to(torch.float32).contiguous().clone()
        for name, tensor in network.state_dict().items()
    }
    for index, state in optimizer.state_dict()["state"].items():
        for key in _ADAM_KEYS:
            if key in state:
                value = torch.as_tensor(state[key], dtype=torch.float32)
                tensors[f"{_OPTIMIZER}{index}.{key}"] = value.detach().contiguous().clone()
    facts = {**network.spec.facts(), "training": progress.to_json()}
    return bytes(save(tensors, metadata=facts))


def save_checkpoint(
    path: Path, network: PolicyNetwork, optimizer: torch.optim.Optimizer, progress: Progress
) -> None:
    write_bytes_atomic(path, checkpoint_bytes(network, optimizer, progress))


def load_checkpoint(
    path: Path, network: PolicyNetwork, optimizer: torch.optim.Optimizer
) -> Progress:
    """Fill `network` and `optimizer` from a checkpoint; its counters are returned.

    The same checks as a policy file: racer-tui format, the same car, every tensor's name,
    shape and dtype. PolicyError says to delete the checkpoints folder when it does not fit.
    """
    data, where = policy_data(path)
    facts, tensors = open_tensors(data, where)
    if "training" not in facts:
        raise PolicyError(f"{where} is not a training checkpoint; delete it to start over.")
    progress = Progress.from_json(facts["training"], where)
    policy = {k[len(_POLICY) :]: v for k, v in tensors.items() if k.startswith(_POLICY)}
    moments = {k[len(_OPTIMIZER) :]: v for k, v in tensors.items() if k.startswith(_OPTIMIZER)}
    if len(policy) + len(moments) != len(tensors):
        raise PolicyError(f"{where} has unexpected tensors; delete it to start over.")
    fill_network(network, facts, policy, where)
    _fill_optimizer(optimizer, moments, where)
    return progress


def _fill_optimizer(
    optimizer: torch.optim.Optimizer, moments: dict[str, torch.Tensor], where: str
) -> None:
    state_dict: dict[str, Any] = optimizer.state_dict()
    params = [p for group in optimizer.param_groups for p in group["params"]]
    shapes: dict[str, tuple[int, ...]] = {}
    state: dict[int, dict[str, torch.Tensor]] = {}
    for index, param in enumerate(params):
        keys = [key for key in _ADAM_KEYS if f"{index}.{key}" in moments]
        if not keys:
            continue  # a parameter that had no gradient yet
        if keys != list(_ADAM_KEYS):
            raise PolicyError(f"{where} has incomplete optimizer state; delete it to start over.")
        shapes[f"{index}.step"] = ()
        shapes[f"{index}.exp_avg"] = tuple(param.shape)
        shapes[f"{index}.exp_avg_sq"] = tuple(param.shape)
        state[index] = {key: moments[f"{index}.{key}"] for key in _ADAM_KEYS}
    if set(shapes) != set(moments):
        raise PolicyError(f"{where} has optimizer state for another network; delete it.")
    check_tensors(moments, shapes, where)
    state_dict["state"] = state
    optimizer.load_state_dict(state_dict)
