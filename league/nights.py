"""League nights: a track, rules frozen when the night opens, entrants, a drawn heat order,
one race per entrant, and standings with season points when the night closes.

Every step is a new shared row (night, entrant, heats of a draw, closure): nothing is
edited in place. A redraw adds heats with a newer draw id; the latest draw orders the
entrants that have not raced yet. Under a `verification` rule, closing the night first
races its simulated heats again (`replay_heats`, through league.trust.replay).
"""

from __future__ import annotations

import json
import random
import re
import sqlite3
from collections.abc import Callable, Collection, Sequence
from dataclasses import dataclass, replace
from datetime import date, datetime
from pathlib import Path
from typing import TYPE_CHECKING

from league.bracket_records import has_bracket, read_bracket
from league.errors import LeagueError
from league.leaderboard import LeaderboardRow
from league.night_changes import DELETE, WITHDRAW
from league.racers import check_name, display_names, ensure_racer
from league.races import find_local_track, record_race
from league.seasons import DEFAULT_POINTS, get_season, night_results
from league.store import League, now_iso
from league.timekeeper.car import PHYSICAL, car_name, is_physical, physical_spec
from league.tracks import ensure_track
from league.trust.replay import DriverFor, verify_races
from sim.foundation.ids import new_id
from sim.foundation.plural import counted
from sim.foundation.remedies import Fix
from sim.garage.bundle import BundleError, read_bundle
from sim.garage.folder import ModelError, models_dir, open_model
from sim.garage.imported import BUNDLE_SUFFIX
from sim.physics.objects.settings import RaceType
from sim.race.driver import REFERENCE_NAME
from sim.race.engine import run_race as engine_run_race
from sim.race.rules import DEFAULT_RULES, DROA_REWARD_RULES, RaceRules, rules_from_mapping
from sim.reward.droa_check import droa_verdict
from sim.reward.errors import RewardFunctionError
from sim.tracks.catalog import DEFAULT_TRACK
from sim.tracks.track import Track

if TYPE_CHECKING:
    from sim.race.driver import Driver
    from sim.race.result import RaceResult

MAX_MODEL_SPEC = 500
_ID_PREFIX = re.compile(r"[0-9A-HJKMNP-TV-Z]{8,26}")  # the start of a record id


@dataclass(frozen=True)
class Night:
    id: str
    name: str
    track_hash: str
    track_name: str
    season_id: str | None
    rules: RaceRules
    created_at: str
    closed: bool
    held_on: str = ""  # YYYY-MM-DD: the day it is held (before nights had one: opened)


@dataclass(frozen=True)
class Entrant:
    id: str
    racer: str
    display_name: str
    model: str  # `reference`, a garage model name, or an absolute bundle/folder path

    @property
    def model_shown(self) -> str:
        """`model` as anything another machine or a visitor reads gives it (an export, the
        web pages): a bundle or model folder by its file name, never the path on the
        host's disk, which says who they are and where they keep their files."""
        return Path(self.model).name if Path(self.model).is_absolute() else self.model

    @property
    def car(self) -> str:
        """The car as every screen and board names it: a garage model by its name, a bundle
        or model folder by its file name (never its whole path), a physical car by its own
        name, marked physical."""
        if is_physical(self.model):
            name = car_name(self.model)
            return name if name == "physical car" else f"{name} (physical)"
        return self.model_shown


@dataclass(frozen=True)
class Heat:
    id: str
    position: int  # in the night's running order, from 1
    entrant: Entrant
    seed: int
    race_id: str | None  # the entrant's race in this night, once run


@dataclass(frozen=True)
class Standing:
    position: int | None  # None: no valid score, so unplaced
    points: int
    entry: LeaderboardRow


# --- nights ----------------------------------------------------------------------------------


