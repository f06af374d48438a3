"""What each kind of pulled record must look like, checked before it touches the database.

record.py has already checked the envelope (kind, id, JSON-only types, sizes, hash). Here
each kind's body must have exactly its table's columns, each of the column's exact JSON
type (an integer where SQLite keeps INTEGER, a float where it keeps REAL: SQLite would
otherwise convert the value and the row would no longer match its content hash), and
each value must make sense: names follow the league's name rule, ids are ids, numbers
are finite and in range, rules load through sim.race.rules, a race passes
RaceResult.from_json (which recomputes its score), a season's points table passes the
league's check. A record that fails is quarantined with the reason; nothing pulled is
ever executed.
"""

from __future__ import annotations

import json
import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from datetime import date, datetime
from typing import Any, Final

from league.assembler import CONSOLE, DRFC, MAX_TRIALS, RACER_TUI
from league.assembler import LAP_COLUMNS as SUBMISSION_LAP_COLUMNS
from league.brackets import MATCH_ID_PATTERN, MAX_ENTRANTS, MIN_ENTRANTS, Format
from league.errors import LeagueError
from league.head_to_heads import MAX_INCIDENTS, lap_from_list
from league.night_changes import NIGHT_CHANGES
from league.race_types import HEAD_TO_BOT, OBJECT_AVOIDANCE, race_type_of, words
from league.racers import HEX_COLOUR, check_name
from league.races import LAP_COLUMNS as RACE_LAP_COLUMNS
from league.seasons import check_points
from league.sync.dates import check_dates
from league.sync.errors import RecordInvalidError
from league.sync.kinds import BUNDLE_KIND, MODEL_KIND, PROFILE_KIND, profile_id
from league.sync.record import HASH_PATTERN, SyncRecord, parse_json
from league.trust.keys import is_public_hex
from league.trust.roster import ACTIONS, FOUNDER_ID, ROLES
from sim.coach.plausible import first_impossible_lap
from sim.deepracer.vocabulary import is_physics
from sim.foundation.ids import is_valid_id
from sim.foundation.names import NAME_RULE, is_valid_name
from sim.physics.labels import PHYSICAL
from sim.physics.objects.settings import RaceType
from sim.race.head_to_head import INCIDENT_KINDS, MAX_CARS, MIN_CARS
from sim.race.result import MAX_RUNTIME_LENGTH, RaceResult, ResultError
from sim.race.rules import RulesError, rules_from_mapping

Checker = Callable[[Any, str], None]  # raises RecordInvalidError naming the field

MAX_TEXT: Final = 500
MAX_JSON_TEXT: Final = 64 * 1024
MAX_SECONDS: Final = 1e6
MAX_COUNT: Final = 10**9
MAX_BUNDLE_BYTES: Final = 256 * 1024 * 1024
CORRECTION_KINDS: Final = ("disqualify_lap", "rename_racer")


def _bad(field: str, what: str) -> RecordInvalidError:
    return RecordInvalidError(f"its {field} {what}")


# --- field checkers ------------------------------------------------------------------------


def name(value: Any, field: str) -> None:
    """A racer-style name: the league's rule (1-100 printable characters, stripped)."""
    try:
        ok = isinstance(value, str) and check_name(value) == value
    except LeagueError:
        ok = False
    if not ok:
        raise _bad(field, "is not a name (1 to 100 printable characters, no line breaks)")


def text(limit: int = MAX_TEXT) -> Checker:
    def check(value: Any, field: str) -> None:
        if not isinstance(value, str) or not 0 < len(value) <= limit or "\x00" in value:
            raise _bad(field, f"is not a text of 1 to {limit} characters")

    return check


def record_id(value: Any, field: str) -> None:
    if not is_valid_id(value):
        raise _bad(field, "is not a record id")


def sha256_hex(value: Any, field: str) -> None:
    if not isinstance(value, str) or not HASH_PATTERN.fullmatch(value):
        raise _bad(field, "is not a SHA-256 hash (64 lowercase hex digits)")


def model_hash(value: Any, field: str) -> None:
    # The race result's rule for driver hashes (a garage hash, or e.g. "reference:...").
    if not isinstance(value, str) or not 0 < len(value) <= 200:
        raise _bad(field, "is not a model hash")
    if not all(char.isalnum() or char in "_:.-" for char in value) or not value.isascii():
        raise _bad(field, "is not a model hash")


