"""The training child's stdout stream: one JSON object per line, one typed event each.

The child (`python -m sim.training.worker`) writes these; the CLI, the TUI and the
benchmark read them through `decode`, which checks every field, so a reader never has to
trust the process on the other end of the pipe. No torch here: watchers stay light.

Every event carries `type` and `elapsed` (seconds since this training run started):

- `started`: the run began (model, track, sensors, cars, where the weights came from);
- `episode`: a training episode of one of the reported cars ended (reward, progress,
  lap time if the lap completed, DeepRacer status, steps);
- `update`: one PPO policy update (entropy, policy loss, value loss, approx KL, clip
  fraction, env steps per second, total steps) with the iteration's episode summary;
- `evaluation`: the current policy's evaluation trials (laps completed, mean progress);
- `system`: the child's CPU % and memory, about every 2 seconds;
- `checkpoint`: a checkpoint (and maybe a new best policy) was written;
- `finished` / `stopped` / `failed`: the last line of a run.
"""

from __future__ import annotations

import json
import math
import types
from dataclasses import MISSING, asdict, dataclass, fields
from typing import Any, ClassVar, Union, get_args, get_origin, get_type_hints

from sim.foundation.remedies import Fix

MAX_LINE_BYTES = 64_000


class EventError(ValueError):
    """A line that is not a valid training event."""


@dataclass(frozen=True)
class Started:
    TYPE: ClassVar[str] = "started"
    elapsed: float
    model: str
    track: str
    sensors: tuple[str, ...]
    cars: int
    resumed_from: str  # "checkpoint", "policy" (a clone's weights) or "scratch"
    total_steps: int
    max_minutes: float
    pid: int
    processes: int = 1  # simulation processes the cars are spread over (sim.training.shards)
    # The cars every training car races (sim.training.opponents), as racers name them.
    opponents: tuple[str, ...] = ()


@dataclass(frozen=True)
class Episode:
    TYPE: ClassVar[str] = "episode"
    elapsed: float
    episode: int
    car: int
    reward: float
    progress: float
    lap_time: float | None  # seconds, when the lap completed
    status: str  # DeepRacer's status label
    steps: int


@dataclass(frozen=True)
class Update:
    TYPE: ClassVar[str] = "update"
    elapsed: float
    iteration: int
    total_steps: int
    episodes: int  # all episodes finished so far, every car
    entropy: float
    policy_loss: float
    value_loss: float
    approx_kl: float
    clip_fraction: float
    steps_per_second: float  # env steps per wall-clock second, collection and learning
    iteration_episodes: int  # episodes finished in this iteration, every car
    mean_reward: float
    mean_progress: float
    laps: int  # laps completed in this iteration, every car
    best_lap: float | None  # fastest training lap of this iteration, seconds


@dataclass(frozen=True)
class Evaluation:
    TYPE: ClassVar[str] = "evaluation"
    elapsed: float
    iteration: int
    total_steps: int
    trials: int
    laps: int  # trials that completed the lap
    mean_progress: float
    best_lap: float | None
    lap_times: tuple[float, ...]
    statuses: tuple[str, ...]
    best: bool  # this evaluation produced a new best policy


@dataclass(frozen=True)
class System:
    TYPE: ClassVar[str] = "system"
    elapsed: float
    cpu_percent: float
    rss_mb: float


@dataclass(frozen=True)
class Checkpoint:
    TYPE: ClassVar[str] = "checkpoint"
    elapsed: float
    iteration: int
    total_steps: int
    file: str  # path relative to the model folder


@dataclass(frozen=True)
class Ended:
    """The last event of a run; `TYPE` is one of ENDINGS, chosen by `kind`."""

    TYPE: ClassVar[str] = "ended"
    elapsed: float
    kind: str  # "finished", "stopped" or "failed"
    message: str  # as the command line says it
    total_steps: int
    episodes: int
    best_progress: float
    best_lap: float | None
    # A failure whose message ends in a remedy a front end may offer its own way: the
    # message without it, and the remedy's name (`sim.foundation.remedies.Fix`). Empty
    # otherwise, and in the lines of older racer-tuis.
    problem: str = ""
    fix: str = ""

    @property
    def remedy(self) -> Fix | None:
        return Fix[self.fix] if self.fix else None


