"""Where a training's objects stood at its last traced step, for the app's agent's-eye view.

DeepRacer's sim-trace has no object columns, and shuffled boxes and bot cars are somewhere
else in every episode, so the trainer's logbook keeps racer-tui's own small file beside it,
`training-objects.json`: the episode and step of the last sim-trace row it wrote, whether
the objects are bot cars, and each object's x, y and heading (radians) at that step. The
view draws them only when the file's episode and step are the trace's last row's.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from sim.foundation.atomic import write_text_atomic
from sim.physics.objects.field import BOT_CAR_SHAPE, BOX_SHAPE, StandingField
from sim.tracks.track import Track

SEEN_FILE = "training-objects.json"
MAX_SEEN_BYTES = 64 * 1024
MAX_OBJECTS = 64


@dataclass(frozen=True)
class SeenObjects:
    """One car's objects at one sim-trace row (its episode and step number)."""

    episode: int
    steps: int
    bots: bool
    poses: tuple[tuple[float, float, float], ...]  # x, y, heading in radians

    def to_json(self) -> str:
        return json.dumps(
            {
                "episode": self.episode,
                "steps": self.steps,
                "bots": self.bots,
                "objects": [[round(v, 4) for v in pose] for pose in self.poses],
            }
        )

    def field(self, track: Track) -> StandingField:
        """The objects standing on `track`, for the camera and lidar to see."""
        shape = BOT_CAR_SHAPE if self.bots else BOX_SHAPE
        return StandingField(track, shape, np.array(self.poses, dtype=np.float64))


def write_seen(folder: Path, seen: SeenObjects) -> None:
    """Replace the folder's file (not fsynced: it is worth one update of the view)."""
    write_text_atomic(folder / SEEN_FILE, seen.to_json(), durable=False)


def read_seen(folder: Path) -> SeenObjects | None:
    """The folder's file, or None when it is missing or not one racer-tui wrote."""
    path = folder / SEEN_FILE
    try:
        if path.stat().st_size > MAX_SEEN_BYTES:
            return None
        data = json.loads(path.read_text(encoding="utf-8"))
        poses = tuple((float(x), float(y), float(heading)) for x, y, heading in data["objects"])
        episode, steps, bots = data["episode"], data["steps"], data["bots"]
    except (OSError, UnicodeDecodeError, ValueError, TypeError, KeyError):
        return None
    if not (
        isinstance(episode, int)
        and isinstance(steps, int)
        and isinstance(bots, bool)
        and len(poses) <= MAX_OBJECTS
        and all(math.isfinite(v) for pose in poses for v in pose)
    ):
        return None
    return SeenObjects(episode, steps, bots, poses)