def timestamp(value: Any, field: str) -> None:
    """An ISO-8601 time with a UTC offset, as the league writes them."""
    parsed = None
    if isinstance(value, str) and len(value) <= 40:
        try:
            parsed = datetime.fromisoformat(value)
        except ValueError:
            parsed = None
    if parsed is None or parsed.utcoffset() is None:
        raise _bad(field, "is not an ISO-8601 time with a UTC offset")


def day(value: Any, field: str) -> None:
    """A calendar date, YYYY-MM-DD."""
    try:
        # Exactly as written, not one of the other forms Python reads (2026-W10-5).
        valid = isinstance(value, str) and date.fromisoformat(value).isoformat() == value
    except ValueError:
        valid = False
    if not valid:
        raise _bad(field, "is not a date (YYYY-MM-DD)")


def integer(low: int, high: int) -> Checker:
    def check(value: Any, field: str) -> None:
        if isinstance(value, bool) or not isinstance(value, int) or not low <= value <= high:
            raise _bad(field, f"is not a whole number from {low} to {high}")

    return check


def flag(value: Any, field: str) -> None:
    if isinstance(value, bool) or value not in (0, 1):
        raise _bad(field, "is not 0 or 1")


def real(low: float, high: float) -> Checker:
    def check(value: Any, field: str) -> None:
        if not isinstance(value, float) or not math.isfinite(value) or not low <= value <= high:
            raise _bad(field, f"is not a decimal number from {low:g} to {high:g}")

    return check


def json_text(value: Any, field: str) -> None:
    if not isinstance(value, str) or len(value) > MAX_JSON_TEXT:
        raise _bad(field, f"is not JSON text of at most {MAX_JSON_TEXT} characters")
    try:
        parse_json(value)
    except RecordInvalidError:
        raise _bad(field, "is not valid JSON") from None


def one_of(*choices: str) -> Checker:
    def check(value: Any, field: str) -> None:
        if value not in choices:
            raise _bad(field, f"is not one of {', '.join(choices)}")

    return check


def public_key(value: Any, field: str) -> None:
    if not is_public_hex(value):
        raise _bad(field, "is not a public key (64 lowercase hex digits)")


MAX_KEPT: Final = 10_000
_DIGEST_CHARS: Final = 16


def digest_list(value: Any, field: str) -> None:
    """A retire act's JSON list of record digests (league.trust.roster.record_digest)."""
    limit = MAX_KEPT * (_DIGEST_CHARS + 3) + 2
    if not isinstance(value, str) or len(value) > limit:
        raise _bad(field, f"is not a list of at most {MAX_KEPT} record digests")
    try:
        items = parse_json(value)
    except RecordInvalidError:
        items = None
    if not isinstance(items, list) or not all(
        isinstance(item, str)
        and len(item) == _DIGEST_CHARS
        and all(char in "0123456789abcdef" for char in item)
        for item in items
    ):
        raise _bad(field, f"is not a list of at most {MAX_KEPT} record digests")


def colour(value: Any, field: str) -> None:
    if not isinstance(value, str) or not HEX_COLOUR.fullmatch(value):
        raise _bad(field, "is not a #rrggbb colour")


# --- bodies --------------------------------------------------------------------------------


@dataclass(frozen=True)
class Field:
    """One column of a shared table: its SQLite type, whether it may be NULL, its check.
    An `optional` column was added after records were first shared: a record may lack it
    (league.records.OPTIONAL_COLUMNS), and it is NULL then."""

    sql_type: str
    check: Checker
    nullable: bool = False
    optional: bool = False


def _t(check: Checker, nullable: bool = False) -> Field:
    return Field("TEXT", check, nullable)


def _i(check: Checker, nullable: bool = False) -> Field:
    return Field("INTEGER", check, nullable)


def _r(check: Checker) -> Field:
    return Field("REAL", check)


def physics(value: Any, field: str) -> None:
    if not is_physics(value):
        raise _bad(field, "is not 'racer-tui/<version>' or 'deepracer'")


