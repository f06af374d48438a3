"""DeepRacer's own weights in a model folder: the frozen graph a DeepRacer model drives with.

DeepRacer's simulator (deepracer-simapp `boto/s3/files/checkpoint_files/tensorflow_model.py`)
freezes every checkpoint it uploads as `model/model_<N>.pb` beside `model_metadata.json`, and
names the best one in `model/deepracer_checkpoints.json` (`{"best_checkpoint": {"name":
"<N>_Step-<steps>.ckpt", ...}}`); SageMaker's output folder holds the best as
`agent/model.pb`. With the metadata, that graph is exactly a car archive's contents, so a
model folder imported from DeepRacer for Cloud or the console can drive in racer-tui as it
would on the car (`sim.car_export`), instead of starting untrained.

Everything here is untrusted: file sizes are capped, the JSON is checked, and the graph is
read and run by `sim.car_export` (an op allow-list; nothing is executed).
"""

from __future__ import annotations

import json
import re
import tempfile
from dataclasses import dataclass
from pathlib import Path

from sim.car_archive.archive import MAX_GRAPH_BYTES, car_archive_bytes, read_car_archive
from sim.car_archive.errors import CarModelError

CHECKPOINTS_FILE = "deepracer_checkpoints.json"
MAX_CHECKPOINTS_BYTES = 64 * 1024
_CHECKPOINT = re.compile(r"^(\d+)_Step")
_FROZEN = re.compile(r"^model_(\d+)\.pb$")


@dataclass(frozen=True)
class FolderWeights:
    """A model folder's frozen graph packed as a car archive, checked to drive."""

    graph: Path  # where it was found, for the racer's note
    archive: bytes  # the car archive (model_metadata.json + agent/model.pb)


def frozen_graph(root: Path) -> Path | None:
    """The graph DeepRacer would drive with: the best checkpoint's `model_<N>.pb`, else the
    only (or newest) `model_<N>.pb`, else SageMaker's `agent/model.pb`; None when the folder
    has no weights."""
    for folder in (root / "model", root):
        if not folder.is_dir():
            continue
        frozen = {
            int(match.group(1)): path
            for path in folder.iterdir()
            if (match := _FROZEN.match(path.name)) and path.is_file() and not path.is_symlink()
        }
        if not frozen:
            continue
        best = _best_checkpoint(folder / CHECKPOINTS_FILE)
        if best is not None and best in frozen:
            return frozen[best]
        return frozen[max(frozen)]
    for agent in (root / "agent" / "model.pb", root / "model" / "agent" / "model.pb"):
        if agent.is_file() and not agent.is_symlink():
            return agent
    return None


def _best_checkpoint(path: Path) -> int | None:
    """N of `best_checkpoint`'s name in deepracer_checkpoints.json, or None."""
    try:
        if not path.is_file() or path.stat().st_size > MAX_CHECKPOINTS_BYTES:
            return None
        data = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, json.JSONDecodeError):
        return None
    best = data.get("best_checkpoint") if isinstance(data, dict) else None
    name = best.get("name") if isinstance(best, dict) else None
    match = _CHECKPOINT.match(name) if isinstance(name, str) else None
    return int(match.group(1)) if match else None


def folder_weights(root: Path, metadata_file: Path) -> FolderWeights | None:
    """The folder's frozen graph as a car archive that racer-tui can drive with, or None
    when it has none. CarModelError (one sentence) when it has one that cannot drive."""
    from sim.car_archive.policy import CarPolicy  # noqa: PLC0415 (torch: runs the graph, only now)

    graph = frozen_graph(root)
    if graph is None:
        return None
    if graph.stat().st_size > MAX_GRAPH_BYTES:
        raise CarModelError(f"{graph.name} is larger than a DeepRacer model can be.")
    archive = car_archive_bytes(metadata_file.read_bytes(), graph.read_bytes())
    with tempfile.TemporaryDirectory(prefix="racer-import-") as scratch:
        packed = Path(scratch) / f"{root.name}.tar.gz"
        packed.write_bytes(archive)
        try:
            CarPolicy(read_car_archive(packed))
        except CarModelError as error:
            # The archive's own name means nothing to the racer: name the graph instead.
            raise CarModelError(str(error).replace(packed.name, graph.name, 1)) from None
    return FolderWeights(graph, archive)