def new_night(
    league: League,
    track: Track,
    *,
    rules: RaceRules = DEFAULT_RULES,
    name: str | None = None,
    season: str | None = None,
    held_on: date | None = None,
) -> Night:
    """Open a night on `track`, held on `held_on` (today by default); its rules are frozen
    in the row from now on."""
    if rules.race_type is RaceType.HEAD_TO_MODEL:
        raise LeagueError(
            "a night's heats are time trials, one car at a time, so its rules cannot be "
            "head-to-head; race models together with `racer-tui --race A B --rules "
            "head-to-head`."
        )
    day = (held_on or datetime.now().date()).isoformat()  # the host's own calendar day
    label = check_name(name, "night name") if name else f"{track.name} {day}"
    with league.transaction():
        season_row = get_season(league, season) if season else None
        ensure_track(league, track.content_hash, track.name)
        night_id = league.insert_record(
            "nights",
            {
                "name": label,
                "track_hash": track.content_hash,
                "season_id": season_row.id if season_row else None,
                "rules": json.dumps(rules.to_dict(), sort_keys=True),
                "created_at": now_iso(),
                "held_on": day,
            },
        )
    return get_night(league, night_id)


def _local_day(stamp: str) -> str:
    """The host's calendar day of a UTC time the league wrote (`created_at`)."""
    try:
        return datetime.fromisoformat(stamp).astimezone().date().isoformat()
    except ValueError:
        return stamp[:10]


def night_date(text: str) -> date:
    """The day a host typed (YYYY-MM-DD, or with / or . between), or a LeagueError saying
    how to write it."""
    typed = text.strip().replace("/", "-").replace(".", "-")
    try:
        day = date.fromisoformat(typed)
    except ValueError:
        day = None
    if day is None or len(typed) != 10 or not 2000 <= day.year <= 2100:
        raise LeagueError(
            f"{text.strip()!r} is not a night's date; write it as YYYY-MM-DD, "
            f"for example {datetime.now().date().isoformat()}."
        )
    return day


def _night(league: League, data: sqlite3.Row) -> Night:
    track = league.query_one("SELECT name FROM tracks WHERE track_hash = ?", (data["track_hash"],))
    closed = league.query_one("SELECT 1 FROM night_closures WHERE night_id = ?", (data["id"],))
    return Night(
        id=data["id"],
        name=data["name"],
        track_hash=data["track_hash"],
        track_name=track["name"] if track else data["track_hash"][:12],
        season_id=data["season_id"],
        rules=rules_from_mapping(json.loads(data["rules"])),
        created_at=data["created_at"],
        closed=closed is not None,
        held_on=data["held_on"] or _local_day(data["created_at"]),
    )


def get_night(league: League, spec: str) -> Night:
    """A night by id, by the start of its id (8+ characters), or by exact name."""
    spec = spec.strip()
    row = league.query_one("SELECT * FROM nights WHERE id = ?", (spec.upper(),))
    if row is None and _ID_PREFIX.fullmatch(spec.upper()):
        rows = league.query(
            "SELECT * FROM nights WHERE substr(id, 1, ?) = ?", (len(spec), spec.upper())
        )
        row = rows[0] if len(rows) == 1 else None
    if row is None:
        rows = league.query("SELECT * FROM nights WHERE name = ? COLLATE NOCASE", (spec,))
        if len(rows) > 1:
            raise LeagueError(
                f"{len(rows)} league nights are called {spec!r}; give the night's id "
                "(see `racer-tui night list`)."
            )
        row = rows[0] if rows else None
    if row is None or row["id"] in _deleted_nights(league):
        raise LeagueError(f"there is no league night {spec!r}; see `racer-tui night list`.")
    return _night(league, row)


def list_nights(league: League) -> list[Night]:
    deleted = _deleted_nights(league)
    return [
        _night(league, row)
        for row in league.query("SELECT * FROM nights ORDER BY id")
        if row["id"] not in deleted
    ]


# A deletion counts only while the night has no race: one pulled from another machine
# never hides results recorded here.
_DELETED_SQL = f"""
    SELECT c.night_id FROM night_changes c
    WHERE c.action = '{DELETE}' AND c.target = c.night_id
      AND NOT EXISTS (SELECT 1 FROM races r WHERE r.night_id = c.night_id)
"""
# Likewise a withdrawal counts only while the entrant has not raced.
_WITHDRAWN_SQL = f"""
    SELECT c.target FROM night_changes c
    WHERE c.night_id = ? AND c.action = '{WITHDRAW}'
      AND NOT EXISTS (
          SELECT 1 FROM races r JOIN heats h ON h.id = r.heat_id
          WHERE r.night_id = c.night_id AND h.entrant_id = c.target
      )
"""