# Which simulator timed the laps (sim.physics.labels); absent in records made before.
_PHYSICS = Field("TEXT", physics, nullable=True, optional=True)
# The policy runtime that drove a race (sim.training.runtimes); absent for the reference
# driver, a physical car and races recorded before.
_RUNTIME = Field("TEXT", text(MAX_RUNTIME_LENGTH), nullable=True, optional=True)
# A submission's race type when it is not a time trial (league.race_types); absent in time
# trials, as in every submission made before race types.
_SUBMISSION_RACE_TYPE = Field(
    "TEXT", one_of(OBJECT_AVOIDANCE, HEAD_TO_BOT), nullable=True, optional=True
)

# A lap's crashes or reversals (a race) or immobilized or reversed count (a submission),
# counted since schema 15: absent when none, as in every lap recorded before.
_COUNT_SINCE_RESETS = Field("INTEGER", integer(1, MAX_COUNT), nullable=True, optional=True)


def match_id(value: Any, field: str) -> None:
    if not isinstance(value, str) or not MATCH_ID_PATTERN.fullmatch(value):
        raise _bad(field, "is not a bracket match (W1-1, L2-1, GF, GF2)")


# Every shared table's columns except id and content_hash (a test holds these to the
# schema in league.migrations, so the two cannot drift apart).
FIELDS: Final[dict[str, dict[str, Field]]] = {
    "roster": {
        "action": _t(one_of(*ACTIONS)),
        "public_key": _t(public_key),
        "racer": _t(name, nullable=True),
        "role": _t(one_of(*ROLES), nullable=True),
        "signed_by": _t(public_key),
        "kept": _t(digest_list, nullable=True),
        "league": _t(record_id, nullable=True),
        "created_at": _t(timestamp),
    },
    "racer": {
        "name": _t(name),
        "display_name": _t(name),
        "colour": _t(colour),
        "created_at": _t(timestamp),
    },
    "track": {"track_hash": _t(sha256_hex), "name": _t(name), "created_at": _t(timestamp)},
    "season": {"name": _t(name), "points": _t(json_text), "created_at": _t(timestamp)},
    "night": {
        "name": _t(name),
        "track_hash": _t(sha256_hex),
        "season_id": _t(record_id, nullable=True),
        "rules": _t(json_text),
        "created_at": _t(timestamp),
        # The day it is held; absent in nights opened before nights had one.
        "held_on": Field("TEXT", day, nullable=True, optional=True),
    },
    "entrant": {
        "night_id": _t(record_id),
        "racer": _t(name),
        "model": _t(text(500)),
        "created_at": _t(timestamp),
    },
    "heat": {
        "night_id": _t(record_id),
        "draw_id": _t(record_id),
        "draw_seed": _i(integer(0, 2**63 - 1)),
        "position": _i(integer(1, MAX_COUNT)),
        "entrant_id": _t(record_id),
        "created_at": _t(timestamp),
    },
    "night_closure": {
        "night_id": _t(record_id),
        "closed_by": _t(name),
        "created_at": _t(timestamp),
    },
    "night_change": {
        "night_id": _t(record_id),
        "action": _t(one_of(*NIGHT_CHANGES)),
        "target": _t(record_id),
        "made_by": _t(name),
        "created_at": _t(timestamp),
    },
    "submission": {
        "racer": _t(name),
        "track_hash": _t(sha256_hex),
        "model_name": _t(text(255)),
        "model_hash": _t(model_hash),
        "source": _t(one_of(RACER_TUI, DRFC, CONSOLE)),
        "action_space": _t(json_text, nullable=True),
        "sensors": _t(json_text, nullable=True),
        "neural_network": _t(text(100), nullable=True),
        "training_algorithm": _t(text(100), nullable=True),
        "hyperparameters": _t(json_text, nullable=True),
        "training": _t(json_text, nullable=True),
        "evaluation_file": _t(text(255)),
        "fingerprint": _t(sha256_hex),
        "submitted_at": _t(timestamp),
        "physics": _PHYSICS,
        "race_type": _SUBMISSION_RACE_TYPE,
    },
    "race": {
        "racer": _t(name),
        "track_hash": _t(sha256_hex),
        "model_name": _t(name),
        "model_hash": _t(model_hash),
        "night_id": _t(record_id, nullable=True),
        "heat_id": _t(record_id, nullable=True),
        "rules": _t(json_text),
        "seed": _i(integer(0, 2**63 - 1)),
        "started_at": _t(timestamp),
        "total_offtracks": _i(integer(0, MAX_COUNT)),
        "physics": _PHYSICS,
        "runtime": _RUNTIME,
    },
    "bracket": {
        "night_id": _t(record_id),
        "format": _t(one_of(*(form.value for form in Format))),
        "seeds": _t(json_text),
        "rules": _t(json_text),
        "created_at": _t(timestamp),
    },
    "head_to_head": {
        "track_hash": _t(sha256_hex),
        "rules": _t(json_text),
        "seed": _i(integer(0, 2**63 - 1)),
        "started_at": _t(timestamp),
        "clock": _r(real(0.0, MAX_SECONDS)),
        "cars": _t(json_text),
        "incidents": _t(json_text),
        "night_id": _t(record_id, nullable=True),
        "match_id": _t(match_id, nullable=True),
        "physics": _t(physics),
    },
    "correction": {
        "kind": _t(one_of(*CORRECTION_KINDS)),
        "target": _t(text(100)),
        "lap_number": _i(integer(1, MAX_COUNT), nullable=True),
        "new_value": _t(name, nullable=True),
        "reason": _t(text(500)),
        "made_by": _t(name),
        "created_at": _t(timestamp),
    },
}
LAP_FIELDS: Final[dict[str, dict[str, Field]]] = {
    "submission": {
        "number": _i(integer(1, MAX_TRIALS)),
        "time_seconds": _r(real(0.0, MAX_SECONDS)),
        "completion": _r(real(0.0, 100.0)),
        "status": _t(text(64)),
        "offtracks": _i(integer(0, MAX_COUNT)),
        "crashes": _i(integer(0, MAX_COUNT)),
        "completed": _i(flag),
        "immobilized": _COUNT_SINCE_RESETS,
        "reversals": _COUNT_SINCE_RESETS,
    },
    "race": {
        "number": _i(integer(1, MAX_COUNT)),
        "time_seconds": _r(real(0.0, MAX_SECONDS)),
        "raw_seconds": _r(real(0.0, MAX_SECONDS)),
        "penalty_seconds": _r(real(0.0, MAX_SECONDS)),
        "offtracks": _i(integer(0, MAX_COUNT)),
        "valid": _i(flag),
        "started_at": _r(real(0.0, MAX_SECONDS)),
        "crashes": _COUNT_SINCE_RESETS,
        "reversals": _COUNT_SINCE_RESETS,
    },
}
# One car of a head-to-head record (league.head_to_heads.car_body), with its laps as a
# race's are.
CAR_FIELDS: Final[dict[str, Field]] = {
    "car": _i(integer(0, MAX_CARS - 1)),
    "racer": _t(name),
    "model_name": _t(name),
    "model_hash": _t(model_hash),
    "finished_at": Field("REAL", real(0.0, MAX_SECONDS), nullable=True),
    "laps_completed": _i(integer(0, MAX_COUNT)),
    "distance": _r(real(-MAX_SECONDS, MAX_SECONDS * 100)),
    "gap_seconds": Field("REAL", real(0.0, MAX_SECONDS), nullable=True),
    "total_offtracks": _i(integer(0, MAX_COUNT)),
    "runtime": _RUNTIME,
}
INCIDENT_FIELDS: Final[dict[str, Field]] = {
    "clock": _r(real(0.0, MAX_SECONDS)),
    "kind": _t(one_of(*INCIDENT_KINDS)),
    "car": _i(integer(0, MAX_CARS - 1)),
    "other": _i(integer(0, MAX_CARS - 1)),
}
assert tuple(LAP_FIELDS["submission"]) == SUBMISSION_LAP_COLUMNS
assert tuple(LAP_FIELDS["race"]) == RACE_LAP_COLUMNS
MAX_LAPS: Final = {"submission": MAX_TRIALS, "race": 10_000}


