"""Trust benchmark: a dishonest racer's attacks on a shared league, and which boards show them.

    python -m benchmarks.league.trust [--stores dir,dynamodb] [--window 20] [--json]

For each store kind, a league as issue 41 tried it: an organiser who founds it, two
admitted racers (ana, honest; bob, dishonest) who race the reference driver on re:Invent
2018, and after the attacks a fresh machine that pulls the store. bob attacks with
racer-tui's own functions (its signing keys, its league API, its submit) and with write
access to the store; each attack leaves a mark (a record id and a lap time) that is looked
for on the organiser's board, the fresh machine's board and, for a local submit, bob's
own, and in the organiser's and the fresh machine's leagues. An attack is held when no
board shows its mark and neither league stores it; the honest results it aimed at must
still be in both leagues with their laps as driven. The DynamoDB store runs against a moto server
started on a loopback port in a child process and stopped at the end.

Figures are printed, never judged; the issue's target is beside them: every attack held
on every board, every honest result kept.
"""

from __future__ import annotations

import argparse
import contextlib
import hashlib
import json
import os
import sys
import tempfile
import uuid
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

from league.assembler import Submission, assemble
from league.entries import refresh_entries
from league.errors import LeagueError
from league.leaderboard import Filters, leaderboard
from league.local_racer import save_local_racer_name
from league.opening import open_league
from league.racers import ensure_racer
from league.races import LAP_COLUMNS, lap_rows, record_race
from league.races import race_result as stored_race
from league.records import record_body
from league.store import League, now_iso
from league.submissions import insert_laps, submit_model
from league.sync.engine import store_key, sync
from league.sync.record import SyncRecord, encode_envelope, make_record
from league.sync.stores import open_store
from league.tracks import ensure_track
from league.trust import membership
from league.trust.keys import SigningKey
from league.trust.seals import make_seal
from sim.deepracer.action_space import discrete_grid
from sim.deepracer.files import (
    HYPERPARAMETERS_PATH,
    MODEL_METADATA_PATH,
    TRAINING_PARAMS,
    EvaluationTrial,
    ModelMetadata,
    TrainingParams,
    default_hyperparameters,
    evaluation_metrics_path,
    write_evaluation_metrics,
    write_hyperparameters,
    write_model_metadata,
    write_training_params,
)
from sim.foundation.ids import canonical_json, new_id
from sim.physics.labels import DEEPRACER
from sim.race.engine import run_race
from sim.race.result import LapRecord, RaceResult
from sim.race.rules import DEFAULT_RULES, RaceRules, score_laps
from sim.tracks.catalog import resolve_track
from sim.tracks.track import Track

TRACK = "reinvent_base"  # re:Invent 2018: the coach's flying limit lap is 4.866 s
TARGET = "every attack held: on no board and in no league; every honest result kept"


@dataclass
class Machine:
    """One laptop: its own league database and signing key, syncing with one store."""

    name: str
    league: League
    key: SigningKey
    url: str

    def sync(self) -> None:
        with open_store(self.url) as store:
            sync(self.league, store, store_key(self.url), signing_key=self.key)

    def holds(self, record_id: str, best_lap: float | None = None) -> bool:
        """Whether the record is in this machine's league at all, on a board or not (with
        that best lap: a forged copy of an honest record is looked for by its laps)."""
        row = self.league.query_one("SELECT best_lap FROM entries WHERE entry_id = ?", (record_id,))
        if row is None:
            return any(
                self.league.query_one(f"SELECT 1 FROM {table} WHERE id = ?", (record_id,))
                for table in ("races", "submissions")
            )
        return best_lap is None or (row[0] is not None and abs(float(row[0]) - best_lap) < 1e-6)

    def keeps(self, record_id: str, best_lap: float) -> bool:
        """Whether an honest record is in this league's entries with its best lap as driven
        (not removed, not disqualified), whether or not it is its racer's best."""
        row = self.league.query_one("SELECT best_lap FROM entries WHERE entry_id = ?", (record_id,))
        return row is not None and row[0] is not None and abs(float(row[0]) - best_lap) < 1e-6

    def shows(self, record_id: str, best_lap: float | None = None) -> bool:
        """Whether any of this machine's boards shows the record (with that best lap)."""
        return any(
            row.record_id == record_id
            and (
                best_lap is None
                or (row.best_lap is not None and abs(row.best_lap - best_lap) < 1e-6)
            )
            for row in leaderboard(self.league, Filters())
        )


