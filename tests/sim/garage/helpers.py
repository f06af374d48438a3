"""Helpers for garage tests: a small valid policy file, evaluations, trainer state."""

from __future__ import annotations

import json
import os
from pathlib import Path

import numpy as np
from safetensors.numpy import save

from sim.deepracer.files import EvaluationTrial, evaluation_metrics_text
from sim.garage.folder import ModelFolder


def policy_bytes(seed: int = 0) -> bytes:
    """A small, valid safetensors file written with the numpy backend (no torch)."""
    rng = np.random.default_rng(seed)
    tensors = {
        "policy.0.weight": rng.standard_normal((8, 21)).astype(np.float32),
        "policy.0.bias": np.zeros(8, dtype=np.float32),
    }
    return bytes(save(tensors, metadata={"format": "racer-tui-policy/1"}))


def add_policy(folder: ModelFolder, seed: int = 0) -> bytes:
    data = policy_bytes(seed)
    folder.policy_file.write_bytes(data)
    return data


def add_evaluation(folder: ModelFolder, stamp: str = "20250101120000", lap_ms: int = 9500) -> Path:
    trials = [
        EvaluationTrial(100.0, lap_ms + 100, 100, lap_ms, "Lap complete", trial=1),
        EvaluationTrial(
            42.0, lap_ms * 2, lap_ms + 100, 4000, "Off track", off_track_count=1, trial=2
        ),
    ]
    path = folder.evaluation_metrics_file(stamp)
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(evaluation_metrics_text(trials))
    return path


def write_training_state(folder: ModelFolder, state: str, pid: int | None = None) -> None:
    folder.training_state_file.write_text(
        json.dumps(
            {
                "state": state,
                "pid": os.getpid() if pid is None else pid,
                "started_at": "2025-01-01T12:00:00+00:00",
                "updated_at": "2025-01-01T12:05:00+00:00",
                "elapsed_seconds": 300.0,
                "steps": 123456,
                "episodes": 400,
                "best_progress": 100.0,
                "message": "",
            }
        )
    )