def check_record(record: SyncRecord) -> None:
    """RecordInvalidError (one sentence) unless `record` is a well-formed record of its kind,
    whose id and dates agree (league.sync.dates)."""
    if record.kind == PROFILE_KIND:
        _check_profile(record)
    elif record.kind == BUNDLE_KIND:
        _check_bundle(record.body)
    elif record.kind == MODEL_KIND:
        _check_fields(record.body, MODEL_FIELDS)
    else:
        _check_fields(
            record.body, FIELDS[record.kind], extra=("laps",) * (record.kind in LAP_FIELDS)
        )
        if record.kind in LAP_FIELDS:
            _check_laps(record.body.get("laps"), record.kind)
            _check_possible_laps(record)
        _SEMANTICS.get(record.kind, _nothing)(record)
    check_dates(record)


def _check_fields(
    body: Mapping[str, Any], fields: Mapping[str, Field], extra: tuple[str, ...] = ()
) -> None:
    expected = set(fields) | set(extra)
    required = expected - {column for column, spec in fields.items() if spec.optional}
    if not required <= set(body) <= expected:
        missing = sorted(required - set(body))
        unknown = sorted(set(body) - expected)
        detail = f"lacks {', '.join(missing)}" if missing else f"has unknown {', '.join(unknown)}"
        raise RecordInvalidError(f"its fields are not its table's columns (it {detail})")
    for column, spec in fields.items():
        value = body.get(column)
        if value is None:
            if not spec.nullable:
                raise _bad(column, "is missing")
            if spec.optional and column in body:
                # Its writer leaves it out instead: a null would give the record a second
                # body, and another content hash, for the same row.
                raise _bad(column, "is null instead of left out")
            continue
        spec.check(value, column)