def _deleted_nights(league: League) -> set[str]:
    return {row[0] for row in league.query(_DELETED_SQL)}


def _withdrawn(league: League, night: Night) -> set[str]:
    return {row[0] for row in league.query(_WITHDRAWN_SQL, (night.id,))}


def delete_night(league: League, night: Night, made_by: str) -> None:
    """Delete a night no heat has been raced on (opened by mistake, or never held). A
    night with results stays: close it instead, so its results keep counting."""
    who = check_name(made_by, "name")
    with league.transaction():
        _open(league, night)
        if league.query_one("SELECT 1 FROM races WHERE night_id = ?", (night.id,)):
            raise LeagueError(
                f"league night {night.name!r} has raced heats, so it cannot be deleted; "
                "close it instead (its results stay in the league).",
                problem=f"league night {night.name!r} has raced heats",
                fix=Fix.CLOSE_NIGHT,
            )
        _change(league, night, DELETE, night.id, who)


def _before_bracket(league: League, night: Night) -> None:
    """Refuse a change to the qualifying of a night whose bracket is drawn: its standings
    are the bracket's seeds (call it inside the transaction, after `_open`)."""
    if has_bracket(league, night.id):
        raise LeagueError(
            f"league night {night.name!r} has its bracket drawn: its qualifying is over, so "
            "entrants and heats stay as they are; race the bracket's matches."
        )


def _open(league: League, night: Night) -> None:
    """Refuse changes to a closed night; asks the database, not a possibly stale `night`
    (another racer-tui may have closed it since), so call it inside the transaction."""
    if night.closed or league.query_one(
        "SELECT 1 FROM night_closures WHERE night_id = ?", (night.id,)
    ):
        raise LeagueError(
            f"league night {night.name!r} is closed; its results are final (open a new night)."
        )
    if night.id in _deleted_nights(league):
        raise LeagueError(f"league night {night.name!r} was deleted (open a new night).")


# --- entrants and heats ------------------------------------------------------------------------


# What a host should know about a car before entering it (it is still entered): the app's
# add-entrant dialog says it as the car is typed, `night add` after entering it.
PHYSICAL_RULES_NOTE = (
    "A physical car is timed by hand: the physical rules (no time added per reset) are "
    "how DeepRacer's own events time one; this night keeps the rules it opened with."
)
SIMULATED_UNDER_PHYSICAL_NOTE = (
    "A simulated car under the physical rules: its off-tracks add no time, as a hand-timed "
    "car's do, and its laps rank beside theirs on this night."
)
TRAINING_NOTE = "{model} is still training: its heat races the policy it has when the heat runs."


def entrant_note(
    model: str, *, training: Collection[str], physical_rules: bool, physical_entered: bool = False
) -> str:
    """The note on entering `model` ("" for none): `training` names the garage models
    training now; `physical_rules`, whether the night races under the physical preset;
    `physical_entered`, whether a physical car is on the night already (its note was said
    then, and is not said again for every car of a fleet)."""
    if model in training:
        return TRAINING_NOTE.format(model=model)
    if is_physical(model) and not physical_rules and not physical_entered:
        return PHYSICAL_RULES_NOTE
    # Not while "physical" is still being typed (the app's dialog notes as keys come).
    if physical_rules and model and not PHYSICAL.startswith(model) and not is_physical(model):
        return SIMULATED_UNDER_PHYSICAL_NOTE
    return ""


def add_entrant(league: League, night: Night, racer: str, model: str) -> Entrant:
    spec = model_spec(model)
    if night.rules.reward_rules == DROA_REWARD_RULES:
        _check_droa_reward(night, spec)
    with league.transaction():
        _open(league, night)
        _before_bracket(league, night)
        name = ensure_racer(league, racer)
        duplicate = any(
            entrant.racer.casefold() == name.casefold() and entrant.model == spec
            for entrant in entrants(league, night)
        )
        if duplicate:
            raise LeagueError(f"{name!r} is already entered with {spec!r} on this night.")
        entrant_id = league.insert_record(
            "night_entrants",
            {"night_id": night.id, "racer": name, "model": spec, "created_at": now_iso()},
        )
    shown = display_names(league, name).get(name, name)
    return Entrant(entrant_id, name, shown, spec)


