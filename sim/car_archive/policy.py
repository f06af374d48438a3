"""A car archive's policy: camera frames in, DeepRacer's actions out, as the car runs it.

The car feeds its graph one greyscale frame per step, raw 0..255 as float32, with no
normalisation of its own (the graph divides by 255) and no frame stacking. For a discrete
action space the graph's output is the softmax over actions and the car takes the argmax;
for a continuous one it is the mean (steering, speed) in -1..1, scaled linearly to the
action space's ranges (`ActionSpace.targets`).
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray

from sim.car_archive.archive import CarArchive
from sim.car_archive.errors import CarModelError
from sim.car_archive.graph_runner import GraphRunner


class CarPolicy:
    """The frozen graph of a `CarArchive`, checked to run on a blank frame when made."""

    def __init__(self, archive: CarArchive) -> None:
        self.archive = archive
        self._runner = GraphRunner(archive.graph, archive.output_node)
        if self._runner.inputs != (archive.input_node,):
            sensors = sorted({name.rsplit("/", 1)[-1] for name in self._runner.inputs})
            raise CarModelError(
                f"{archive.path.name}: the policy reads {len(self._runner.inputs)} inputs "
                f"({', '.join(sensors)}); racer-tui drives car archives from their camera alone."
            )
        placeholder = archive.graph.node(archive.input_node)
        shape = placeholder.attrs["shape"].shape if "shape" in placeholder.attrs else None
        if shape is None or len(shape) != 4 or min(shape[1:]) < 1:
            raise CarModelError(
                f"{archive.path.name}: the camera input has no fixed [?, height, width, "
                "channels] shape."
            )
        self.height, self.width, channels = shape[1:]
        if channels != 1:
            raise CarModelError(
                f"{archive.path.name}: the model takes {channels} camera channels (a stereo "
                "camera or stacked frames); racer-tui's car renders one greyscale frame."
            )
        space = archive.metadata.action_space
        outputs = len(space.actions) if space.kind == "discrete" else 2
        blank = self.outputs(np.zeros((1, self.height, self.width), dtype=np.uint8))
        if blank.shape != (1, outputs):
            raise CarModelError(
                f"{archive.path.name}: the policy gives {blank.shape[-1]} values per frame, "
                f"but the {space.kind} action space needs {outputs}."
            )

    def outputs(self, frames: NDArray[np.uint8]) -> NDArray[np.float32]:
        """The graph's output for (N, H, W) greyscale frames: (N, actions) probabilities,
        or (N, 2) means for a continuous action space."""
        batch = np.asarray(frames, dtype=np.float32)[..., np.newaxis]  # raw 0..255, NHWC
        out = self._runner.run({self.archive.input_node: batch})
        return np.asarray(out, dtype=np.float32)

    def actions(self, frames: NDArray[np.uint8]) -> NDArray[Any]:
        """What the car does with each frame: action indices (discrete, the argmax), or
        (N, 2) means clipped to -1..1 (continuous)."""
        out = self.outputs(frames)
        if self.archive.metadata.action_space.kind == "discrete":
            return np.asarray(out.argmax(axis=1), dtype=np.int64)
        return np.clip(out, -1.0, 1.0)