def _check_laps(laps: Any, kind: str) -> None:
    if not isinstance(laps, list) or len(laps) > MAX_LAPS[kind]:
        raise _bad("laps", f"are not a list of at most {MAX_LAPS[kind]} laps")
    for index, lap in enumerate(laps):
        if not isinstance(lap, dict):
            raise _bad(f"lap {index + 1}", "is not an object")
        _check_fields(lap, LAP_FIELDS[kind])
        if lap["number"] != index + 1:
            raise _bad(f"lap {index + 1}", f"is numbered {lap['number']}")


def _check_possible_laps(record: SyncRecord) -> None:
    """No lap quicker than any car could drive the track (when this machine knows it), by
    the floor for the physics that timed it (`sim.coach.plausible`)."""
    _check_laps_possible(
        str(record.body["track_hash"]), str(record.body.get("physics") or ""), record.body["laps"]
    )


def _check_laps_possible(track_hash: str, timed_by: str, laps: list[dict[str, Any]]) -> None:
    driven = [
        (lap["number"], lap.get("raw_seconds", lap["time_seconds"]))
        for lap in laps
        # A trial that stopped part-way is not a lap; a physical car's lap that does not
        # count may be one it never finished (its time is when it was given up).
        if lap.get("completed", True) and (timed_by != PHYSICAL or lap.get("valid", True))
    ]
    impossible = first_impossible_lap(track_hash, timed_by, driven)
    if impossible is not None:
        raise RecordInvalidError(
            f"its lap {impossible.number} of {impossible.seconds:.3f} s is faster than any "
            f"car can go round that track (no lap under {impossible.floor:.3f} s is possible "
            f"there: {impossible.why})"
        )


def _nothing(record: SyncRecord) -> None:
    """No checks beyond the fields'."""


def _check_season(record: SyncRecord) -> None:
    points = json.loads(record.body["points"])
    try:
        if not isinstance(points, list):
            raise LeagueError("not a list")
        check_points(points)
    except LeagueError:
        raise _bad(
            "points", "are not a points table (whole numbers, never more for a worse place)"
        ) from None


# The keys of each race type's own objects (sim.race.rules.RaceRules). Rules of another race
# type never carry them (RaceRules.to_dict leaves them out), and rules_from_mapping would
# pass over them: a record with them says one race type in its keys and another in its
# race_type, and would be ranked as the one nobody can see it raced.
_RACE_TYPE_KEYS: Final = {
    "obstacles": OBJECT_AVOIDANCE,
    "randomize_obstacles": OBJECT_AVOIDANCE,
    "bots": HEAD_TO_BOT,
    "bot_speed": HEAD_TO_BOT,
    "bot_lane_change": HEAD_TO_BOT,
}


def _rules(text_value: str) -> None:
    data = json.loads(text_value)
    try:
        if not isinstance(data, dict):
            raise RulesError("not an object")
        rules = rules_from_mapping(data)
    except RulesError as error:  # its own sentence, inside this one
        raise _bad("rules", f"are not race rules ({str(error).rstrip('.')})") from None
    kind = race_type_of(rules)
    if rules.race_type is RaceType.HEAD_TO_MODEL:
        # A head-to-head race is one record of all its cars (league.head_to_heads), never a
        # race or a night: none can have been made honestly.
        raise _bad("rules", "are a head-to-head race's, which a league keeps as one record")
    for key, owner in _RACE_TYPE_KEYS.items():
        if key in data and owner != kind:
            raise _bad(
                "rules", f"are a {words(kind)}'s but set {key}, which only {words(owner)} has"
            )