def _check_droa_reward(night: Night, spec: str) -> None:
    """A night under DeepRacer on AWS's reward rules takes a model only if DRoA's validator
    would take its reward function (on the night's track). The reference driver, a
    physical car and a model that drives with a DeepRacer graph have none to check; a
    bundle's travels as text and is checked as it is."""
    if spec == REFERENCE_NAME or is_physical(spec):
        return
    if spec.endswith(BUNDLE_SUFFIX):
        try:
            source, name = read_bundle(Path(spec)).reward_source, spec
        except BundleError as error:
            raise LeagueError(str(error)) from None
    else:
        folder = open_model(spec)
        if folder.drives_with_car_archive():
            return
        source, name = folder.reward_source(), str(folder.reward_file)
    # DRoA runs the function on its track's route: the night's, or where this machine has
    # no copy of it, the default track's (the verdict then says which it used).
    local = find_local_track(night.track_hash, night.track_name)
    try:
        verdict = droa_verdict(source, name, local.name if local else DEFAULT_TRACK)
    except RewardFunctionError as error:
        raise LeagueError(f"{spec}'s reward function could not be checked: {error}") from None
    if verdict.accepted:
        return
    first = verdict.reasons[0]
    where = f" (line {first.line})" if first.line is not None else ""
    raise LeagueError(
        f"{spec}'s reward function would be refused by DeepRacer on AWS{where}, saying "
        f'"{first.message.strip()}"; this night takes only functions DRoA takes: fix it, '
        "and check it with `racer-tui reward check --strict`."
    )


def withdraw_entrant(league: League, night: Night, entrant_id: str, made_by: str) -> Entrant:
    """Take an entrant out of the night before their heat: they leave the running order,
    and the same racer and car may be entered again."""
    who = check_name(made_by, "name")
    with league.transaction():
        _open(league, night)
        found = {entrant.id: entrant for entrant in entrants(league, night)}
        entrant = found.get(entrant_id)
        if entrant is None:
            raise LeagueError(f"there is no entrant {entrant_id} on league night {night.name!r}.")
        if entrant_id in _raced(league, night):
            raise LeagueError(
                f"{entrant.display_name} has raced on league night {night.name!r}; their "
                "result stays (a correction can disqualify a lap)."
            )
        _change(league, night, WITHDRAW, entrant_id, who)
    return entrant


def find_entrant(league: League, night: Night, racer: str, model: str | None = None) -> Entrant:
    """The night's entrant `racer` (with `model`, when the racer has entered twice)."""
    found = [
        entrant
        for entrant in entrants(league, night)
        if racer.casefold() in (entrant.racer.casefold(), entrant.display_name.casefold())
        and (model is None or _same_car(entrant.model, model))
    ]
    if not found:
        raise LeagueError(f"{racer!r} has not entered league night {night.name!r}.")
    if len(found) > 1:
        cars = ", ".join(entrant.model for entrant in found)
        raise LeagueError(f"{racer!r} has entered {len(found)} cars ({cars}); give --model too.")
    return found[0]


def _same_car(entered: str, given: str) -> bool:
    """Whether `given` names the car entered as `entered`, as a host would write it: the
    same text, a physical car's spec, or a bundle's or folder's path or file name (the
    car need not be on this machine any more)."""
    given = given.strip()
    if is_physical(given):
        return entered == physical_spec(given)
    if given in (entered, Path(entered).name):
        return True
    return entered == str(Path(given).expanduser().resolve())


def _change(league: League, night: Night, action: str, target: str, who: str) -> None:
    league.insert_record(
        "night_changes",
        {
            "night_id": night.id,
            "action": action,
            "target": target,
            "made_by": who,
            "created_at": now_iso(),
        },
    )