@dataclass
class Mark:
    """What an attack left: a record to look for on the boards (with its forged best lap),
    whether bob's own board counts (a local submit), and honest records that must stay."""

    record_id: str | None
    best_lap: float | None = None
    own_board_counts: bool = False
    honest: list[tuple[str, float]] = field(default_factory=list)
    note: str = ""


@dataclass
class World:
    root: Path
    url: str
    track: Track
    rules: RaceRules
    machines: dict[str, Machine] = field(default_factory=dict)
    honest_races: dict[str, tuple[str, float]] = field(default_factory=dict)
    seeds: Iterator[int] = field(default_factory=lambda: iter(range(100, 10_000)))

    def machine(self, name: str, racer: str | None = None) -> Machine:
        league = open_league(self.root / f"{name}-{uuid.uuid4().hex[:6]}.db")
        if racer is not None:
            save_local_racer_name(league, racer)
        made = Machine(name, league, SigningKey.generate(), self.url)
        self.machines[name] = made
        return made

    def victim_race(self) -> tuple[str, float]:
        """A new honest race of ana's, synced, and pulled by bob (and so by the attack)."""
        ana, bob = self.machines["ana"], self.machines["bob"]
        made = self.honest_race(ana, "ana", next(self.seeds))
        ana.sync()
        bob.sync()
        return made

    def honest_race(self, machine: Machine, racer: str, seed: int) -> tuple[str, float]:
        """A race of the racer's own car, as their machine records it: the laps are the
        reference driver's, raced for real here; the car's name and hash are the racer's own
        (their machine registers the model when it syncs), so a copy is another's model."""
        driven = run_race(self.track, self.rules, racer=racer, seed=seed, keep_trace=False)
        car = f"{racer}-car"
        result = replace(
            driven, model_name=car, model_hash=hashlib.sha256(car.encode()).hexdigest()
        )
        record_race(machine.league, result)
        best = result.best_lap
        assert best is not None, "the reference driver completes laps"
        return result.result_id, best.time_seconds


def _laps(times: Sequence[float], rules: RaceRules) -> tuple[LapRecord, ...]:
    laps, clock = [], 0.0
    for number, seconds in enumerate(times, start=1):
        laps.append(LapRecord(number, seconds, seconds, 0.0, 0, True, clock))
        clock += seconds
    return tuple(laps)


def forged_race(world: World, racer: str, times: Sequence[float], **changes: Any) -> RaceResult:
    laps = _laps(times, world.rules)
    result = RaceResult(
        result_id=new_id(),
        racer=racer,
        model_name="fast",
        model_hash="f" * 64,  # a made-up model hash
        track_name=world.track.name,
        track_hash=world.track.content_hash,
        rules=world.rules,
        seed=1,
        laps=laps,
        scoring=score_laps(laps, world.rules),
        total_offtracks=0,
        started_at=now_iso(),
    )
    return replace(result, **changes)


