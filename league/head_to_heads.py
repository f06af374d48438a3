"""Head-to-head races in the league: one shared record per race, every car in it.

A head-to-head race (sim.race.head_to_head) is one result of two to six racers' cars, so
it is one record, `head_to_heads`, signed as a whole: its track, rules, seed and clock; its
cars in finishing order, each with its racer, model, laps (as a race's laps are kept),
where it ended and how far behind the winner; its crashes and overtakes. A car's laps are
never a time-trial entry: a lap among rivals does not compare with a lap alone, so they
rank on no lap board. What a head-to-head race counts for is who beat whom:
`head_to_head_board` (wins and losses) and `record_between` (two racers' record against
each other).

Only an organiser signs one (league.trust.roster): it names several racers, and no racer
may put a result on another's record. Every car's laps are held to the track's fastest
possible lap, as every race's are (`check_possible_laps`).
"""

from __future__ import annotations

import json
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

from league.brackets import MATCH_ID_PATTERN
from league.errors import LeagueError
from league.racers import ensure_racer
from league.races import LAP_COLUMNS, OPTIONAL_LAP_COLUMNS, check_possible_laps, lap_rows
from league.store import League, record_body
from league.tracks import ensure_track
from sim.foundation.ids import content_hash, is_valid_id
from sim.physics.labels import PHYSICAL
from sim.physics.objects.settings import RaceType
from sim.race.head_to_head import CarFinish, HeadToHeadResult, Incident

TABLE = "head_to_heads"
# A synced record's longest text (league.sync.record.MAX_STRING_CHARS): the cars, with
# their laps, and the incidents must each fit in one.
MAX_TEXT = 32 * 1024
# Incidents a record keeps, the first of the race: a 3-lap race of six cars has tens. They
# tell the race; its result is the cars' order and laps.
MAX_INCIDENTS = 400


def lap_list(lap: Mapping[str, Any]) -> list[Any]:
    """A race lap's record (league.races.lap_rows) as a list in `LAP_COLUMNS` order, its
    optional counts 0 when it has none: six cars' laps fit in one synced text."""
    return [lap.get(column, 0) for column in LAP_COLUMNS]


def lap_from_list(values: Sequence[Any]) -> dict[str, Any]:
    """`lap_list`'s lap as a race lap's record holds it (the optional counts left out when
    there are none)."""
    lap = dict(zip(LAP_COLUMNS, values, strict=True))
    for column in OPTIONAL_LAP_COLUMNS:
        if lap[column] == 0:
            del lap[column]
    return lap


def car_body(finish: CarFinish) -> dict[str, Any]:
    """One car of a head-to-head record, as the record's `cars` list holds it."""
    result = finish.result
    body: dict[str, Any] = {
        "car": finish.car,
        "racer": result.racer,
        "model_name": result.model_name,
        "model_hash": result.model_hash,
        "finished_at": finish.finished_at,
        "laps_completed": finish.laps_completed,
        "distance": round(finish.distance, 6),
        "gap_seconds": finish.gap_seconds,
        "total_offtracks": result.total_offtracks,
        "laps": [lap_list(lap) for lap in lap_rows(result)],
    }
    if result.runtime:  # only a policy has one, as in a race's record
        body["runtime"] = result.runtime
    return body


def incident_body(incident: Incident) -> dict[str, Any]:
    return {
        "clock": incident.clock,
        "kind": incident.kind,
        "car": incident.car,
        "other": incident.other,
    }


def _text(value: object) -> str:
    return json.dumps(value, sort_keys=True, separators=(",", ":"))


def record_head_to_head(
    league: League,
    result: HeadToHeadResult,
    *,
    night_id: str | None = None,
    match_id: str | None = None,
) -> str:
    """Store `result` (one transaction) and return its id, the race's own. Recording the
    same race twice is a no-op; the same id with other content is refused."""
    if not is_valid_id(result.race_id):
        raise LeagueError(f"head-to-head race id {result.race_id!r} is not a valid record id.")
    if result.rules.race_type is not RaceType.HEAD_TO_MODEL:
        raise LeagueError("only a head-to-head race's result is recorded as one.")
    if match_id is not None and (night_id is None or not MATCH_ID_PATTERN.fullmatch(match_id)):
        raise LeagueError(
            f"{match_id!r} is not a bracket match of a night (W1-1, L2-1, GF, GF2 with its night)."
        )
    for finish in result.cars:
        check_possible_laps(finish.result)  # before the transaction: a floor takes a moment
    physics = {finish.result.physics for finish in result.cars}
    if len(physics) != 1:
        raise LeagueError("the cars of one head-to-head race were timed by different physics.")
    incidents = _text([incident_body(i) for i in result.incidents[:MAX_INCIDENTS]])
    with league.transaction():
        cars = []
        for finish in result.cars:
            racer = ensure_racer(league, finish.result.racer)
            cars.append({**car_body(finish), "racer": racer})
        cars_text = _text(cars)
        if len(cars_text) > MAX_TEXT:
            raise LeagueError(
                f"the race's {sum(len(car['laps']) for car in cars)} laps are more than one "
                "shared record holds; race a head-to-head over fewer laps or a shorter "
                "window."
            )
        fields = {
            "track_hash": result.track_hash,
            "rules": json.dumps(result.rules.to_dict(), sort_keys=True),
            "seed": result.seed,
            "started_at": result.started_at,
            "clock": result.clock,
            "cars": cars_text,
            "incidents": incidents,
            "night_id": night_id,
            "match_id": match_id,
            "physics": physics.pop(),
        }
        existing = league.query_one(
            f"SELECT content_hash FROM {TABLE} WHERE id = ?", (result.race_id,)
        )
        if existing is not None:
            if existing["content_hash"] == content_hash(record_body(fields)):
                return result.race_id
            raise LeagueError(
                f"head-to-head race {result.race_id} is already recorded with different "
                "content; a recorded race never changes."
            )
        if (
            night_id is not None
            and league.query_one("SELECT 1 FROM nights WHERE id = ?", (night_id,)) is None
        ):
            raise LeagueError(f"there is no league night {night_id}; see `racer-tui night list`.")
        ensure_track(league, result.track_hash, result.track_name)
        league.insert_record(TABLE, fields, record_id=result.race_id)
    return result.race_id