def model_spec(model: str) -> str:
    """What an entrant races, checked now rather than when the heat starts: `reference`, a
    garage model name, the absolute path of a bundle or model folder (so `night run`
    finds it from any working directory), or a physical car (`league.timekeeper.car`)."""

    spec = model.strip()
    if not spec or len(spec) > MAX_MODEL_SPEC:
        raise LeagueError(
            "--model must name a garage model, a bundle file, `reference` or `physical`.",
            problem="the car must be a garage model, a bundle file, `reference` or `physical`",
        )
    if spec == REFERENCE_NAME:
        return spec
    if is_physical(spec):
        return physical_spec(spec)
    if spec.endswith(BUNDLE_SUFFIX):
        path = Path(spec).expanduser()
        if not path.is_file():
            raise LeagueError(f"there is no bundle file {spec}; check the path.")
        return str(path.resolve())
    try:
        folder = open_model(spec)
    except ModelError as error:  # its remedy too: the app names its own keys
        raise LeagueError(str(error), problem=error.problem, fix=error.fix) from None
    if not (folder.has_policy() or folder.drives_with_car_archive()):
        # Refused now, not at its heat (the host walk's entrant failed on the night).
        problem = f"model {folder.name!r} has no trained policy yet"
        raise LeagueError(
            f"{problem}; train it (racer-tui train {folder.name}), then enter it.",
            problem=problem,
            fix=Fix.TRAIN_MODEL,
        )
    if folder.path.parent == models_dir():
        return folder.name
    return str(folder.path.resolve())


def entrants(league: League, night: Night) -> list[Entrant]:
    """The night's entrants in the order they were entered, less those withdrawn."""
    shown = display_names(league)
    withdrawn = _withdrawn(league, night)
    return [
        Entrant(row["id"], row["racer"], shown.get(row["racer"], row["racer"]), row["model"])
        for row in league.query(
            "SELECT * FROM night_entrants WHERE night_id = ? ORDER BY id", (night.id,)
        )
        if row["id"] not in withdrawn
    ]


def _raced(league: League, night: Night) -> dict[str, str]:
    """Entrant id -> race id, for entrants whose heat has been run."""
    rows = league.query(
        "SELECT h.entrant_id, r.id FROM races r JOIN heats h ON h.id = r.heat_id "
        "WHERE r.night_id = ? ORDER BY r.id",
        (night.id,),
    )
    return {row[0]: row[1] for row in rows}


def draw_heats(league: League, night: Night, seed: int | None = None) -> list[Heat]:
    """Draw a random order for the entrants that have not raced, and store it."""
    chosen = random.SystemRandom().randrange(2**31) if seed is None else seed
    if not 0 <= chosen < 2**62:
        raise LeagueError("--seed must be a whole number from 0 to 2^62.")
    with league.transaction():
        _open(league, night)
        _before_bracket(league, night)
        raced = _raced(league, night)
        waiting = [entrant for entrant in entrants(league, night) if entrant.id not in raced]
        if not waiting:
            raise LeagueError(
                f"league night {night.name!r} has no entrants waiting to race; add some with "
                "`racer-tui night add`."
            )
        random.Random(chosen).shuffle(waiting)
        _store_order(league, night, waiting, chosen)
    return heats(league, night)


def move_heat(league: League, night: Night, heat_id: str, offset: int) -> list[Heat]:
    """Move a waiting heat `offset` places up (negative) or down the running order: the
    host's change to the draw, stored as a new order of the heats still to race."""
    with league.transaction():
        _open(league, night)
        waiting = pending_heats(league, night)
        index = next((i for i, heat in enumerate(waiting) if heat.id == heat_id), None)
        if index is None:
            raise LeagueError("only a heat still waiting to race can be moved.")
        target = min(max(index + offset, 0), len(waiting) - 1)
        if target == index:
            edge = "first" if offset < 0 else "last"
            raise LeagueError(f"that heat is already the {edge} still to race.")
        order = [heat.entrant for heat in waiting]
        order.insert(target, order.pop(index))
        seed = league.query("SELECT draw_seed FROM heats WHERE id = ?", (heat_id,))[0][0]
        # The draw's seed, with positions after the heats already raced: no heat of this
        # draw ever races with a seed another one raced with.
        raced = len(_raced(league, night))
        _store_order(league, night, order, int(seed), first=raced + 1)
    return heats(league, night)


def _store_order(
    league: League, night: Night, order: Sequence[Entrant], seed: int, first: int = 1
) -> None:
    """A new draw: the entrants' heats in this order (call inside a transaction)."""
    draw_id = new_id()
    created = now_iso()
    for position, entrant in enumerate(order, start=first):
        league.insert_record(
            "heats",
            {
                "night_id": night.id,
                "draw_id": draw_id,
                "draw_seed": seed,
                "position": position,
                "entrant_id": entrant.id,
                "created_at": created,
            },
        )


