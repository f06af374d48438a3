"""DeepRacer's race types as the league keeps them apart: a lap among boxes or bot cars is
never ranked beside a time-trial lap, so each race type has a board of its own per track.

A race's type is in its rules (sim.race.rules.RaceRules.race_type); the leaderboard cache
keeps it in a column as the rules write it ("time_trial", "object_avoidance",
"head_to_bot"). Submissions are DeepRacer evaluations ranked as time trials. On the
command line a race type is written with hyphens (`--race-type object-avoidance`); both
spellings are read.
"""

from __future__ import annotations

from typing import Final

from league.errors import LeagueError
from sim.physics.objects.settings import RaceType
from sim.race.rules import RaceRules

TIME_TRIAL: Final = RaceType.TIME_TRIAL.value.lower()
OBJECT_AVOIDANCE: Final = RaceType.OBJECT_AVOIDANCE.value.lower()
HEAD_TO_BOT: Final = RaceType.HEAD_TO_BOT.value.lower()
# The league's order of race types: boards and choices are listed in it.
RACE_TYPES: Final = (TIME_TRIAL, OBJECT_AVOIDANCE, HEAD_TO_BOT)
WORDS: Final = {
    TIME_TRIAL: "time trial",
    OBJECT_AVOIDANCE: "object avoidance",
    HEAD_TO_BOT: "head-to-bot",
}


def race_type_of(rules: RaceRules) -> str:
    """The race type of a race run under `rules`, as the cache stores it."""
    return rules.race_type.value.lower()


def option_name(race_type: str) -> str:
    """ "object-avoidance": how the command line writes a race type."""
    return race_type.replace("_", "-")


OPTION_CHOICES: Final = tuple(option_name(race_type) for race_type in RACE_TYPES)
# The board of head-to-head races (league.head_to_heads): wins and losses, not laps, so it
# is no race type's lap board; `--race-type head-to-head` asks for it.
HEAD_TO_HEAD_BOARD: Final = "head-to-head"


def parse_race_type(text: str) -> str:
    """A race type as typed (time-trial, object_avoidance, Head-To-Bot), or a LeagueError
    listing them."""
    value = text.strip().lower().replace("-", "_")
    if value not in RACE_TYPES:
        raise LeagueError(
            f"--race-type must be one of {', '.join(OPTION_CHOICES)}, not {text.strip()!r}."
        )
    return value


def words(race_type: str) -> str:
    """ "object avoidance": a race type as a racer reads it."""
    return WORDS.get(race_type, race_type.replace("_", " "))


def in_order(race_types: set[str]) -> list[str]:
    """Race types in the league's order (an unknown one, from a newer racer-tui, last)."""

    def place(kind: str) -> tuple[int, str]:
        return (RACE_TYPES.index(kind) if kind in RACE_TYPES else len(RACE_TYPES), kind)

    return sorted(race_types, key=place)


def board_name(track_name: str, physics: str, race_type: str) -> str:
    """A board's name: its track, then what sets it apart from today's time trials there
    ("beginner-oval", "beginner-oval (DeepRacer)", "beginner-oval (object avoidance)",
    "beginner-oval (object avoidance, physics 1)"), briefly enough for a table column."""
    from sim.physics.labels import board_suffix  # noqa: PLC0415 (numpy and pymunk: not for the CLI's start)

    suffix = board_suffix(physics)
    if race_type == TIME_TRIAL:
        return track_name + suffix
    inner = suffix.strip().removeprefix("(").removesuffix(")")
    return f"{track_name} ({words(race_type)}{', ' + inner if inner else ''})"
