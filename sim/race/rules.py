"""League race rules: one frozen value that every race result and league night carries.

A league night is a series of time trials: each car gets a window (4 minutes by default),
drives laps continuously, and is ranked by its valid laps. A lap-count race ends sooner,
as soon as the car has completed its laps (DeepRacer's `maximumLaps`), the window still
its time limit. An off-track puts the car back
on the track and holds it for a penalty while the race clock runs; a lap with too many
off-tracks does not count. The score of a set of laps is computed here so that every
caller (race engine, league store, leaderboard) computes it the same way.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import asdict, dataclass
from enum import StrEnum
from pathlib import Path
from typing import Any, Protocol

import yaml

from sim.foundation.plural import counted
from sim.foundation.remedies import RemedyError
from sim.foundation.strict_yaml import DuplicateKeyError, load_data
from sim.physics.objects.settings import (
    MAX_BOT_CARS,
    MAX_BOT_SPEED,
    MAX_OBSTACLES,
    BotSettings,
    ObstacleSettings,
    RaceSettings,
    RaceType,
)
from sim.physics.resets import COLLISION_PENALTY, OFF_TRACK_PENALTY


class RulesError(RemedyError):
    """A rules file or value that cannot be used; the message names the key."""


class RankingMethod(StrEnum):
    BEST_LAP = "best_lap"
    BEST_AVERAGE = "best_average"  # best average of N consecutive valid laps
    TOTAL_TIME = "total_time"  # total time of the first N valid laps


# `reward_rules` that hold a night's models to DeepRacer on AWS's reward validator.
DROA_REWARD_RULES = "droa"


class Verification(StrEnum):
    """Which results a board under these rules ranks, by each result's standing
    (league.trust.standing): every one, or only those a machine can vouch for by racing
    them again from the model, track, rules and seed they name."""

    ANY = "any"
    VERIFIABLE = "verifiable"  # verified by replay here, or its model is here to replay
    REPLAYED = "replayed"  # verified by replay on this machine

    @property
    def requires(self) -> bool:
        """Whether some results do not count under it."""
        return self is not Verification.ANY

    @property
    def words(self) -> str:
        return {
            Verification.ANY: "every result",
            Verification.VERIFIABLE: "only results verified or verifiable by replay",
            Verification.REPLAYED: "only results verified by replay",
        }[self]


@dataclass(frozen=True)
class RaceRules:
    """Everything that decides how a time trial is run and scored."""

    window_seconds: float = 240.0
    penalty_seconds: float = 3.0
    # None = unlimited. A lap with more off-tracks than this does not count.
    max_offtracks_per_lap: int | None = 3
    ranking: RankingMethod = RankingMethod.BEST_LAP
    ranking_laps: int = 3  # N for best_average and total_time
    collision_penalty_seconds: float = 5.0
    # None: a time race, driven for the whole window. N: the race ends when the car has
    # completed N laps (counting or not), or when the window closes first.
    lap_count: int | None = None
    # DeepRacer's race type. The objects are the same for every car of a night, so laps
    # compare: boxes evenly spaced in alternating lanes (DeepRacer's layout when it does
    # not randomise them), or drawn from the race's seed when randomised; bot cars at
    # `bot_speed` m/s, changing lanes every 3-5 s with `bot_lane_change`.
    race_type: RaceType = RaceType.TIME_TRIAL
    obstacles: int = 0
    randomize_obstacles: bool = False
    bots: int = 0
    bot_speed: float = 1.0
    bot_lane_change: bool = False
    # Which results count (a league night's standings): a setting of the organiser's.
    verification: Verification = Verification.ANY
    # DeepRacer on AWS's minimumLaps: a race is ranked only once it has this many
    # consecutive counting laps, whatever it is ranked by (its BEST_LAP_TIME races too).
    min_laps: int = 1
    # "droa": a night takes only models whose reward function DeepRacer on AWS's validator
    # would take (sim.reward.droa_rules), for a league that mirrors a DRoA event; "":
    # racer-tui's own check only.
    reward_rules: str = ""

    def __post_init__(self) -> None:
        if self.race_type is RaceType.OBJECT_AVOIDANCE and not 1 <= self.obstacles <= MAX_OBSTACLES:
            raise RulesError(
                f"an object-avoidance race needs obstacles from 1 to {MAX_OBSTACLES}, "
                f"not {self.obstacles}."
            )
        if self.race_type is RaceType.HEAD_TO_BOT and not 1 <= self.bots <= MAX_BOT_CARS:
            raise RulesError(
                f"a head-to-bot race needs bots from 1 to {MAX_BOT_CARS}, not {self.bots}."
            )

    def to_dict(self) -> dict[str, Any]:
        data = asdict(self)
        data["ranking"] = self.ranking.value
        data["race_type"] = self.race_type.value.lower()
        # Only the keys of the race's own type are kept, and none for a time trial, so the
        # rules of every race written before other race types existed keep their stored
        # form and content hash.
        if self.race_type is not RaceType.OBJECT_AVOIDANCE:
            del data["obstacles"], data["randomize_obstacles"]
        if self.race_type is not RaceType.HEAD_TO_BOT:
            del data["bots"], data["bot_speed"], data["bot_lane_change"]
        if self.race_type is RaceType.TIME_TRIAL:
            del data["race_type"]
        if self.max_offtracks_per_lap is None:
            data["max_offtracks_per_lap"] = "unlimited"
        if self.lap_count is None:
            # Left out, so the rules of every time race written before lap-count races
            # existed keep their stored form and content hash.
            del data["lap_count"]
        if self.verification is Verification.ANY:
            del data["verification"]  # likewise for every rules written before it existed
        else:
            data["verification"] = self.verification.value
        if self.min_laps == 1:
            del data["min_laps"]  # likewise
        if not self.reward_rules:
            del data["reward_rules"]  # likewise
        return data

    def lap_of(self, lap: int) -> str:
        """The lap in progress as a racer reads it: "Lap 2", or "Lap 2 of 3" in a lap-count
        race."""
        if self.lap_count is None:
            return f"Lap {lap}"
        # After the last lap the count has moved on: the race's last lap is what was run.
        return f"Lap {min(lap, self.lap_count)} of {self.lap_count}"

    def race_over(self, clock: float, laps_completed: int) -> bool:
        """Whether a race under these rules ends at `clock` with so many laps completed."""
        if self.lap_count is not None and laps_completed >= self.lap_count:
            return True
        return clock >= self.window_seconds

    @property
    def laps_scored(self) -> int:
        return 1 if self.ranking is RankingMethod.BEST_LAP else self.ranking_laps

    @property
    def race_settings(self) -> RaceSettings:
        """The race's objects as the simulation takes them (DeepRacer's settings)."""
        if self.race_type is RaceType.OBJECT_AVOIDANCE:
            boxes = ObstacleSettings(count=self.obstacles, randomize=self.randomize_obstacles)
            return RaceSettings(self.race_type, obstacles=boxes)
        if self.race_type is RaceType.HEAD_TO_BOT:
            bots = BotSettings(
                count=self.bots, speed=self.bot_speed, lane_change=self.bot_lane_change
            )
            return RaceSettings(self.race_type, bots=bots)
        return RaceSettings()

    @property
    def race_words(self) -> str:
        """The race type as a racer reads it: "time trial", "object avoidance (3 boxes)"."""
        if self.race_type is RaceType.OBJECT_AVOIDANCE:
            shuffled = ", shuffled" if self.randomize_obstacles else ""
            return f"object avoidance ({counted(self.obstacles, 'box', 'boxes')}{shuffled})"
        if self.race_type is RaceType.HEAD_TO_BOT:
            lanes = ", changing lanes" if self.bot_lane_change else ""
            return f"head-to-bot ({counted(self.bots, 'bot')} at {self.bot_speed:g} m/s{lanes})"
        if self.race_type is RaceType.HEAD_TO_MODEL:
            return "head-to-head"
        return "time trial"

    def describe(self) -> str:
        if self.race_type is RaceType.HEAD_TO_MODEL:
            return self._describe_head_to_head()
        limit = (
            "unlimited off-tracks"
            if self.max_offtracks_per_lap is None
            else f"at most {counted(self.max_offtracks_per_lap, 'off-track')} per lap"
        )
        ranking = {
            RankingMethod.BEST_LAP: "best lap",
            RankingMethod.BEST_AVERAGE: f"best average of {self.ranking_laps} consecutive laps",
            RankingMethod.TOTAL_TIME: f"total time of {self.ranking_laps} laps",
        }[self.ranking]
        length = f"{_clock(self.window_seconds)} window"
        if self.lap_count is not None:
            laps = "1 lap" if self.lap_count == 1 else f"{self.lap_count} laps"
            length = f"race of {laps} within {_clock(self.window_seconds)}"
        # "no time added" rather than "0 s": as the physical preset says it (the host walk
        # read the two as different rules).
        penalty = (
            f"{self.penalty_seconds:g} s per off-track"
            if self.penalty_seconds
            else "no time added per off-track"
        )
        words = f"{length}, {penalty}, {limit}, ranked by {ranking}"
        if self.min_laps > 1:
            words = f"{words} once {self.min_laps} laps in a row count"
        if self.reward_rules == DROA_REWARD_RULES:
            words = f"{words}, reward functions DeepRacer on AWS would take"
        if self.verification is not Verification.ANY:
            words = f"{words} ({self.verification.words})"
        if self.race_type is RaceType.TIME_TRIAL:
            return words
        crash = f"{self.collision_penalty_seconds:g} s per crash"
        return f"{self.race_words}: {words}, {crash}"

    def _describe_head_to_head(self) -> str:
        window = _clock(self.window_seconds)
        if self.lap_count is None:
            length = f"{window} window, most laps then the best lap"
        else:
            laps = "1 lap" if self.lap_count == 1 else f"{self.lap_count} laps"
            length = f"{laps} within {window}, first past the line"
        return (
            f"head-to-head: {length}, {self.penalty_seconds:g} s per off-track, "
            f"{self.collision_penalty_seconds:g} s per crash"
        )


DEFAULT_RULES = RaceRules()
DROA_RULES = RaceRules(
    window_seconds=1200.0,
    penalty_seconds=1.0,
    collision_penalty_seconds=1.0,
    max_offtracks_per_lap=None,
    ranking=RankingMethod.TOTAL_TIME,
    ranking_laps=3,
    lap_count=3,
    min_laps=3,
)

# Rules a host picks by name instead of writing a file: (name, what it is, the rules).
# "physical" is how DeepRacer's own physical events time a car (DREM's defaults: 4
# minutes, at most 3 resets a lap): the time a marshal takes to put the car back is the
# penalty, so no seconds are added.
RULE_PRESETS: tuple[tuple[str, str, RaceRules], ...] = (
    ("league", "4:00, 3 s per off-track, 3 a lap", DEFAULT_RULES),
    ("physical", "4:00, 3 resets a lap, no time added", RaceRules(penalty_seconds=0.0)),
    (
        "practice",
        "10:00, 3 s per off-track, no limit",
        RaceRules(window_seconds=600.0, max_offtracks_per_lap=None),
    ),
    (
        "object-avoidance",
        "4:00 among 3 boxes, 5 s per crash",
        RaceRules(race_type=RaceType.OBJECT_AVOIDANCE, obstacles=3),
    ),
    (
        "head-to-bot",
        "4:00 among 3 bots at 1 m/s, 5 s per crash",
        RaceRules(race_type=RaceType.HEAD_TO_BOT, bots=3, bot_lane_change=True),
    ),
    # DeepRacer on AWS's community race as its console proposes one: total time of the
    # laps run, 1 s per off-track and per collision, every reset allowed (it sends its
    # simulator 10,000), 20 minutes at most for the whole run.
    ("droa", "DeepRacer on AWS: total of 3 laps, 1 s per off-track, no limit", DROA_RULES),
)


# simapp's head-to-head evaluation as deepracer-for-cloud runs it: 3 laps, the race over
# when the first car completes them; off-tracks hold a car 2 s and crashes 5 s
# (evaluation_worker's defaults), every reset allowed. The window caps a race nobody
# finishes.
HEAD_TO_HEAD_RULES = RaceRules(
    race_type=RaceType.HEAD_TO_MODEL,
    lap_count=3,
    penalty_seconds=OFF_TRACK_PENALTY,
    collision_penalty_seconds=COLLISION_PENALTY,
    max_offtracks_per_lap=None,
)
# Presets only `racer-tui --race` takes: a night's heats are one car at a time.
RACE_ONLY_PRESETS: tuple[tuple[str, str, RaceRules], ...] = (
    (
        "head-to-head",
        "2-6 models together: 3 laps, first past the line, 2 s per off-track, 5 s per crash",
        HEAD_TO_HEAD_RULES,
    ),
)


def preset_rules(name: str) -> RaceRules:
    """The preset called `name`, or a RulesError listing them."""
    for preset, _, rules in RULE_PRESETS:
        if preset == name.strip().lower():
            return rules
    names = ", ".join(preset for preset, _, _ in RULE_PRESETS)
    raise RulesError(f"there is no rules preset {name.strip()!r}; choose one of {names}.")


# Numeric keys and their allowed ranges, in seconds.
_LIMITS: dict[str, tuple[float, float]] = {
    "window_seconds": (10.0, 3600.0),
    "penalty_seconds": (0.0, 60.0),
    "collision_penalty_seconds": (0.0, 60.0),
}


def rules_from_mapping(data: Mapping[str, Any], base: RaceRules = DEFAULT_RULES) -> RaceRules:
    """Build rules from a mapping (a YAML file, a database row, JSON); unset keys keep `base`."""
    if not isinstance(data, Mapping):
        raise RulesError(
            "the rules must be a mapping of keys to values, for example `window_seconds: 240`."
        )
    known = set(RaceRules.__dataclass_fields__)
    unknown = sorted(str(key) for key in data if key not in known)
    if unknown:
        raise RulesError(
            f"unknown rules key {unknown[0]!r}; valid keys are {', '.join(sorted(known))}."
        )
    values = base.to_dict()
    values.update(data)
    for key, (low, high) in _LIMITS.items():
        values[key] = _number(values[key], key, low, high)
    rules = RaceRules(
        window_seconds=values["window_seconds"],
        penalty_seconds=values["penalty_seconds"],
        max_offtracks_per_lap=_offtrack_limit(values["max_offtracks_per_lap"]),
        ranking=_ranking(values["ranking"]),
        ranking_laps=_whole(values["ranking_laps"], "ranking_laps", 1, 100),
        collision_penalty_seconds=values["collision_penalty_seconds"],
        lap_count=_lap_count(values.get("lap_count")),
        verification=_verification(values.get("verification", Verification.ANY.value)),
        min_laps=_whole(values.get("min_laps", 1), "min_laps", 1, 100),
        reward_rules=_reward_rules(values.get("reward_rules", "")),
        **_race_type_values(values),
    )
    for key in data:  # a key of another race type would be silently dropped: say so
        owner = _RACE_TYPE_KEYS.get(str(key))
        if owner is not None and owner is not rules.race_type:
            raise RulesError(
                f"{key} is for {owner.words} races, but these rules are a "
                f"{rules.race_type.words}'s; set race_type: {owner.value.lower()} or leave "
                f"{key} out."
            )
    if rules.lap_count is not None and rules.min_laps > rules.lap_count:
        raise RulesError(
            f"a race of {rules.lap_count} laps never has {rules.min_laps} laps in a row; "
            f"make min_laps at most {rules.lap_count} or lap_count larger."
        )
    if rules.lap_count is not None and rules.laps_scored > rules.lap_count:
        raise RulesError(
            f"a race of {rules.lap_count} laps cannot be ranked over {rules.laps_scored} "
            f"laps; make ranking_laps at most {rules.lap_count} or lap_count larger."
        )
    return rules


def load_rules(path: Path | str) -> RaceRules:
    """Read a rules YAML file; any problem is one RulesError naming the file and the key."""
    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8")
    except OSError as error:
        reason = error.strerror or str(error)
        raise RulesError(f"cannot read rules file {path}: {reason}.") from None
    except UnicodeDecodeError:
        raise RulesError(
            f"rules file {path} is not UTF-8 text; give a YAML file saved as UTF-8."
        ) from None
    try:
        data = load_data(text)
    except DuplicateKeyError as error:
        line = error.problem_mark.line + 1 if error.problem_mark is not None else "?"
        raise RulesError(
            f"rules file {path}: {error.problem} (line {line}); keep one of them."
        ) from None
    except yaml.YAMLError as error:
        mark = getattr(error, "problem_mark", None)
        where = f" at line {mark.line + 1}" if mark is not None else ""
        raise RulesError(f"rules file {path} is not valid YAML{where}; fix the syntax.") from None
    if data is None:
        return DEFAULT_RULES
    try:
        return rules_from_mapping(data)
    except RulesError as error:
        raise RulesError(f"rules file {path}: {error}") from None


def _number(value: object, key: str, low: float, high: float) -> float:
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise RulesError(f"{key} must be a number of seconds, not {value!r}.")
    number = float(value)
    if not math.isfinite(number) or not low <= number <= high:
        raise RulesError(f"{key} must be between {low:g} and {high:g} seconds, not {value!r}.")
    return number


def _whole(value: object, key: str, low: int, high: int) -> int:
    if isinstance(value, bool) or not isinstance(value, int) or not low <= value <= high:
        raise RulesError(f"{key} must be a whole number from {low} to {high}, not {value!r}.")
    return value


def _offtrack_limit(value: object) -> int | None:
    if value is None or (isinstance(value, str) and value.strip().lower() == "unlimited"):
        return None
    key = "max_offtracks_per_lap"
    if isinstance(value, bool) or not isinstance(value, int) or not 0 <= value <= 1000:
        raise RulesError(
            f"{key} must be a whole number from 0 to 1000 or 'unlimited', not {value!r}."
        )
    return value


def _lap_count(value: object) -> int | None:
    if value is None or (isinstance(value, str) and value.strip().lower() == "none"):
        return None
    if isinstance(value, bool) or not isinstance(value, int) or not 1 <= value <= 100:
        raise RulesError(
            "lap_count must be a whole number of laps from 1 to 100, or none for a race "
            f"over the whole window, not {value!r}."
        )
    return value


# Each race type's own keys.
_RACE_TYPE_KEYS: dict[str, RaceType] = {
    "obstacles": RaceType.OBJECT_AVOIDANCE,
    "randomize_obstacles": RaceType.OBJECT_AVOIDANCE,
    "bots": RaceType.HEAD_TO_BOT,
    "bot_speed": RaceType.HEAD_TO_BOT,
    "bot_lane_change": RaceType.HEAD_TO_BOT,
}


def _race_type_values(values: Mapping[str, Any]) -> dict[str, Any]:
    """The race type's keys, checked; a type's own keys take its defaults when left out."""
    raw = values.get("race_type", "time_trial")
    try:
        race_type = RaceType(str(raw).strip().upper().replace("-", "_"))
    except ValueError:
        choices = ", ".join(kind.value.lower() for kind in RaceType)
        raise RulesError(f"race_type must be one of {choices}, not {raw!r}.") from None
    out: dict[str, Any] = {"race_type": race_type}
    if race_type is RaceType.OBJECT_AVOIDANCE:
        out["obstacles"] = _whole(values.get("obstacles", 3), "obstacles", 1, MAX_OBSTACLES)
        out["randomize_obstacles"] = _flag(
            values.get("randomize_obstacles", False), "randomize_obstacles"
        )
    elif race_type is RaceType.HEAD_TO_BOT:
        out["bots"] = _whole(values.get("bots", 3), "bots", 1, MAX_BOT_CARS)
        speed = values.get("bot_speed", 1.0)
        if (
            isinstance(speed, bool)
            or not isinstance(speed, int | float)
            or not (0.1 <= float(speed) <= MAX_BOT_SPEED)
        ):
            raise RulesError(
                f"bot_speed must be a number of m/s from 0.1 to {MAX_BOT_SPEED:g}, not {speed!r}."
            )
        out["bot_speed"] = float(speed)
        out["bot_lane_change"] = _flag(values.get("bot_lane_change", False), "bot_lane_change")
    return out


def _flag(value: object, key: str) -> bool:
    if not isinstance(value, bool):
        raise RulesError(f"{key} must be true or false, not {value!r}.")
    return value


def _verification(value: object) -> Verification:
    try:
        return Verification(str(value).strip().lower())
    except ValueError:
        choices = ", ".join(level.value for level in Verification)
        raise RulesError(
            f"verification must be one of {choices} (which results count), not {value!r}."
        ) from None


def _ranking(value: object) -> RankingMethod:
    try:
        return RankingMethod(str(value))
    except ValueError:
        choices = ", ".join(method.value for method in RankingMethod)
        raise RulesError(f"ranking must be one of {choices}, not {value!r}.") from None


def _clock(seconds: float) -> str:
    minutes, rest = divmod(round(seconds), 60)
    return f"{minutes}:{rest:02d}"


class TimedLap(Protocol):
    """What scoring needs from a lap: its time with penalties, off-tracks and validity."""

    @property
    def time_seconds(self) -> float: ...
    @property
    def offtracks(self) -> int: ...
    @property
    def valid(self) -> bool: ...


@dataclass(frozen=True)
class Score:
    """A race's ranking score under its rules; `value` is None when it has no score."""

    value: float | None
    lap_numbers: tuple[int, ...]  # 1-based numbers of the laps that make the score
    offtracks: int  # off-tracks in those laps: the first tie-break
    valid_laps: int