def heats(league: League, night: Night) -> list[Heat]:
    """The running order: heats already raced (in race order), then the latest draw's."""
    by_id = {entrant.id: entrant for entrant in entrants(league, night)}
    raced = _raced(league, night)
    rows = league.query(
        "SELECT * FROM heats WHERE night_id = ? ORDER BY draw_id, position", (night.id,)
    )
    done: list[Heat] = []
    race_heats = {
        row["heat_id"]
        for row in league.query("SELECT heat_id FROM races WHERE night_id = ?", (night.id,))
    }
    latest = rows[-1]["draw_id"] if rows else None
    pending: list[Heat] = []
    for row in rows:
        if row["entrant_id"] not in by_id:
            continue  # withdrawn before their heat
        heat = Heat(
            row["id"],
            row["position"],
            by_id[row["entrant_id"]],
            _heat_seed(row["draw_seed"], row["position"]),
            raced.get(row["entrant_id"]),
        )
        if row["id"] in race_heats:
            done.append(heat)
        elif row["draw_id"] == latest and heat.race_id is None:
            pending.append(heat)
    done.sort(key=lambda heat: heat.race_id or "")
    # Numbered in the running order, the number every screen and command says (a draw's
    # own positions restart with each draw and have gaps where an entrant withdrew).
    return [replace(heat, position=number) for number, heat in enumerate(done + pending, 1)]


def _heat_seed(draw_seed: int, position: int) -> int:
    return (draw_seed * 1009 + position) % 2**31


def pending_heats(league: League, night: Night) -> list[Heat]:
    return [heat for heat in heats(league, night) if heat.race_id is None]


RunRace = Callable[..., "RaceResult"]
ResolveDriver = Callable[[str, Track], "Driver"]


def run_heats(
    league: League,
    night: Night,
    track: Track,
    resolve_driver: ResolveDriver,
    *,
    run_race: RunRace | None = None,
    on_result: Callable[[Heat, RaceResult], None] | None = None,
    limit: int | None = None,
) -> list[str]:
    """Race the pending simulated heats in order, headless, recording each result as it
    finishes; up to `limit` of them.

    `resolve_driver(model spec, track)` turns an entrant's model into a driver (the front
    end supplies it, so the league never imports policies). A heat that fails stops the
    run; the heats before it stay recorded. A physical car's heat is passed over and stays
    waiting (`timekept_heats`): only the app's timekeeper can time it; the heats raced
    meanwhile go before it in the running order (`on_result` gets each heat numbered so).
    """
    _open(league, night)  # record_race checks again for each heat, inside its transaction
    if track.content_hash != night.track_hash:
        raise LeagueError(f"that is not league night {night.name!r}'s track.")
    if run_race is None:
        run_race = engine_run_race
    todo = pending_heats(league, night)
    if not todo:
        raise LeagueError(
            f"league night {night.name!r} has no drawn heats waiting; draw them with "
            "`racer-tui night draw`."
        )
    simulated = [heat for heat in todo if not is_physical(heat.entrant.model)]
    if not simulated:
        raise LeagueError(
            f"the heats waiting on league night {night.name!r} are physical cars', which a "
            "timekeeper times: run them in the app (r on the Nights screen)."
        )
    recorded: list[str] = []
    for heat in simulated[:limit]:
        driver = resolve_driver(heat.entrant.model, track)
        result = run_race(track, night.rules, driver, racer=heat.entrant.racer, seed=heat.seed)
        recorded.append(record_race(league, result, night.id, heat_id=heat.id))
        if on_result is not None:
            # Its number in the running order now: heats raced come first, so a physical
            # car's heat passed over moves behind it, and every screen says this number.
            on_result(next(h for h in heats(league, night) if h.id == heat.id), result)
    return recorded


def timekept_heats(league: League, night: Night) -> list[Heat]:
    """The heats waiting for a timekeeper: physical cars'."""
    return [heat for heat in pending_heats(league, night) if is_physical(heat.entrant.model)]


