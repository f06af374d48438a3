"""How a model's car looks in DeepRacer's simulator: its body shell and, for DeepRacer's own
shell, its colour.

DeepRacer's `training_params.yaml` says it in two keys: `BODY_SHELL_TYPE` (the simulator's
shell id: `deepracer`, `f1_car_tron_05`, ...) and `CAR_COLOR` (written only with the
`deepracer` shell, as `Black`, `Blue`, ...). DeepRacer on AWS keeps a model's look as a
shell and a colour (`carCustomization`) and writes those two keys from its table
(`SimAppCarShells` in deepracer-on-aws's `workflow/constants/simulation.ts`), copied below;
deepracer-for-cloud writes the same keys from its `DR_CAR_BODY_SHELL_TYPE` and
`DR_CAR_COLOR`. racer-tui keeps them as found and names the look as DRoA does.
"""

from __future__ import annotations

import re
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

BODY_SHELL_TYPE = "BODY_SHELL_TYPE"
CAR_COLOR = "CAR_COLOR"
CAR_LOOK_KEYS = (BODY_SHELL_TYPE, CAR_COLOR)
DEEPRACER_SHELL = "deepracer"
# A shell id or colour is a short identifier; anything else in a file is not kept.
_IDENTIFIER = re.compile(r"[A-Za-z0-9_]{1,64}")

# (DRoA's CarShell, its CarColor, the simulator's shell id), in DRoA's order.
DROA_CAR_SHELLS: tuple[tuple[str, str, str], ...] = (
    ("AGATHA", "GREY", "f1_car_mercedes_08"),
    ("AMAZON_EDV", "PURPLE", "f1_amazon_van_purple_with_wheel"),
    ("AMAZON_EDV", "WHITE", "f1_amazon_van_white_with_wheel"),
    ("BAJA_TRUCK", "TEAL", "f1_baja_truck_05"),
    ("BAJA_TRUCK", "ORANGE", "f1_baja_truck_03"),
    ("BANANA", "BLACK", "f1_car_banana_01"),
    ("BIKE", "BLUE", "f1_august_bike_02_with_wheel"),
    ("BIKE", "RED", "f1_august_bike_01_with_wheel"),
    ("BUGGY", "WHITE", "f1_september_bug_01_with_wheel"),
    ("BUGGY", "PURPLE", "f1_september_bug_02_with_wheel"),
    ("CLOWN", "YELLOW", "f1_car_clown_01"),
    ("COMPACT", "RED", "f1_june_car_01"),
    ("COMPACT", "PURPLE", "f1_june_car_02"),
    ("DEEPRACER", "BLACK", "deepracer"),
    ("DEEPRACER", "BLUE", "deepracer"),
    ("DEEPRACER", "GREY", "deepracer"),
    ("DEEPRACER", "ORANGE", "deepracer"),
    ("DEEPRACER", "PURPLE", "deepracer"),
    ("DEEPRACER", "RED", "deepracer"),
    ("DEEPRACER", "WHITE", "deepracer"),
    ("DOG_VAN", "BROWN", "f1_dog_van"),
    ("DRAGON", "BROWN", "f1_dragon"),
    ("DUNE_BUGGY", "RED", "f1_dune_buggy_01"),
    ("DUNE_BUGGY", "GOLDEN", "f1_dune_buggy_07"),
    ("F1", "RED", "f1_2021"),
    ("F1_NUDIE", "PURPLE", "f1_nudie_purple_with_wheel"),
    ("F1_NUDIE", "ORANGE", "f1_nudie_orange_with_wheel"),
    ("F1_NUDIE", "WHITE", "f1_nudie_white_with_wheel"),
    ("FAMILY_WAGON", "GREEN", "f1_october_wagon_01_with_wheel"),
    ("FAMILY_WAGON", "PURPLE", "f1_october_wagon_02_with_wheel"),
    ("GT", "PURPLE", "f1_december_car_01_with_wheel"),
    ("GT", "RED", "f1_december_car_02_with_wheel"),
    ("HOT_ROD", "PURPLE", "f1_hotrod_03"),
    ("HOT_ROD", "ORANGE", "fl_hotrod_02"),
    ("KART", "RED", "f1_kart"),
    ("LORRY", "PURPLE", "f1_lorry_01"),
    ("LUNAR_ROVER", "BROWN", "f1_lunar_rover"),
    ("LUNAR_ROVER", "GOLDEN", "f1_july_car_03_with_wheel"),
    ("MARS_ROVER", "WHITE", "f1_mars_rover_with_wheel"),
    ("MONSTER_TRUCK", "PURPLE", "f1_monster_truck_01"),
    ("NELL", "RED", "f1_mustang_eleanor_01"),
    ("NELL", "BLACK", "f1_mustang_eleanor_02"),
    ("NELL", "YELLOW", "f1_mustang_eleanor_03"),
    ("RETRO_FUTURISTIC", "PURPLE", "f1_car_retro_01"),
    ("ROGUE_ROD", "ORANGE", "f1_rogue_01"),
    ("SNAIL", "PINK", "f1_snail"),
    ("TRON", "BLUE", "f1_car_tron_01"),
    ("TRON", "RED", "f1_car_tron_02"),
    ("TRON", "GOLDEN", "f1_car_tron_03"),
    ("TRON", "WHITE", "f1_car_tron_04"),
    ("TRON", "SKY_BLUE", "f1_car_tron_05"),
    ("TRON", "GREEN", "f1_car_tron_06"),
    ("TRON", "PURPLE", "f1_car_tron_07"),
    ("TRON", "YELLOW", "f1_car_tron_08"),
    ("TRON", "GREY", "f1_car_tron_09"),
    ("TRON", "GOLDENPINK", "f1_car_tron_10"),
    ("WAGON", "PINK", "f1_july_car_01_with_wheel"),
    ("WAGON", "BLUE", "f1_july_car_02_with_wheel"),
)


@dataclass(frozen=True)
class CarLook:
    body_shell: str  # the simulator's id
    colour: str | None = None  # DeepRacer's colour word, for the deepracer shell

    def describe(self) -> str:
        """In DRoA's words: "DeepRacer, black", "Tron, sky blue (f1_car_tron_05)"."""
        if self.body_shell == DEEPRACER_SHELL:
            return f"DeepRacer, {self.colour.lower()}" if self.colour else "DeepRacer"
        for shell, colour, shell_id in DROA_CAR_SHELLS:
            if shell_id == self.body_shell:
                return f"{_words(shell)}, {_words(colour).lower()} ({shell_id})"
        return self.body_shell

    def to_params(self) -> dict[str, str]:
        keys = {BODY_SHELL_TYPE: self.body_shell}
        if self.colour is not None:
            keys[CAR_COLOR] = self.colour
        return keys


def car_look(params: Mapping[str, Any]) -> CarLook | None:
    """The look a training_params mapping gives, or None where it gives none (or gives
    something no shell id can be)."""
    shell = params.get(BODY_SHELL_TYPE)
    if not isinstance(shell, str) or not _IDENTIFIER.fullmatch(shell):
        return None
    colour = params.get(CAR_COLOR)
    if not isinstance(colour, str) or not _IDENTIFIER.fullmatch(colour):
        colour = None
    return CarLook(shell, colour if shell == DEEPRACER_SHELL else None)


def _words(enum_name: str) -> str:
    words = enum_name.replace("_", " ").lower()
    special = {"deepracer": "DeepRacer", "gt": "GT", "f1": "F1", "amazon edv": "Amazon EDV"}
    return special.get(words, words.capitalize())