# --- reading ---------------------------------------------------------------------------------


@dataclass(frozen=True)
class CarPlace:
    """One car's place in a recorded head-to-head race."""

    position: int  # 1-based
    racer: str
    model_name: str
    laps_completed: int
    finished_at: float | None
    gap_seconds: float | None
    best_lap: float | None  # its best valid lap, seconds


@dataclass(frozen=True)
class RecordedHeadToHead:
    id: str
    track_hash: str
    started_at: str
    seed: int
    clock: float
    places: tuple[CarPlace, ...]  # in finishing order
    night_id: str | None
    match_id: str | None
    hand_timed: bool = False  # physical cars timed by hand: nothing to replay

    @property
    def winner(self) -> str:
        return self.places[0].racer


def _place(position: int, car: Mapping[str, Any], *, hand_timed: bool = False) -> CarPlace:
    laps = [lap_from_list(values) for values in car["laps"]]
    valid = [lap["time_seconds"] for lap in laps if lap["valid"]]
    model = str(car["model_name"])
    return CarPlace(
        position=position,
        racer=str(car["racer"]),
        # A physical car is named as the lap boards name it: "red" is not a model.
        model_name=f"{model} ({PHYSICAL})" if hand_timed else model,
        laps_completed=int(car["laps_completed"]),
        finished_at=car["finished_at"],
        gap_seconds=car["gap_seconds"],
        best_lap=min(valid, default=None),
    )


def _where(track_hash: str | None, night_id: str | None) -> tuple[str, tuple[str, ...]]:
    where, values = [], []
    if track_hash is not None:
        where.append("track_hash = ?")
        values.append(track_hash)
    if night_id is not None:
        where.append("night_id = ?")
        values.append(night_id)
    return (f"WHERE {' AND '.join(where)}" if where else ""), tuple(values)


def has_head_to_heads(
    league: League, *, track_hash: str | None = None, night_id: str | None = None
) -> bool:
    """Whether any head-to-head race is recorded (on one track, or of one night), without
    reading one: a lap board asks on every read whether to offer the head-to-head board."""
    clause, values = _where(track_hash, night_id)
    return league.query_one(f"SELECT 1 FROM {TABLE} {clause} LIMIT 1", values) is not None


def head_to_head_races(
    league: League, *, track_hash: str | None = None, night_id: str | None = None
) -> list[RecordedHeadToHead]:
    """The recorded head-to-head races, oldest first (on one track, or of one night)."""
    clause, values = _where(track_hash, night_id)
    rows = league.query(
        f"SELECT id, track_hash, started_at, seed, clock, cars, night_id, match_id, physics "
        f"FROM {TABLE} {clause} ORDER BY started_at, id",
        values,
    )
    return [
        RecordedHeadToHead(
            id=row["id"],
            track_hash=row["track_hash"],
            started_at=row["started_at"],
            seed=row["seed"],
            clock=row["clock"],
            places=tuple(
                _place(position, car, hand_timed=row["physics"] == PHYSICAL)
                for position, car in enumerate(json.loads(row["cars"]), start=1)
            ),
            night_id=row["night_id"],
            match_id=row["match_id"],
            hand_timed=row["physics"] == PHYSICAL,
        )
        for row in rows
    ]


# --- the board -------------------------------------------------------------------------------


@dataclass(frozen=True)
class HeadToHeadStanding:
    """A racer's head-to-head record, car for car (a racer with two cars in one race, a
    model raced against itself, starts twice): starts, wins, losses (finished behind
    someone), and rival cars beaten and beaten by."""

    racer: str
    starts: int
    wins: int
    losses: int
    beaten: int  # cars that finished behind this racer's, over all races
    beaten_by: int  # cars that finished ahead of it


def head_to_head_board(races: Sequence[RecordedHeadToHead]) -> list[HeadToHeadStanding]:
    """Each racer's record over `races`, most wins first; then fewest losses, then more
    rivals beaten, then the name (a board is the same on every machine)."""
    tally: dict[str, list[int]] = {}
    for race in races:
        cars = len(race.places)
        for place in race.places:
            figures = tally.setdefault(place.racer, [0, 0, 0, 0, 0])
            figures[0] += 1
            figures[1 if place.position == 1 else 2] += 1
            figures[3] += cars - place.position
            figures[4] += place.position - 1
    standings = [HeadToHeadStanding(racer, *figures) for racer, figures in tally.items()]
    return sorted(
        standings, key=lambda s: (-s.wins, s.losses, -s.beaten, s.racer.casefold(), s.racer)
    )


def record_between(races: Sequence[RecordedHeadToHead], one: str, other: str) -> tuple[int, int]:
    """(times `one` finished ahead of `other`, times `other` finished ahead of `one`) in the
    races both were in, each by their better car."""
    ahead = behind = 0
    for race in races:
        positions: dict[str, int] = {}
        for place in reversed(race.places):  # the better car's place is set last
            positions[place.racer] = place.position
        if one in positions and other in positions:
            if positions[one] < positions[other]:
                ahead += 1
            else:
                behind += 1
    return ahead, behind
