"""One drawn camera: the concrete numbers a car's camera sees an episode through.

`draw_perturbation(settings, rng)` draws one from a seeded numpy Generator; the same seed
gives the same draw. At strength 1 (the default range) a family draws:

* light: brightness, a gain on every grey level, 0.67-1.5; contrast about mid grey,
  0.77-1.3 (both even on a log scale);
* noise: sensor noise, fresh in every frame, of a standard deviation of 0-6 grey levels;
* blur: a Gaussian blur of a standard deviation of 0-1 pixel;
* pose: the camera's height +-2 cm (in 5 mm steps) and pitch +-3 degrees (in 0.5 degree
  steps), through the camera's geometry;
* colours: the road's, edge bands', centre dashes', field's and background's tones each
  +-40 grey levels, the walls' +-20, keeping the road apart from the field and the lines.

Strength s scales every range by s (the gain's and the contrast's on the log scale); at
s = 0 a family draws nothing, and a perturbation that changes nothing is `PLAIN`. Pose
jitter comes in steps so that cars share cameras (a camera per height and pitch is built
once, then reused).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace

import numpy as np

from sim.sensors import camera_scene as scene
from sim.sensors.randomisation.settings import CameraRandomisation

# Ranges at strength 1.
LIGHT_GAIN = 1.5  # brightness gain within [1/1.5, 1.5]
CONTRAST = 1.3  # contrast within [1/1.3, 1.3]
NOISE_LEVELS = 6.0  # grey levels, standard deviation
BLUR_PIXELS = 1.0  # standard deviation
HEIGHT_M = 0.02
PITCH_DEG = 3.0
HEIGHT_STEP_M = 0.005
PITCH_STEP_DEG = 0.5
TONE_LEVELS = 40.0
WALL_LEVELS = 20.0
# What keeps a drawn scene drivable: the field stays this far from the road, the edge
# bands stay brighter than the road by this much, the dashes this far from the road, and
# road and field this far from the tones of boxes and bot cars (so objects still show).
ROAD_FROM_FIELD = 20
BANDS_OVER_ROAD = 60
DASHES_FROM_ROAD = 30
FROM_OBJECTS = 8
_OBJECT_TONES = (scene.BOX_SIDE, scene.BOX_TOP, scene.BOT_CAR_SIDE, scene.BOT_CAR_TOP)
_TRIES = 50


@dataclass(frozen=True)
class Palette:
    """The scene's grey tones (`sim.sensors.camera_scene`): road, edge bands, centre dashes,
    field, background over the walls, and a shift of every wall's tone."""

    road: int = scene.ROAD
    border: int = scene.BORDER
    centre: int = scene.CENTRE
    grass: int = scene.GRASS
    background: int = scene.BACKGROUND
    wall_shift: int = 0

    def __post_init__(self) -> None:
        for name in ("road", "border", "centre", "grass", "background"):
            tone = getattr(self, name)
            if not 0 <= tone <= 255:
                raise ValueError(f"the {name} tone must be a grey level 0-255, not {tone}.")
        if not -255 <= self.wall_shift <= 255:
            raise ValueError(f"the walls' shift must be within +-255, not {self.wall_shift}.")

    @property
    def plain(self) -> bool:
        return self == PLAIN_PALETTE


PLAIN_PALETTE = Palette()