def insert_bypassing_checks(league: League, result: RaceResult) -> str:
    """What a script does when `record_race` refuses: the row written as record_race
    writes it, without any of its checks."""
    laps = lap_rows(result)
    with league.transaction():
        ensure_racer(league, result.racer)
        ensure_track(league, result.track_hash, result.track_name)
        league.insert_record(
            "races",
            {
                "racer": result.racer,
                "track_hash": result.track_hash,
                "model_name": result.model_name,
                "model_hash": result.model_hash,
                "night_id": None,
                "heat_id": None,
                "rules": json.dumps(result.rules.to_dict(), sort_keys=True),
                "seed": result.seed,
                "started_at": result.started_at,
                "total_offtracks": result.total_offtracks,
                "physics": result.physics,
            },
            record_id=result.result_id,
            children={"laps": laps},
        )
        league.conn.executemany(
            f"INSERT INTO race_laps (race_id, {', '.join(LAP_COLUMNS)}) "
            f"VALUES (?, {', '.join('?' for _ in LAP_COLUMNS)})",
            [(result.result_id, *(lap.get(column) for column in LAP_COLUMNS)) for lap in laps],
        )
    refresh_entries(league.conn, [result.result_id])
    return result.result_id


def record_or_bypass(league: League, result: RaceResult) -> str:
    try:
        return record_race(league, result)
    except LeagueError:
        return insert_bypassing_checks(league, result)


def overwrite_in_store(url: str, record: SyncRecord) -> None:
    """Write `record` over what the store holds under its key, as anyone with write
    access to the shared folder or the table can."""
    if url.startswith("dir:"):
        folder = Path(url.removeprefix("dir:")) / "records" / record.kind / record.record_id[-1]
        folder.mkdir(parents=True, exist_ok=True)
        (folder / f"{record.record_id}.json").write_bytes(encode_envelope(record))
        return
    from league.sync.aws import dynamodb_client
    from league.sync.dynamodb_table import record_item
    from league.sync.retry import RetryPolicy
    from league.sync.urls import DynamoDbUrl, parse_store_url

    parsed = parse_store_url(url)
    assert isinstance(parsed, DynamoDbUrl)
    client = dynamodb_client("us-east-1", parsed.endpoint, RetryPolicy(), 1)
    client.put_item(TableName=parsed.table, Item=record_item(record, 1_900_000_000_000))


def drfc_folder(root: Path, laps: Sequence[float], track: Track) -> Path:
    """A deepracer-for-cloud model folder whose evaluation JSON has been hand-edited."""
    folder = root / f"edited-{uuid.uuid4().hex[:6]}"
    write_model_metadata(folder / MODEL_METADATA_PATH, ModelMetadata(discrete_grid(), ("vector",)))
    write_hyperparameters(folder / HYPERPARAMETERS_PATH, default_hyperparameters())
    write_training_params(
        folder / TRAINING_PARAMS,
        TrainingParams(world_name=track.name, track_hash=track.content_hash),
    )
    trials, start = [], 5_000
    for trial, seconds in enumerate(laps, start=1):
        ms = round(seconds * 1000)
        trials.append(EvaluationTrial(100.0, start + ms, start, ms, "Lap complete", 0, trial))
        start += ms + 100
    write_evaluation_metrics(folder / evaluation_metrics_path("20261129190000"), trials, DEEPRACER)
    return folder


# --- the attacks ------------------------------------------------------------------------


def edit_another_racers_record(world: World) -> Mark:
    ana, bob = world.machines["ana"], world.machines["bob"]
    race_id, best = world.victim_race()
    honest = make_record("race", race_id, record_body(ana.league, "races", race_id))
    body = json.loads(canonical_json(honest.body))
    body["laps"] = [{**lap, "time_seconds": 5.0, "raw_seconds": 5.0} for lap in body["laps"]]
    forged = make_record("race", race_id, body)  # re-hashed; ana's seal kept, then bob's
    for seal in (make_seal(honest, ana.key), make_seal(forged, bob.key)):
        overwrite_in_store(world.url, forged.sealed(seal))
    return Mark(race_id, 5.0, honest=[(race_id, best)], note="ana's race, laps 5.000 s")