# --- standings ----------------------------------------------------------------------------------


def night_points(league: League, night: Night) -> tuple[int, ...]:
    if night.season_id is None:
        return DEFAULT_POINTS
    return get_season(league, night.season_id).points


def standings(
    league: League,
    night: Night,
    points: Sequence[int] | None = None,
    local_models: Collection[str] = (),
) -> list[Standing]:
    """Each racer's best race of the night, ranked under the night's rules, with points.

    One ranking, as the season counts it: a night may race simulated and physical cars
    together (the host's choice), though the leaderboard never ranks their laps together.
    A racer without a valid score is unplaced and scores no points. Under a `verification`
    rule only the results it allows count (`local_models`: the garage's model hashes).
    """
    table = tuple(points) if points is not None else night_points(league, night)
    return standings_from(night_results(league, [night.id], local_models), table)


def standings_from(rows: Sequence[LeaderboardRow], points: Sequence[int]) -> list[Standing]:
    result: list[Standing] = []
    for row in rows:  # already in rank order
        placed = row.score is not None
        position = row.rank if placed else None
        earned = points[row.rank - 1] if placed and row.rank <= len(points) else 0
        result.append(Standing(position, earned, row))
    return result


def close_night(
    league: League,
    night: Night,
    closed_by: str,
    *,
    force: bool = False,
    driver_for: DriverFor | None = None,
) -> list[Standing]:
    """Close the night: no more entrants, draws or races; its standings count for the season.

    Heats still waiting are refused unless `force` (a car that cannot run must not hold the
    night open): those entrants simply have no result. Under a `verification` rule the
    night's simulated heats are first raced again here with `driver_for` (`replay_heats`):
    a heat whose laps differ is withdrawn, and the standings count only what the rule
    allows (league.night_verification says which heats do not).
    """
    who = check_name(closed_by, "name")
    if driver_for is not None and night.rules.verification.requires:
        _open(league, night)  # before racing heats again for a night that cannot close
        replay_heats(league, night, driver_for)
    with league.transaction():
        _open(league, night)
        waiting = len(pending_heats(league, night))
        drawn = read_bracket(league, night.id)
        if drawn is not None and drawn.final_order() is None and not force:
            problem = f"league night {night.name!r} has bracket matches still to race"
            raise LeagueError(
                f"{problem}; race them with `racer-tui night match`, or close anyway with "
                "--force (the night's places are then its qualifying's).",
                problem=problem,
            )
        if waiting and not force:
            problem = f"league night {night.name!r} still has {counted(waiting, 'heat')} to run"
            raise LeagueError(
                f"{problem}; run them with `racer-tui night run`, or close anyway with --force.",
                problem=problem,
                fix=Fix.RUN_HEATS,
            )
        league.insert_record(
            "night_closures", {"night_id": night.id, "closed_by": who, "created_at": now_iso()}
        )
    return standings(league, get_night(league, night.id))


def replay_heats(league: League, night: Night, driver_for: DriverFor) -> list[str]:
    """Race the night's simulated heats again here (those not verified before) and say,
    one sentence each, which were withdrawn because their laps came out differently.

    The driver comes from the caller, as for league.trust.replay: racing a trained model
    needs torch, which the league package never imports.
    """
    raced = {
        heat.race_id: f"heat {heat.position} ({heat.entrant.display_name}, {heat.entrant.car})"
        for heat in heats(league, night)
        if heat.race_id is not None and not is_physical(heat.entrant.model)
    }
    if not raced:
        return []
    verdicts = verify_races(league, driver_for, race_ids=list(raced))
    return [
        f"{raced[verdict.race_id]} is withdrawn: {verdict.detail}."
        for verdict in verdicts
        if verdict.outcome == "differs"
    ]


def find_night_track(night: Night) -> Track:
    """The night's track on this machine, found by content hash."""
    track = find_local_track(night.track_hash, night.track_name)
    if track is None:
        problem = (
            f"league night {night.name!r} races on track {night.track_name!r}, which is not on "
            "this machine"
        )
        raise LeagueError(
            f"{problem}; import it with `racer-tui tracks import FILE`.",
            problem=problem,
            fix=Fix.IMPORT_TRACK,
        )
    return track