@dataclass(frozen=True)
class CameraPerturbation:
    """What one car's camera sees differently for an episode; the defaults change nothing.

    Light: every grey level v becomes 128 + contrast * (gain * v - 128). Blur and noise are
    standard deviations (pixels, grey levels). The pose moves the camera up by
    `height_m` and tilts it down by `pitch_deg` more than the model's camera. `palette`
    recolours the scene."""

    gain: float = 1.0
    contrast: float = 1.0
    noise: float = 0.0
    blur: float = 0.0
    height_m: float = 0.0
    pitch_deg: float = 0.0
    palette: Palette = field(default_factory=Palette)

    def __post_init__(self) -> None:
        numbers = (self.gain, self.contrast, self.noise, self.blur, self.height_m, self.pitch_deg)
        if not all(math.isfinite(value) for value in numbers):
            raise ValueError("a camera perturbation's numbers must be finite.")
        if self.gain <= 0.0 or self.contrast <= 0.0:
            raise ValueError("a camera perturbation's gain and contrast must be positive.")
        if self.noise < 0.0 or self.blur < 0.0:
            raise ValueError("a camera perturbation's noise and blur must not be negative.")

    @property
    def moves_camera(self) -> bool:
        """The camera's geometry differs from the model's (height or pitch)."""
        return self.height_m != 0.0 or self.pitch_deg != 0.0

    @property
    def changes_tones(self) -> bool:
        """Grey levels map differently (light, contrast or colours)."""
        return self.gain != 1.0 or self.contrast != 1.0 or not self.palette.plain

    @property
    def changes_frames(self) -> bool:
        """Anything at all differs from the plain render."""
        return self.moves_camera or self.changes_tones or self.noise > 0.0 or self.blur > 0.0


PLAIN = CameraPerturbation()


def draw_perturbation(
    settings: CameraRandomisation, rng: np.random.Generator
) -> CameraPerturbation:
    """One episode's camera for one car. Every family draws its numbers whether on or not
    (an off family's are then dropped), so turning one family off leaves the others' draws
    from the same seed as they were."""
    light, noise, blur = rng.uniform(-1.0, 1.0, size=2), rng.uniform(), rng.uniform()
    pose = rng.uniform(-1.0, 1.0, size=2)
    palette = _draw_palette(settings.colours, rng)
    chosen = PLAIN
    if settings.light > 0.0:
        s = settings.light
        chosen = replace(
            chosen,
            gain=math.exp(light[0] * s * math.log(LIGHT_GAIN)),
            contrast=math.exp(light[1] * s * math.log(CONTRAST)),
        )
    if settings.noise > 0.0:
        chosen = replace(chosen, noise=float(noise) * settings.noise * NOISE_LEVELS)
    if settings.blur > 0.0:
        chosen = replace(chosen, blur=float(blur) * settings.blur * BLUR_PIXELS)
    if settings.pose > 0.0:
        s = settings.pose
        chosen = replace(
            chosen,
            height_m=_stepped(pose[0] * s * HEIGHT_M, HEIGHT_STEP_M),
            pitch_deg=_stepped(pose[1] * s * PITCH_DEG, PITCH_STEP_DEG),
        )
    if settings.colours > 0.0:
        chosen = replace(chosen, palette=palette)
    return chosen


def _stepped(value: float, step: float) -> float:
    steps = round(value / step)
    return 0.0 if steps == 0 else round(steps * step, 6)


def _draw_palette(strength: float, rng: np.random.Generator) -> Palette:
    """Tones within +-TONE_LEVELS * strength of the plain ones (walls WALL_LEVELS), drawn
    again until the scene stays drivable (see the constants); the plain palette if no
    draw does."""
    spread = TONE_LEVELS * strength
    for _ in range(_TRIES):
        shifts = rng.uniform(-1.0, 1.0, size=6)
        if strength <= 0.0:
            return PLAIN_PALETTE
        road, border, centre, grass, background = (
            int(np.clip(round(plain + shift * spread), 0, 255))
            for plain, shift in zip(
                (scene.ROAD, scene.BORDER, scene.CENTRE, scene.GRASS, scene.BACKGROUND),
                shifts[:5],
                strict=True,
            )
        )
        palette = Palette(
            road=road,
            border=border,
            centre=centre,
            grass=grass,
            background=background,
            wall_shift=round(float(shifts[5]) * WALL_LEVELS * strength),
        )
        if drivable(palette):
            return palette
    return PLAIN_PALETTE


def drivable(palette: Palette) -> bool:
    """The road still stands out from the field, the lines from the road, and the road
    and the field from boxes and bot cars."""
    road, grass = palette.road, palette.grass
    return (
        abs(road - grass) >= ROAD_FROM_FIELD
        and palette.border - road >= BANDS_OVER_ROAD
        and abs(palette.centre - road) >= DASHES_FROM_ROAD
        and all(abs(tone - obj) >= FROM_OBJECTS for tone in (road, grass) for obj in _OBJECT_TONES)
    )