def sign_as_another_racer(world: World) -> Mark:
    bob = world.machines["bob"]
    result = run_race(world.track, world.rules, racer="ana", seed=11, keep_trace=False)
    race_id = record_or_bypass(bob.league, result)  # bob's machine, ana's name
    bob.sync()
    return Mark(race_id, note="a real race, named ana's, signed by bob")


def unadmitted_key_pushes(world: World) -> Mark:
    mallory = world.machine("mallory", racer="mallory")
    race_id, _ = world.honest_race(mallory, "mallory", seed=12)
    mallory.sync()
    return Mark(race_id, note="a real race by a key nobody admitted")


def second_key_for_a_racer(world: World) -> Mark:
    other = world.machine("ana-second-key", racer="ana")
    race_id, _ = world.honest_race(other, "ana", seed=13)
    other.sync()
    return Mark(race_id, note="a new key proposed as ana's")


def correction_as_a_racer(world: World) -> Mark:
    bob = world.machines["bob"]
    race_id, best = world.victim_race()
    # bob holds ana's race from his last pull; he disqualifies its laps and renames ana.
    try:
        from league.corrections import disqualify_lap, rename_racer

        for number in (1, 2, 3):
            with contextlib.suppress(LeagueError):
                disqualify_lap(bob.league, race_id, number, reason="cheating", by="bob")
        with contextlib.suppress(LeagueError):
            rename_racer(bob.league, "ana", "ana the slow", by="bob")
    finally:
        bob.sync()
    return Mark(None, honest=[(race_id, best)], note="bob disqualifies ana's laps")


def submit_edited_evaluation(world: World, lap: float, bypass: bool) -> Mark:
    bob = world.machines["bob"]
    folder = drfc_folder(world.root, [lap, 9.5, 9.8], world.track)
    try:
        _, submitted = submit_model(bob.league, str(folder), "bob")
        submission_id: str | None = submitted.submission_id
    except LeagueError:
        submission_id = None
    if submission_id is None and bypass:
        submission_id = insert_submission_bypassing_checks(bob.league, assemble(str(folder), "bob"))
    bob.sync()
    how = "with submit" if not bypass else "written by a script"
    return Mark(
        submission_id,
        lap,
        own_board_counts=not bypass,
        note=f"evaluation JSON edited to {lap:.3f} s, {how}",
    )


def insert_submission_bypassing_checks(league: League, submission: Submission) -> str:
    """What a script does when `submit` refuses: the rows written as `submit` writes
    them, without any of its checks."""
    laps = [lap.record() for lap in submission.laps]
    with league.transaction():
        ensure_racer(league, submission.racer)
        ensure_track(league, submission.track_hash, submission.track_name)
        body = {
            "racer": submission.racer,
            "track_hash": submission.track_hash,
            "model_name": submission.model_name,
            "model_hash": submission.model_hash,
            "source": submission.source,
            "action_space": json.dumps(submission.action_space, sort_keys=True),
            "sensors": json.dumps(submission.sensors, sort_keys=True),
            "neural_network": submission.neural_network,
            "training_algorithm": submission.training_algorithm,
            "hyperparameters": json.dumps(submission.hyperparameters, sort_keys=True),
            "training": None,
            "evaluation_file": submission.evaluation_file,
            "fingerprint": submission.fingerprint,
            "submitted_at": now_iso(),
            "physics": submission.physics,
        }
        submission_id = league.insert_record("submissions", body, children={"laps": laps})
        insert_laps(league, submission_id, laps)
        refresh_entries(league.conn, [submission_id])
    return submission_id


def own_race_at_impossible_laps(world: World) -> Mark:
    bob = world.machines["bob"]
    result = forged_race(world, "bob", [4.1, 4.1, 4.1, 4.1])
    race_id = record_or_bypass(bob.league, result)
    bob.sync()
    return Mark(race_id, 4.1, note="bob's own race, laps 4.100 s, made-up model hash")