def lap_counts(lap: TimedLap, rules: RaceRules) -> bool:
    """Whether a completed lap qualifies under the off-track limit."""
    limit = rules.max_offtracks_per_lap
    return lap.valid and (limit is None or lap.offtracks <= limit)


def score_laps(laps: Sequence[TimedLap], rules: RaceRules) -> Score:
    """The ranking score of a race's completed laps (lap number = position + 1)."""
    valid = [i for i, lap in enumerate(laps) if lap_counts(lap, rules)]
    if rules.min_laps > 1 and _longest_run(valid) < rules.min_laps:
        return Score(None, (), 0, len(valid))
    n = rules.laps_scored
    candidates: list[list[int]]
    if rules.ranking is RankingMethod.BEST_LAP:
        candidates = [[i] for i in valid]
    elif rules.ranking is RankingMethod.TOTAL_TIME:
        candidates = [valid[:n]] if len(valid) >= n else []
    else:
        valid_set = set(valid)
        candidates = [
            list(range(start, start + n))
            for start in range(len(laps) - n + 1)
            if all(i in valid_set for i in range(start, start + n))
        ]
    if not candidates:
        return Score(None, (), 0, len(valid))

    def total(indexes: list[int]) -> float:
        return sum(laps[i].time_seconds for i in indexes)

    def offtracks(indexes: list[int]) -> int:
        return sum(laps[i].offtracks for i in indexes)

    # Among equal scores prefer fewer off-tracks, then the earlier laps: a stable choice.
    best = min(candidates, key=lambda idx: (round(total(idx), 6), offtracks(idx), idx))
    value = total(best) / n if rules.ranking is RankingMethod.BEST_AVERAGE else total(best)
    return Score(value, tuple(i + 1 for i in best), offtracks(best), len(valid))


def _reward_rules(value: object) -> str:
    if value in ("", None, "racer-tui"):
        return ""
    if value == DROA_REWARD_RULES:
        return DROA_REWARD_RULES
    raise RulesError(
        f"reward_rules must be {DROA_REWARD_RULES} (DeepRacer on AWS's validator) or "
        f"racer-tui, not {value!r}."
    )


def _longest_run(indexes: Sequence[int]) -> int:
    """The most consecutive lap numbers among `indexes` (ascending)."""
    longest = run = 0
    previous = None
    for index in indexes:
        run = run + 1 if previous is not None and index == previous + 1 else 1
        longest = max(longest, run)
        previous = index
    return longest