def _check_night(record: SyncRecord) -> None:
    _rules(record.body["rules"])


def _check_race(record: SyncRecord) -> None:
    _rules(record.body["rules"])
    _check_race_result(record.record_id, record.body, record.body)


def _check_race_result(record_id: str, race: Mapping[str, Any], car: Mapping[str, Any]) -> None:
    """The laps of one car (`car`: racer, model, laps, off-tracks) in a race (`race`: its
    track, rules, seed, start, physics) make a valid race result: RaceResult.from_json
    recomputes its score and holds every lap's time to its parts."""
    laps = [{**lap, "valid": bool(lap["valid"])} for lap in car["laps"]]
    try:
        RaceResult.from_json(
            {
                "result_id": record_id,
                "racer": car["racer"],
                "model_name": car["model_name"],
                "model_hash": car["model_hash"],
                "track_name": race["track_hash"][:12],
                "track_hash": race["track_hash"],
                "rules": json.loads(race["rules"]),
                "seed": race["seed"],
                "started_at": race["started_at"],
                "laps": laps,
                "total_offtracks": car["total_offtracks"],
                **({"physics": race["physics"]} if race.get("physics") else {}),
            }
        )
    except ResultError as error:
        raise RecordInvalidError(f"it is not a valid race result ({error})") from None


def _head_to_head_rules(text_value: str) -> None:
    """Rules of a head-to-head race (a bracket's matches are raced under them)."""
    try:
        rules = rules_from_mapping(json.loads(text_value))
    except (RulesError, AttributeError, TypeError) as error:
        raise _bad("rules", f"are not race rules ({str(error).rstrip('.')})") from None
    if rules.race_type is not RaceType.HEAD_TO_MODEL:
        raise _bad("rules", "are not a head-to-head race's")


def _check_bracket(record: SyncRecord) -> None:
    """A knock-out bracket (league.bracket_records): head-to-head rules for its matches,
    and 2 to 64 seeds, each an entrant's id, none twice."""
    body = record.body
    _head_to_head_rules(body["rules"])
    seeds = json.loads(body["seeds"])
    if not isinstance(seeds, list) or not MIN_ENTRANTS <= len(seeds) <= MAX_ENTRANTS:
        raise _bad("seeds", f"are not a list of {MIN_ENTRANTS} to {MAX_ENTRANTS} entrants")
    if not all(isinstance(seed, str) and is_valid_id(seed) for seed in seeds):
        raise _bad("seeds", "hold one that is not an entrant's id")
    if len(set(seeds)) != len(seeds):
        raise _bad("seeds", "name an entrant twice")


def _check_head_to_head(record: SyncRecord) -> None:
    """Rules of a head-to-head race; 2 to 6 cars, each a whole car with its race's laps,
    none quicker than the track allows; incidents between the race's own cars."""
    body = record.body
    _head_to_head_rules(body["rules"])
    if body["match_id"] is not None and body["night_id"] is None:
        raise _bad("match_id", "names a bracket match of no night")
    cars = json.loads(body["cars"])
    if not isinstance(cars, list) or not MIN_CARS <= len(cars) <= MAX_CARS:
        raise _bad("cars", f"are not a list of {MIN_CARS} to {MAX_CARS} cars")
    grid: set[int] = set()
    for position, car in enumerate(cars, start=1):
        if not isinstance(car, dict):
            raise _bad(f"car in place {position}", "is not an object")
        try:
            _check_fields(car, CAR_FIELDS, extra=("laps",))
            laps = _car_laps(car["laps"])
            _check_laps(laps, "race")
        except RecordInvalidError as error:
            raise RecordInvalidError(f"its car in place {position}: {error}") from None
        if car["car"] in grid:
            raise _bad("cars", f"hold grid slot {car['car'] + 1} twice")
        grid.add(car["car"])
        if car["laps_completed"] != len(car["laps"]):
            raise _bad(f"car in place {position}", "counts other laps than it holds")
        try:
            _check_race_result(record.record_id, body, {**car, "laps": laps})
            _check_laps_possible(body["track_hash"], body["physics"], laps)
        except RecordInvalidError as error:
            raise RecordInvalidError(f"its car in place {position}: {error}") from None
    incidents = json.loads(body["incidents"])
    if not isinstance(incidents, list) or len(incidents) > MAX_INCIDENTS:
        raise _bad("incidents", f"are not a list of at most {MAX_INCIDENTS}")
    for incident in incidents:
        if not isinstance(incident, dict):
            raise _bad("incidents", "hold one that is not an object")
        _check_fields(incident, INCIDENT_FIELDS)
        if not {incident["car"], incident["other"]} <= grid or incident["car"] == incident["other"]:
            raise _bad("incidents", "name a car that is not in the race")


