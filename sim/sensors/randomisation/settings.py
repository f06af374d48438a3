"""What a camera model's training randomises, and how a model folder keeps it.

Five families, each with a strength from 0 (off) to `MAX_STRENGTH`; 1 is racer-tui's
default range (`sim.sensors.randomisation.perturbation` says what each strength draws):

* light: brightness and contrast;
* noise: sensor noise, fresh in every frame;
* blur: a soft lens or a moving car;
* pose: the camera's height on the car and its pitch;
* colours: the road's, the lines' (edge bands, centre dashes) and the surroundings'
  (field, walls, background) grey tones.

DeepRacer has no keys for this, so they are racer-tui's own in `training_params.yaml`,
`CAMERA_RANDOMISATION_<FAMILY>`, all five written when any family is on and none when all
are off: a file without them (every model made before, and every DeepRacer file) reads as
off, and an off model's files are byte for byte what they were.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, fields, replace
from typing import Any, ClassVar

from sim.deepracer.files import DeepRacerFileError, TrainingParams

MAX_STRENGTH = 2.0
KEY_PREFIX = "CAMERA_RANDOMISATION_"
# The families in the order racers read them, with the words that name them.
FAMILIES: tuple[str, ...] = ("light", "noise", "blur", "pose", "colours")
FAMILY_WORDS: Mapping[str, str] = {
    "light": "light and contrast",
    "noise": "sensor noise",
    "blur": "blur",
    "pose": "camera height and pitch",
    "colours": "road, line and surroundings colours",
}
CAMERA_RANDOMISATION_KEYS: tuple[str, ...] = tuple(KEY_PREFIX + f.upper() for f in FAMILIES)


@dataclass(frozen=True)
class CameraRandomisation:
    """One strength per family, 0 (off) to MAX_STRENGTH; 1 is the default range.

    `CameraRandomisation()` is racer-tui's recommended setting (every family at 1);
    `CameraRandomisation.OFF` randomises nothing (the plain render)."""

    light: float = 1.0
    noise: float = 1.0
    blur: float = 1.0
    pose: float = 1.0
    colours: float = 1.0

    OFF: ClassVar[CameraRandomisation]

    def __post_init__(self) -> None:
        for family in FAMILIES:
            value = getattr(self, family)
            if isinstance(value, bool) or not isinstance(value, int | float):
                raise ValueError(f"the {family} strength must be a number, not {value!r}.")
            if not (math.isfinite(value) and 0.0 <= value <= MAX_STRENGTH):
                raise ValueError(
                    f"the {family} strength must be from 0 (off) to {MAX_STRENGTH:g}, "
                    f"not {value:g}."
                )
            object.__setattr__(self, family, float(value))

    @property
    def on(self) -> bool:
        """Whether any family is randomised."""
        return any(self.strength(family) > 0.0 for family in FAMILIES)

    def strength(self, family: str) -> float:
        if family not in FAMILIES:
            raise ValueError(f"unknown family {family!r}; choose from {', '.join(FAMILIES)}.")
        return float(getattr(self, family))

    def describe(self) -> str:
        """In words, for a model's details: "off", or the families on with strengths."""
        if not self.on:
            return "off"
        parts = [
            f"{FAMILY_WORDS[family]} {self.strength(family):g}"
            for family in FAMILIES
            if self.strength(family) > 0.0
        ]
        return ", ".join(parts)


CameraRandomisation.OFF = CameraRandomisation(**{family: 0.0 for family in FAMILIES})


def camera_randomisation_keys(settings: CameraRandomisation) -> dict[str, object]:
    """`training_params.yaml` keys for `settings`: all five when any family is on, none
    when off (so an off model's file is unchanged)."""
    if not settings.on:
        return {}
    return {
        key: settings.strength(family)
        for key, family in zip(CAMERA_RANDOMISATION_KEYS, FAMILIES, strict=True)
    }


def with_camera_randomisation_keys(
    extra: Mapping[str, object], settings: CameraRandomisation
) -> dict[str, object]:
    """A training params file's other keys (`TrainingParams.extra`) with the camera
    randomisation keys of `settings` in place of any it held: what saving an edited model
    writes."""
    kept = {key: value for key, value in extra.items() if key not in CAMERA_RANDOMISATION_KEYS}
    return {**kept, **camera_randomisation_keys(settings)}


def read_camera_randomisation(
    params: TrainingParams | Mapping[str, Any], where: str = "training_params.yaml"
) -> CameraRandomisation:
    """A model's camera randomisation from its training params (or their extra keys); a
    missing key is that family off. A bad value is one sentence naming the key."""
    data = params.extra if isinstance(params, TrainingParams) else params
    values: dict[str, float] = {}
    for key, family in zip(CAMERA_RANDOMISATION_KEYS, FAMILIES, strict=True):
        value = data.get(key, 0.0)
        if isinstance(value, bool):  # a racer writing `true` means the default range
            number = 1.0 if value else 0.0
        elif isinstance(value, str) and value.strip().lower() in ("true", "false"):
            number = 1.0 if value.strip().lower() == "true" else 0.0
        else:
            try:
                number = float(value)
            except (TypeError, ValueError):
                number = math.nan
        if not 0.0 <= number <= MAX_STRENGTH:  # also false for nan
            raise DeepRacerFileError(
                f"{where}: {key} must be a number from 0 (off) to {MAX_STRENGTH:g}, not {value!r}."
            )
        values[family] = number
    return CameraRandomisation(**values)


def parse_camera_randomisation(text: str) -> CameraRandomisation:
    """A racer's words for a setting, as a command-line option takes them:

    "on" (or "default"): every family at 1; "off" (or "none"): nothing;
    "light,noise=0.5,pose": only the families named, at 1 unless given a strength.
    ValueError says what is wrong in one sentence."""
    words = text.strip().lower()
    if words in ("on", "default", "all", "yes", "true"):
        return CameraRandomisation()
    if words in ("off", "none", "no", "false", ""):
        return CameraRandomisation.OFF
    chosen = CameraRandomisation.OFF
    for item in words.split(","):
        name, sep, amount = (part.strip() for part in item.partition("="))
        family = "colours" if name in ("colour", "color", "colors") else name
        if family not in FAMILIES:
            raise ValueError(
                f"unknown camera randomisation {name!r}; write on, off, or families from "
                f"{', '.join(FAMILIES)} (for example light,noise=0.5)."
            )
        try:
            strength = float(amount) if sep else 1.0
        except ValueError:
            raise ValueError(
                f"the {family} strength must be a number from 0 to {MAX_STRENGTH:g}, "
                f"not {amount!r}."
            ) from None
        chosen = replace(chosen, **{family: strength})
    return chosen


def settings_text(settings: CameraRandomisation) -> str:
    """`settings` in the words `parse_camera_randomisation` reads back: "off", "on" (every
    family at 1), or the families on with their strengths ("light,noise=0.5")."""
    if not settings.on:
        return "off"
    if settings == CameraRandomisation():
        return "on"
    parts = []
    for family in FAMILIES:
        strength = settings.strength(family)
        if strength > 0.0:
            parts.append(family if strength == 1.0 else f"{family}={strength:g}")
    return ",".join(parts)


def as_mapping(settings: CameraRandomisation) -> dict[str, float]:
    """Family -> strength, for JSON output."""
    return {f.name: float(getattr(settings, f.name)) for f in fields(settings)}