def copy_another_racers_race(world: World, dated_1970: bool) -> Mark:
    bob = world.machines["bob"]
    race_id, best = world.victim_race()
    original = stored_race(bob.league, race_id)  # bob pulled ana's race
    copy = replace(
        original,
        result_id=new_id(0) if dated_1970 else new_id(),
        racer="bob",
        started_at="1970-01-01T00:00:00.000Z" if dated_1970 else original.started_at,
    )
    copy_id = record_or_bypass(bob.league, copy)
    bob.sync()
    when = "dated 1970" if dated_1970 else "dated as driven"
    return Mark(copy_id, best, honest=[(race_id, best)], note=f"ana's race as bob's, {when}")


ATTACKS: dict[str, Callable[[World], Mark]] = {
    "edit another racer's record in the store, re-hash it": edit_another_racers_record,
    "sign a race claiming to be another racer": sign_as_another_racer,
    "an unadmitted key pushes": unadmitted_key_pushes,
    "a second key proposed for an existing racer": second_key_for_a_racer,
    "push a correction (organiser-only) as a racer": correction_as_a_racer,
    "hand-edit an evaluation to 3.900 s, submit, sync": lambda w: submit_edited_evaluation(
        w, 3.9, bypass=False
    ),
    "the same, stored by a script past submit's checks": lambda w: submit_edited_evaluation(
        w, 3.9, bypass=True
    ),
    "sign one's own race at 4.100 s with a made-up model hash": own_race_at_impossible_laps,
    "copy another racer's race as one's own, dated 1970": lambda w: copy_another_racers_race(
        w, dated_1970=True
    ),
    "copy another racer's race as one's own, dated as driven": lambda w: copy_another_racers_race(
        w, dated_1970=False
    ),
    "submit a hand-edited 1.000 s evaluation": lambda w: submit_edited_evaluation(
        w, 1.0, bypass=False
    ),
}


# --- running them -----------------------------------------------------------------------


def make_world(root: Path, url: str, window: float) -> World:
    world = World(root, url, resolve_track(TRACK), replace(DEFAULT_RULES, window_seconds=window))
    with open_store(url) as store:
        store.init()
    organiser = world.machine("organiser", racer="organiser")
    membership.found_league(organiser.league, organiser.key)
    organiser.sync()
    for seed, racer in enumerate(("ana", "bob"), start=1):
        machine = world.machine(racer, racer=racer)
        world.honest_races[racer] = world.honest_race(machine, racer, seed)
        machine.sync()  # proposes the machine's key under its racer's name
    organiser.sync()
    for racer in ("ana", "bob"):
        membership.admit(organiser.league, organiser.key, racer)
    organiser.sync()
    for racer in ("ana", "bob"):
        world.machines[racer].sync()
    return world


def run_store(
    kind: str, url: str, root: Path, window: float, only: Sequence[str]
) -> list[dict[str, Any]]:
    world = make_world(root, url, window)
    marks: dict[str, Mark | str] = {}
    for name, attack in ATTACKS.items():
        if only and not any(word in name for word in only):
            continue
        try:
            marks[name] = attack(world)
        except Exception as error:  # an attack that cannot even be made is reported
            marks[name] = f"{type(error).__name__}: {error}"
    organiser, ana = world.machines["organiser"], world.machines["ana"]
    for honest in (organiser, ana, organiser):
        honest.sync()  # the honest machines sync once more after the attacks
    fresh = world.machine("fresh")
    fresh.sync()
    rows = []
    for name, mark in marks.items():
        if isinstance(mark, str):
            rows.append(
                {"attack": name, "store": kind, "error": mark, "held": False, "honest_kept": False}
            )
            continue
        shown, accepted = {}, []
        if mark.record_id is not None:
            accepted = [
                m.name for m in (organiser, fresh) if m.holds(mark.record_id, mark.best_lap)
            ]
            shown = {
                "organiser": organiser.shows(mark.record_id, mark.best_lap),
                "fresh": fresh.shows(mark.record_id, mark.best_lap),
            }
            if mark.own_board_counts:
                shown["own"] = world.machines["bob"].shows(mark.record_id, mark.best_lap)
        lost_on = sorted(
            {
                machine.name
                for record_id, best in mark.honest
                for machine in (organiser, fresh)
                if not machine.keeps(record_id, best)
            }
        )
        rows.append(
            {
                "attack": name,
                "store": kind,
                "note": mark.note,
                "shown_on": sorted(board for board, yes in shown.items() if yes),
                "in_league_of": accepted,
                "held": not any(shown.values()) and not accepted,
                "honest_kept": not lost_on,
                "honest_lost_on": lost_on,
            }
        )
    for machine in world.machines.values():
        machine.league.close()
    return rows