def _car_laps(laps: Any) -> list[dict[str, Any]]:
    """A head-to-head car's laps, each a list of a race lap's values
    (league.head_to_heads.lap_list), as race laps' records."""
    if not isinstance(laps, list) or len(laps) > MAX_LAPS["race"]:
        raise _bad("laps", f"are not a list of at most {MAX_LAPS['race']} laps")
    width = len(RACE_LAP_COLUMNS)
    if not all(isinstance(lap, list) and len(lap) == width for lap in laps):
        raise _bad("laps", f"are not lists of a lap's {width} values")
    return [lap_from_list(lap) for lap in laps]


def _check_correction(record: SyncRecord) -> None:
    body = record.body
    if body["kind"] == "disqualify_lap":
        record_id(body["target"], "target")
        if body["lap_number"] is None or body["new_value"] is not None:
            raise RecordInvalidError("a lap disqualification needs a lap number and no new value")
    else:
        name(body["target"], "target")
        if body["lap_number"] is not None or body["new_value"] is None:
            raise RecordInvalidError("a rename needs a new display name and no lap number")


def _check_roster(record: SyncRecord) -> None:
    """Each act has its own shape: who signs it, which id it has, what it names."""
    body = record.body
    action, role, racer = body["action"], body["role"], body["racer"]
    self_signed = body["signed_by"] == body["public_key"]
    if action == "found":
        ok = record.record_id == FOUNDER_ID and self_signed and role == "organiser"
        rule = "a founding act has the founder id, the organiser role, and its own key's seal"
    elif action == "propose":
        ok = self_signed and role == "racer" and racer is not None
        rule = "a proposal has the racer role, a racer name, and its own key's seal"
    elif action == "admit":
        ok = role is not None and (role == "organiser" or racer is not None)
        rule = "an admission names a role, and a racer for the racer role"
    else:
        ok = role is None and record.record_id != FOUNDER_ID
        rule = f"a {action} names no role"
    if body["kept"] is not None and action != "retire":
        ok, rule = False, "only a retirement lists the records it keeps"
    if (body["league"] is None) != (action == "propose"):
        ok, rule = False, "every act but a proposal names its league"
    if not ok:
        raise RecordInvalidError(f"it is not a well-formed roster act ({rule})")


_SEMANTICS: Final[dict[str, Callable[[SyncRecord], None]]] = {
    "roster": _check_roster,
    "season": _check_season,
    "night": _check_night,
    "race": _check_race,
    "bracket": _check_bracket,
    "head_to_head": _check_head_to_head,
    "correction": _check_correction,
}

PROFILE_FIELDS: Final = {"racer": _t(name), "display_name": _t(name), "correction": _t(record_id)}
# A racer's word that a model is theirs (league.sync.models): the model's name as their
# results name it (a race's is a name, a submission's any text), and its hash.
MODEL_FIELDS: Final = {
    "racer": _t(name),
    "model_name": _t(text(255)),
    "model_hash": _t(model_hash),
    "registered_at": _t(timestamp),
}
BUNDLE_FIELDS: Final = {
    "model_hash": _t(sha256_hex),
    "sha256": _t(sha256_hex),
    "size": _i(integer(1, MAX_BUNDLE_BYTES)),
    "name": _t(text(64)),
}


def _check_profile(record: SyncRecord) -> None:
    _check_fields(record.body, PROFILE_FIELDS)
    if record.record_id != profile_id(record.body["racer"]):
        raise RecordInvalidError("its id is not the profile id of the racer it names")


def _check_bundle(body: Mapping[str, Any]) -> None:
    _check_fields(body, BUNDLE_FIELDS)
    if not is_valid_name(body["name"]):
        raise _bad("name", f"is not a model name ({NAME_RULE})")