Event = Started | Episode | Update | Evaluation | System | Checkpoint | Ended
ENDINGS = ("finished", "stopped", "failed")
_CLASSES: dict[str, type[Any]] = {
    cls.TYPE: cls for cls in (Started, Episode, Update, Evaluation, System, Checkpoint)
}
_HINTS = {cls: get_type_hints(cls) for cls in (*_CLASSES.values(), Ended)}


def type_of(event: Event) -> str:
    return event.kind if isinstance(event, Ended) else event.TYPE


def encode(event: Event) -> str:
    """One JSON line (without the newline). Non-finite floats become null."""
    data = asdict(event)
    if isinstance(event, Ended):
        del data["kind"]
    payload = {"type": type_of(event), **{k: _plain(v) for k, v in data.items()}}
    return json.dumps(payload, separators=(",", ":"), allow_nan=False)


def _plain(value: Any) -> Any:
    if isinstance(value, float) and not math.isfinite(value):
        return None
    if isinstance(value, tuple | list):
        return [_plain(item) for item in value]
    return value


def decode(line: str | bytes) -> Event:
    """Parse and validate one line; EventError says what is wrong with it."""
    if len(line) > MAX_LINE_BYTES:
        raise EventError("event line is too long")
    try:
        data = json.loads(line)
    except (json.JSONDecodeError, UnicodeDecodeError):
        raise EventError("event line is not JSON") from None
    if not isinstance(data, dict):
        raise EventError("event line is not a JSON object")
    kind = data.get("type")
    if kind in ENDINGS:
        cls: type[Any] = Ended
        data = {**data, "kind": kind}
    elif isinstance(kind, str) and kind in _CLASSES:
        cls = _CLASSES[kind]
    else:
        raise EventError(f"unknown event type {kind!r}")
    values: dict[str, Any] = {}
    for spec in fields(cls):
        if spec.name not in data:
            if spec.default is not MISSING:  # a field newer than the line's writer
                continue
            raise EventError(f"{kind} event has no {spec.name!r}")
        values[spec.name] = _check(data[spec.name], _HINTS[cls][spec.name], f"{kind}.{spec.name}")
    if cls is Ended and values.get("fix", "") not in ("", *Fix.__members__):
        raise EventError(f"{kind}.fix names no remedy racer-tui knows")
    return cls(**values)  # type: ignore[no-any-return]


def _check(value: Any, hint: Any, where: str) -> Any:
    origin = get_origin(hint)
    if origin in (Union, types.UnionType):
        options = get_args(hint)
        if value is None and type(None) in options:
            return None
        (inner,) = (option for option in options if option is not type(None))
        return _check(value, inner, where)
    if origin is tuple:
        if not isinstance(value, list) or len(value) > 10_000:
            raise EventError(f"{where} must be a list")
        item_hint = get_args(hint)[0]
        return tuple(_check(item, item_hint, where) for item in value)
    if hint is bool:
        if not isinstance(value, bool):
            raise EventError(f"{where} must be true or false")
        return value
    if hint is int:
        if isinstance(value, bool) or not isinstance(value, int):
            raise EventError(f"{where} must be a whole number")
        return value
    if hint is float:
        if value is None:  # a non-finite figure (a NaN loss) travels as null
            return math.nan
        if isinstance(value, bool) or not isinstance(value, int | float):
            raise EventError(f"{where} must be a number")
        return float(value)
    if hint is str:
        if not isinstance(value, str) or len(value) > 4_000:
            raise EventError(f"{where} must be a short text")
        return value
    raise EventError(f"{where} has an unsupported type")  # pragma: no cover - schema bug