@contextlib.contextmanager
def _aws_env() -> Iterator[None]:
    saved = dict(os.environ)
    os.environ.update(
        AWS_ACCESS_KEY_ID="testing",
        AWS_SECRET_ACCESS_KEY="testing",
        AWS_DEFAULT_REGION="us-east-1",
        AWS_EC2_METADATA_DISABLED="true",
    )
    try:
        yield
    finally:
        os.environ.clear()
        os.environ.update(saved)


def run(stores: Sequence[str], window: float, only: Sequence[str] = ()) -> list[dict[str, Any]]:
    from benchmarks.league.sync import moto_server

    rows: list[dict[str, Any]] = []
    with tempfile.TemporaryDirectory(prefix="racer-tui-trust-") as tmp:
        root = Path(tmp)
        os.environ.setdefault("RACER_TUI_HOME", str(root / "home"))
        for kind in stores:
            folder = root / kind
            folder.mkdir()
            if kind == "dir":
                rows += run_store(kind, f"dir:{folder / 'store'}", folder, window, only)
            else:
                with _aws_env(), moto_server() as server:
                    url = f"dynamodb://trust-{uuid.uuid4().hex[:8]}?region=us-east-1&endpoint={server.endpoint}"
                    rows += run_store(kind, url, folder, window, only)
    return rows


def _table(rows: Sequence[dict[str, Any]]) -> str:
    """One line an attack: the boards that show its mark, the leagues that store it at all
    (organiser, fresh machine), and whether the honest results it aimed at are kept."""
    head = f"{'attack':56} {'store':8} {'shown on':17} {'stored by':17} {'honest kept':11}"
    lines = [head, f"target: {TARGET}"]
    for row in rows:
        attack = f"{row['attack'][:56]:56} {row['store']:8}"
        if "error" in row:
            lines.append(f"{attack} could not run: {row['error']}")
            continue
        shown = ", ".join(row["shown_on"]) or "no board"
        stored = ", ".join(row["in_league_of"]) or "nobody"
        kept = "yes" if row["honest_kept"] else "NO: " + ", ".join(row["honest_lost_on"])
        lines.append(f"{attack} {shown:17} {stored:17} {kept:11}")
    held = sum(1 for row in rows if row.get("held"))
    kept_count = sum(1 for row in rows if row.get("honest_kept"))
    total = len(rows)
    lines.append(f"held {held} of {total} (target {total}); honest kept {kept_count} of {total}")
    return "\n".join(lines)


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m benchmarks.league.trust", description=__doc__)
    parser.add_argument("--stores", default="dir,dynamodb", help="dir, dynamodb or both")
    parser.add_argument("--window", type=float, default=20.0, help="seconds of each honest race")
    parser.add_argument("--only", default="", help="run only attacks whose name holds these words")
    parser.add_argument("--json", action="store_true")
    args = parser.parse_args(argv)
    stores = [kind for kind in args.stores.split(",") if kind]
    rows = run(stores, args.window, [word for word in args.only.split(",") if word])
    print(json.dumps({"target": TARGET, "attacks": rows}, indent=2) if args.json else _table(rows))
    return 0


if __name__ == "__main__":
    sys.exit(main())
