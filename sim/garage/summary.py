"""A model's training in a few figures: what `model show` prints and a bundle carries.

Built from `metrics/TrainingMetrics.json` (one row per episode) and the trainer's
`training-state.json`. A model installed from a bundle has neither; it keeps the bundle's
summary in `training-summary.json` instead.
"""

from __future__ import annotations

import json
import math
from pathlib import Path
from statistics import fmean
from typing import Any

from sim.deepracer.files import DeepRacerFileError, parse_json_object
from sim.garage.folder import TRAINING_SUMMARY_FILE, ModelError, ModelFolder

RECENT_EPISODES = 20
MAX_SUMMARY_BYTES = 64_000
MAX_SUMMARY_KEYS = 40
MAX_SUMMARY_TEXT = 500


def training_summary(folder: ModelFolder) -> dict[str, Any]:
    """Episodes, laps, progress, reward, time and the trainer's last state, as plain JSON."""
    metrics = folder.training_metrics()
    state = folder.training_state()
    kept = folder.path / TRAINING_SUMMARY_FILE
    if metrics is None and state is None and kept.is_file():
        return read_summary_text(_read_kept(kept), str(kept))
    episodes = [e for e in (metrics.episodes if metrics else ()) if e.phase == "training"]
    recent = episodes[-RECENT_EPISODES:]
    summary: dict[str, Any] = {
        "episodes": len(episodes),
        "laps_completed": sum(1 for e in episodes if e.completion_percentage >= 100),
        "best_progress": max((e.completion_percentage for e in episodes), default=0.0),
        "recent_progress": round(fmean(e.completion_percentage for e in recent), 2)
        if recent
        else None,
        "recent_reward": round(fmean(e.reward_score for e in recent), 3) if recent else None,
        "training_seconds": episodes[-1].metric_time / 1000.0 if episodes else 0.0,
        "steps": None,
        "state": None,
        "updated_at": None,
        "message": None,
        "problem": None,  # a failure's message without its remedy, and the remedy's name
        "fix": None,
        # The car the policy learnt (sim.physics.labels); travels with a bundle's summary.
        "physics": folder.trained_physics(),
        # How its training computed it (float32, bfloat16 convolutions); travels too.
        "numerics": folder.trained_numerics(),
    }
    if state is not None:
        for key in ("state", "updated_at", "message", "problem", "fix"):
            if isinstance(state.get(key), str):
                summary[key] = state[key][:MAX_SUMMARY_TEXT]
        if _is_count(state.get("steps")):
            summary["steps"] = state["steps"]
        if _is_number(state.get("elapsed_seconds")):
            summary["training_seconds"] = float(state["elapsed_seconds"])
        if _is_number(state.get("best_progress")):
            summary["best_progress"] = max(summary["best_progress"], state["best_progress"])
    return summary


def read_summary_text(text: str, where: str) -> dict[str, Any]:
    """A training summary from untrusted JSON: an object of at most 40 plain values."""
    try:
        data = parse_json_object(text, where)
    except DeepRacerFileError as error:
        raise ModelError(str(error)) from None
    if len(data) > MAX_SUMMARY_KEYS:
        raise ModelError(f"{where}: a training summary has at most {MAX_SUMMARY_KEYS} entries.")
    for key, value in data.items():
        plain = value is None or isinstance(value, bool) or _is_number(value)
        if isinstance(value, str):
            plain = len(value) <= MAX_SUMMARY_TEXT
        if not plain or len(key) > 64:
            raise ModelError(f"{where}: {key[:64]!r} is not a plain number or short text.")
    return data


def summary_text(summary: dict[str, Any]) -> str:
    return json.dumps(summary, indent=2, allow_nan=False) + "\n"


def _read_kept(path: Path) -> str:
    try:
        if path.stat().st_size > MAX_SUMMARY_BYTES:
            raise ModelError(f"{path}: larger than a training summary can be.")
        return path.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError):
        raise ModelError(f"{path}: cannot be read as UTF-8 text.") from None


def _is_number(value: object) -> bool:
    return isinstance(value, int | float) and not isinstance(value, bool) and math.isfinite(value)


def _is_count(value: object) -> bool:
    return isinstance(value, int) and not isinstance(value, bool) and value >= 0
