"""A perturbation's light, colours, blur and noise, applied to rendered frames.

Colours go through the scene's tones. The camera samples the ground's texture without
blending (`sim.sensors.camera`), so every pixel of a plain frame is one of the scene's tones
(`sim.sensors.camera_scene`) plus its fixed grain: the level alone says which surface a pixel
shows. Recolouring the scene is therefore one lookup per grey level, with each surface's
grain kept: a level moves by its surface's change of tone. Light and contrast are a map of
levels too, so both fold into one lookup table per car; blur and noise come after it, in
floating point, and the frame is rounded once at the end.

Surfaces by level: 0-24 the walls (every wall tone, and the ground past them); the tones of
boxes and bot cars exactly (left as they are); the centre dashes (140) and the background
(179) exactly; any other level the road, the edge bands or the field, whichever tone it is
the fewest grain spreads from. (One cell in 65,536 of the road's grain tile lands on a bot
car's top tone, 36, and keeps its level; nothing else is ambiguous.)
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from numpy.typing import NDArray

from sim.sensors import camera_scene as scene
from sim.sensors.randomisation.perturbation import CameraPerturbation

UInt8Array = NDArray[np.uint8]
Float32Array = NDArray[np.float32]

SURFACES = ("walls", "road", "border", "centre", "grass", "background", "objects")
_LEVELS = np.arange(256, dtype=np.float32)
# A blur's kernel reaches this many standard deviations either side.
_TRUNCATE = 3.0
# Noise frames are cut out of a few larger fields of standard normal numbers at random
# offsets: fresh noise in every frame without drawing a whole frame of numbers each time.
_NOISE_FIELDS = 4


def _surface_of_level() -> NDArray[np.intp]:
    """(256,) index into SURFACES of the surface a plain frame's grey level shows."""
    index = {name: i for i, name in enumerate(SURFACES)}
    grained = [
        ("road", scene.ROAD, scene.ROAD_GRAIN),
        ("border", scene.BORDER, scene.BORDER_GRAIN),
        ("grass", scene.GRASS, scene.GRASS_GRAIN),
    ]
    spreads = np.array([[abs(level - tone) / spread for _, tone, spread in grained]
                        for level in range(256)])  # fmt: skip
    surface = np.array([index[grained[i][0]] for i in spreads.argmin(axis=1)], dtype=np.intp)
    surface[: scene.GROUND_FLOOR] = index["walls"]
    surface[scene.CENTRE] = index["centre"]
    surface[scene.BACKGROUND] = index["background"]
    for tone in (scene.BOX_SIDE, scene.BOX_TOP, scene.BOT_CAR_SIDE, scene.BOT_CAR_TOP):
        surface[tone] = index["objects"]
    return surface


SURFACE_OF_LEVEL = _surface_of_level()


def tone_table(perturbation: CameraPerturbation) -> Float32Array:
    """(256,) float32: what each grey level of a plain frame becomes under the
    perturbation's colours, then its light and contrast (0..255, not yet rounded)."""
    palette = perturbation.palette
    shift = np.array(
        [
            palette.wall_shift,
            palette.road - scene.ROAD,
            palette.border - scene.BORDER,
            palette.centre - scene.CENTRE,
            palette.grass - scene.GRASS,
            palette.background - scene.BACKGROUND,
            0,
        ],
        dtype=np.float32,
    )
    levels = np.clip(_LEVELS + shift[SURFACE_OF_LEVEL], 0.0, 255.0)
    lit = 128.0 + perturbation.contrast * (perturbation.gain * levels - 128.0)
    return np.asarray(np.clip(lit, 0.0, 255.0), dtype=np.float32)


def blur(frames: Float32Array, sigma: Float32Array) -> Float32Array:
    """(n, H, W) frames each blurred in place by a Gaussian of its own standard deviation
    `sigma` (n,) pixels, down and across (edges repeated); returns `frames`."""
    from scipy.ndimage import gaussian_filter  # noqa: PLC0415 (scipy: only when frames are blurred)

    for frame, spread in zip(frames, sigma.tolist(), strict=True):
        if spread > 0.0:
            gaussian_filter(frame, spread, output=frame, mode="nearest", truncate=_TRUNCATE)
    return frames


class SensorNoise:
    """Per-frame Gaussian noise of a chosen standard deviation per car, seeded."""

    def __init__(self, height: int, width: int, rng: np.random.Generator) -> None:
        self._rng = rng
        self._shape = (height, width)
        self._fields: Float32Array | None = None

    def add(self, frames: Float32Array, sigma: Float32Array) -> None:
        """Adds noise of standard deviation `sigma[i]` (grey levels) to frame i, in place."""
        if self._fields is None:
            height, width = self._shape
            self._fields = self._rng.standard_normal(
                (_NOISE_FIELDS, 2 * height, 2 * width), dtype=np.float32
            )
        height, width = self._shape
        picks = self._rng.integers(0, (_NOISE_FIELDS, height + 1, width + 1), size=(len(frames), 3))
        fields = self._fields
        for i, (level, (k, row, column)) in enumerate(
            zip(sigma.tolist(), picks.tolist(), strict=True)
        ):
            if level > 0.0:
                frames[i] += level * fields[k, row : row + height, column : column + width]


def perturb_frames(
    frames: UInt8Array,
    perturbations: Sequence[CameraPerturbation],
    noise: SensorNoise,
    tables: Sequence[Float32Array] | None = None,
) -> UInt8Array:
    """Plain frames (n, H, W) through each one's perturbation (colours, light, blur,
    noise), in place; `tables` are the perturbations' `tone_table`s when already made."""
    if tables is None:
        tables = [tone_table(p) for p in perturbations]
    table = np.stack(tables)
    rows = np.arange(len(frames))[:, None, None]
    sigma_blur = np.array([p.blur for p in perturbations], dtype=np.float32)
    sigma_noise = np.array([p.noise for p in perturbations], dtype=np.float32)
    if not sigma_blur.any() and not sigma_noise.any():
        frames[...] = np.rint(table).astype(np.uint8)[rows, frames]
        return frames
    values = table[rows, frames]
    values = blur(values, sigma_blur)
    noise.add(values, sigma_noise)
    np.rint(values, out=values)
    np.clip(values, 0.0, 255.0, out=values)
    frames[...] = values
    return frames
