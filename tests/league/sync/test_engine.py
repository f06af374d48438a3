"""Two racers with separate league databases syncing through each store (the shared folder
and DynamoDB on a real loopback server) until they print the same leaderboards; and every
failure the issue lists: a push killed halfway, two pushes at once, a conflicting record,
malformed records in the store, and the store down."""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from league.opening import open_league
from league.races import record_race
from league.records import record_body, store_record
from league.store import League
from league.sync.engine import SyncSummary, push, store_key, sync
from league.sync.outgoing import count_unsent, unsent_batches
from league.sync.record import SyncRecord, make_record
from league.sync.stores import open_store
from sim.foundation.ids import new_id
from sim.tracks.catalog import resolve_track
from tests.conftest import REPO_ROOT
from tests.league.helpers import race_result
from tests.league.sync.conftest import QUICK_RETRY, StoreFactory
from tests.league.sync.leagues import (
    add_submissions,
    found_store,
    host_league,
    sealed,
    shared_rows,
    views,
)
from tests.league.sync.test_store_contract import pull_all


@pytest.fixture
def url(store_url: str, open_racer_store: StoreFactory, tmp_path: Path) -> str:
    """The URL of one shared store, initialised and founded by the organiser."""
    found_store(store_url, tmp_path)
    return store_url


def sync_with(league: League, url: str, **options: bool) -> SyncSummary:
    with open_store(url, retry=QUICK_RETRY) as store:
        return sync(league, store, store_key(url), **options)


def all_records(league: League) -> list[SyncRecord]:
    """Every shared record of a league, as a push would send it."""
    return [record for batch in unsent_batches(league, "nowhere") for record in batch.records]


def result_keys(records: list[SyncRecord]) -> list[tuple[str, str]]:
    """The keys of the league's own records, without the roster acts every league adds
    (the founding record, each league's proposal of its key)."""
    return sorted(record.key for record in records if record.kind != "roster")


def clean(summary: SyncSummary) -> bool:
    return not (summary.conflicts or summary.quarantined or summary.refused or summary.damaged)


def test_two_racers_reach_identical_leaderboards(url: str, tmp_path: Path) -> None:
    with open_league(tmp_path / "host.db") as host, open_league(tmp_path / "racer.db") as racer:
        host_league(host, tmp_path)  # makes racer "ana" first
        # The racer made their own "ana", "dee" and the same track before ever syncing.
        add_submissions(racer, tmp_path, [("ana", (10.2, 10.9)), ("dee", (12.2,))])
        summaries = [sync_with(host, url), sync_with(racer, url)]
        summaries.append(sync_with(host, url))

        assert all(clean(summary) for summary in summaries)
        assert views(host) == views(racer)
        assert shared_rows(host) == shared_rows(racer)
        board = views(racer)["leaderboard"]
        assert {row["racer"] for row in board} == {"ana", "bob", "Cyrus", "dee"}
        # One racer "ana" on both machines: the first one made, with both racers' entries.
        ana_ids = {
            league.query("SELECT id FROM racers WHERE name = 'ana'")[0][0]
            for league in (host, racer)
        }
        assert len(ana_ids) == 1
        ana_entries = racer.query("SELECT count(*) FROM entries WHERE racer = 'ana'")[0][0]
        assert ana_entries == 3  # a night race and a submission by the host, one by the racer
        assert {row["kind"] for row in racer.query("SELECT kind FROM sync_aliases")} == {
            "racer",
            "track",
        }

        again = sync_with(host, url)
        assert (again.pushed, again.pulled) == (0, 0)
        assert count_unsent(racer, store_key(url)) == 0


def _worker(db: Path, url: str, batch: int, *stop_after: str) -> subprocess.Popen[str]:
    worker = subprocess.Popen(
        [
            sys.executable,
            "-m",
            "tests.league.sync.sync_worker",
            str(db),
            url,
            str(batch),
            *stop_after,
        ],
        cwd=REPO_ROOT,
        stdin=subprocess.PIPE,
        stdout=subprocess.PIPE,
        text=True,
    )
    assert worker.stdout is not None
    assert worker.stdout.readline().strip() == "ready"  # waits for the process, no sleep
    return worker


def _go(worker: subprocess.Popen[str]) -> None:
    assert worker.stdin is not None
    worker.stdin.write("go\n")
    worker.stdin.flush()


def test_a_push_killed_halfway_then_repeated_stores_every_record_once(
    url: str, open_racer_store: StoreFactory, tmp_path: Path
) -> None:
    db = tmp_path / "a.db"
    with open_league(db) as league:
        add_submissions(league, tmp_path, [(f"racer-{n}", (10.0 + n,)) for n in range(8)])
        expected = result_keys(all_records(league))
    worker = _worker(db, url, 4, "6")
    _go(worker)
    assert worker.stdout is not None
    while worker.stdout.readline().strip() != "stopped":
        pass
    worker.kill()  # mid-batch: the store has some records its bookkeeping does not know
    worker.wait(timeout=30)

    with open_league(db) as league:
        assert 0 < count_unsent(league, store_key(url)) < len(expected)
        with open_store(url, retry=QUICK_RETRY) as store:
            repeated = push(league, store, store_key(url))
        assert repeated.skipped > 0 and clean(repeated)
        pulled = pull_all(open_racer_store())
        assert result_keys(list(pulled.records)) == expected  # each record once
        assert pulled.quarantined == []
        with open_league(tmp_path / "b.db") as other:
            assert clean(sync_with(other, url))
            assert views(other) == views(league)


def test_concurrent_pushes_from_two_processes_through_the_engine(
    url: str, open_racer_store: StoreFactory, tmp_path: Path
) -> None:
    first, second = tmp_path / "first.db", tmp_path / "second.db"
    with open_league(first) as league:
        add_submissions(league, tmp_path, [("ana", (11.0,)), ("bob", (11.5,))])
    assert not first.with_name("first.db-wal").exists()  # closed: the WAL is checkpointed
    shutil.copy(first, second)  # both machines hold the same records, neither has pushed
    for db, racer in ((first, "cy"), (second, "dee")):
        with open_league(db) as league:
            add_submissions(league, tmp_path / racer, [(racer, (12.0,)), ("ana", (10.5,))])

    workers = [_worker(first, url, 3), _worker(second, url, 3)]
    for worker in workers:
        _go(worker)
    summaries = []
    for worker in workers:
        out, _ = worker.communicate(timeout=120)
        assert worker.returncode == 0
        summaries.append(json.loads(out.strip().splitlines()[-1]))
    assert all(summary["conflicts"] == [] for summary in summaries)

    with open_league(first) as one, open_league(second) as two:
        expected = {key for league in (one, two) for key in result_keys(all_records(league))}
        pulled = pull_all(open_racer_store())
        assert result_keys(list(pulled.records)) == sorted(expected)
        with open_league(tmp_path / "third.db") as three:
            for league in (one, two, three, one):
                assert clean(sync_with(league, url))
            assert views(one) == views(two) == views(three)


def test_a_conflicting_record_is_reported_with_both_sides_and_never_overwritten(
    url: str, tmp_path: Path
) -> None:
    with open_league(tmp_path / "a.db") as mine, open_league(tmp_path / "b.db") as theirs:
        (submission,) = add_submissions(mine, tmp_path, [("ana", (11.0,))])
        # Another machine holds the same id with other content (a bug, or tampering).
        with theirs.transaction():
            for table in ("racers", "tracks"):
                (row_id,) = mine.query_one(f"SELECT id FROM {table}")
                store_record(theirs, table, row_id, record_body(mine, table, row_id))
            body = record_body(mine, "submissions", submission)
            body["laps"][0]["time_seconds"] = 9.0
            store_record(theirs, "submissions", submission, body)
        theirs_hash = theirs.query_one("SELECT content_hash FROM submissions")[0]
        assert clean(sync_with(mine, url))

        found = sync_with(theirs, url)
        (reported,) = found.conflicts  # found by the push; the pull brings their side
        assert submission in reported
        assert theirs.query_one("SELECT content_hash FROM submissions")[0] == theirs_hash
        (conflict,) = theirs.query("SELECT * FROM sync_conflicts")
        assert conflict["record_id"] == submission and conflict["kind"] == "submission"
        assert conflict["local_hash"] == theirs_hash
        assert conflict["remote_hash"] == mine.query_one("SELECT content_hash FROM submissions")[0]
        assert json.loads(conflict["local_body"])["laps"][0]["time_seconds"] == 9.0
        assert json.loads(conflict["remote_body"])["laps"][0]["time_seconds"] == 11.0

        assert clean(sync_with(theirs, url))  # reported once, kept in `sync status`
        assert clean(sync_with(mine, url))
        assert mine.query_one("SELECT content_hash FROM submissions")[0] != theirs_hash


def _put_raw(url: str, tmp_path: Path, store_kind: str, record_id: str) -> None:
    """A record in the store that is not valid JSON, put there by something else."""
    if store_kind == "dir":
        shard = Path(url.removeprefix("dir:")) / "records" / "submission" / record_id[-1]
        shard.mkdir(parents=True, exist_ok=True)
        path = shard / f"{record_id}.json"
        path.write_bytes(b'{"format": 1, "kind": "submission", oops')
        os.utime(path, (1_700_000_000, 1_700_000_000))  # old: not a file still being written
        return
    from league.sync.aws import dynamodb_client
    from league.sync.dynamodb_table import push_key, shard_of
    from league.sync.urls import DynamoDbUrl, parse_store_url

    parsed = parse_store_url(url)
    assert isinstance(parsed, DynamoDbUrl)
    client = dynamodb_client("us-east-1", parsed.endpoint, QUICK_RETRY, 1)
    pk = f"submission#{record_id}"
    placeholder = make_record("submission", record_id, {"x": 1})
    client.put_item(
        TableName=parsed.table,
        Item={
            "pk": {"S": pk},
            "body": {"S": "{not json"},
            "content_hash": {"S": "0" * 64},
            "version": {"N": "0"},
            "shard": {"S": shard_of(pk)},
            "pushed_key": {"S": push_key(1_800_000_000_000, placeholder)},
        },
    )


def test_malformed_records_in_the_store_are_quarantined_and_the_rest_syncs(
    url: str, store_kind: str, open_racer_store: StoreFactory, tmp_path: Path
) -> None:
    with open_league(tmp_path / "a.db") as mine, open_league(tmp_path / "b.db") as theirs:
        add_submissions(mine, tmp_path, [("ana", (11.0,)), ("bob", (11.4,))])
        host_league(mine, tmp_path)
        assert clean(sync_with(mine, url))
        race = mine.query_one("SELECT id FROM races ORDER BY id")[0]
        bad_race = record_body(mine, "races", race)
        bad_race["laps"][0]["time_seconds"] += 5.0  # no longer raw + penalty
        padded = {
            "name": " ana ",
            "display_name": "ana",
            "colour": "#ffffff",
            "created_at": "2026-01-01T00:00:00.000Z",
        }
        bad = [make_record("race", new_id(), bad_race), make_record("racer", new_id(), padded)]
        open_racer_store().push(sealed(*bad))
        _put_raw(url, tmp_path, store_kind, new_id())

        pulled = sync_with(theirs, url)
        assert len(pulled.quarantined) == 3
        assert pulled.pulled == len(all_records(mine)) + 1  # and the profile of renamed "cy"
        assert views(theirs) == views(mine)
        rows = theirs.query("SELECT * FROM sync_quarantine")
        assert {(row["kind"], row["record_id"] is not None) for row in rows} == {
            ("race", True),
            ("racer", True),
            ("submission", True),
        }
        reasons = " ".join(row["reason"] for row in rows)
        assert "not a valid race result" in reasons and "is not a name" in reasons


def test_a_racer_dated_before_any_league_cannot_take_over_a_name(
    url: str, open_racer_store: StoreFactory, tmp_path: Path
) -> None:
    # The identity rule lets the first racer made keep a name everywhere; an id dated
    # 1 ms after 1970 would always be first, and rename the real "ana" on every machine.
    with open_league(tmp_path / "a.db") as mine:
        add_submissions(mine, tmp_path, [("ana", (11.0,))])
        assert clean(sync_with(mine, url))
        forged = {
            "name": "ana",
            "display_name": "ana (impostor)",
            "colour": "#000000",
            "created_at": "1970-01-01T00:00:00.001Z",
        }
        open_racer_store().push(sealed(make_record("racer", new_id(now_ms=1), forged)))
        pulled = sync_with(mine, url)
        assert len(pulled.quarantined) == 1
        (row,) = mine.query("SELECT kind, reason FROM sync_quarantine")
        assert row["kind"] == "racer"
        assert row["reason"].startswith("its id claims it was made on 1970-01-01, which cannot")
        racer = mine.query_one("SELECT display_name, colour FROM racers WHERE name = 'ana'")
        assert racer["display_name"] == "ana" and racer["colour"] != "#000000"


def test_a_race_faster_than_any_car_could_drive_never_reaches_a_leaderboard(
    url: str, open_racer_store: StoreFactory, tmp_path: Path
) -> None:
    # Every lap edited to 3.000 s on a 17.8 m track whose shortest loop is 12.8 m (at
    # 4 m/s at least 3.19 s), the content hash recomputed so the record looks whole.
    hairpin = resolve_track("hairpin-circuit")
    with open_league(tmp_path / "a.db") as mine, open_league(tmp_path / "b.db") as theirs:
        record_race(mine, race_result("mallory", [12.0, 11.8], track=hairpin))
        honest = next(r for r in all_records(mine) if r.kind == "race")
        forged = dict(honest.body)
        forged["laps"] = [
            {**lap, "time_seconds": 3.0, "raw_seconds": 3.0, "penalty_seconds": 0.0}
            for lap in honest.body["laps"]
        ]
        racer = next(r for r in all_records(mine) if r.kind == "racer")
        track = next(r for r in all_records(mine) if r.kind == "track")
        open_racer_store().push(sealed(racer, track, make_record("race", new_id(), forged)))
        pulled = sync_with(theirs, url)
        assert len(pulled.quarantined) == 1
        (row,) = theirs.query("SELECT kind, reason FROM sync_quarantine")
        assert row["kind"] == "race"
        assert "lap 1 of 3.000 s is faster than any car can go round that track" in row["reason"]
        assert theirs.query("SELECT * FROM races") == []


def test_a_record_that_arrives_before_what_it_refers_to_waits_for_it(
    open_racer_store: StoreFactory, url: str, tmp_path: Path
) -> None:
    with open_league(tmp_path / "a.db") as mine, open_league(tmp_path / "b.db") as theirs:
        add_submissions(mine, tmp_path, [("ana", (11.0,))])
        records = all_records(mine)
        open_racer_store().push(sealed(*(r for r in records if r.kind == "submission")))
        early = sync_with(theirs, url, push_records=False)
        assert (early.pulled, early.waiting) == (1, 1)  # the founding record; the submission
        assert views(theirs)["leaderboard"] == []

        rest = (r for r in records if r.kind not in {"submission", "roster"})
        open_racer_store().push(sealed(*rest))
        later = sync_with(theirs, url, push_records=False)
        assert (later.pulled, later.waiting) == (3, 0)
        assert views(theirs) == views(mine)


def test_a_stale_rename_is_refused_with_a_message_to_pull_first(url: str, tmp_path: Path) -> None:
    from league.corrections import rename_racer

    with open_league(tmp_path / "a.db") as mine, open_league(tmp_path / "b.db") as theirs:
        add_submissions(mine, tmp_path, [("bob", (11.0,))])
        sync_with(mine, url)
        sync_with(theirs, url)
        rename_racer(mine, "bob", "Bobby", by="bob")
        rename_racer(theirs, "bob", "Robert", by="host")  # without having seen "Bobby"
        assert clean(sync_with(mine, url))

        refused = sync_with(theirs, url)
        (message,) = refused.refused
        assert "'Robert' was not shared" in message and "pull first" in message
        assert views(theirs) == views(mine)  # both show "Bobby"; the refused edit is kept aside
        (kept,) = theirs.query("SELECT * FROM sync_conflicts WHERE kind = 'correction'")
        assert json.loads(kept["local_body"])["new_value"] == "Robert"

        rename_racer(theirs, "bob", "Robert", by="host")  # again, now from version 1
        assert clean(sync_with(theirs, url))
        assert clean(sync_with(mine, url))
        assert views(mine)["racers"] == views(theirs)["racers"]
        assert [r["display_name"] for r in views(mine)["racers"]] == ["Robert"]

        # A rename made offline, then a pull that brings a newer one: refused at push.
        rename_racer(mine, "bob", "B", by="bob")
        rename_racer(theirs, "bob", "Rob", by="host")
        assert clean(sync_with(theirs, url))
        assert sync_with(mine, url, push_records=False).conflicts == []
        stale = sync_with(mine, url, pull_records=False)
        assert len(stale.refused) == 1 and "'B' was not shared" in stale.refused[0]
        assert views(mine) == views(theirs)


def test_the_store_down_leaves_the_local_league_untouched(store_kind: str, tmp_path: Path) -> None:
    import socket

    from league.sync.errors import StoreUnavailable

    if store_kind == "dir":
        url = f"dir:{tmp_path / 'unplugged-drive' / 'league'}"
    else:
        with socket.socket() as probe:  # a port nobody listens on
            probe.bind(("127.0.0.1", 0))
            port = probe.getsockname()[1]
        url = f"dynamodb://league?region=us-east-1&endpoint=http://127.0.0.1:{port}"
    with open_league(tmp_path / "a.db") as league:
        host_league(league, tmp_path)
        before = list(league.conn.iterdump())
        with pytest.raises(StoreUnavailable, match=r"cannot reach|not there"):
            sync_with(league, url)
        assert list(league.conn.iterdump()) == before


def test_a_pulled_page_is_all_or_nothing(
    url: str, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Ctrl+C mid-pull: the page's rows and its cursor roll back together; pulling again
    completes it without duplicates."""
    from league.sync import incoming

    with open_league(tmp_path / "a.db") as mine, open_league(tmp_path / "b.db") as theirs:
        add_submissions(mine, tmp_path, [("ana", (11.0,)), ("bob", (11.4,))])
        sync_with(mine, url)
        real_apply = incoming.apply_page

        def interrupted(league: League, store: str, records: list[SyncRecord]) -> object:
            real_apply(league, store, records)
            raise KeyboardInterrupt

        monkeypatch.setattr(incoming, "apply_page", interrupted)
        with pytest.raises(KeyboardInterrupt):
            sync_with(theirs, url, push_records=False)
        assert theirs.query_one("SELECT count(*) FROM submissions")[0] == 0
        assert theirs.query_one("SELECT count(*) FROM sync_cursors")[0] == 0
        monkeypatch.setattr(incoming, "apply_page", real_apply)
        assert clean(sync_with(theirs, url))
        assert views(theirs) == views(mine)


def test_same_named_seasons_referred_to_by_id_are_a_conflict_not_a_swap(
    url: str, tmp_path: Path
) -> None:
    from league.nights import list_nights
    from league.seasons import new_season

    with open_league(tmp_path / "a.db") as first, open_league(tmp_path / "b.db") as second:
        new_season(first, "spring")
        host_league(second, tmp_path)  # its own "spring", with a night referring to it
        sync_with(first, url)
        found = sync_with(second, url)
        assert any("season" in line for line in found.conflicts)
        (conflict,) = second.query("SELECT * FROM sync_conflicts")
        assert "refer to it by id" in conflict["detail"]
        assert [night.name for night in list_nights(second)] == ["Friday"]


def test_a_waiting_record_is_added_once_what_it_needs_is_made_here(tmp_path: Path) -> None:
    from league.racers import add_racer
    from league.tracks import ensure_track

    url = f"dir:{tmp_path / 'shared'}"
    with open_store(url) as store:
        store.init()
    found_store(url, tmp_path)
    with open_league(tmp_path / "a.db") as mine, open_league(tmp_path / "b.db") as theirs:
        add_submissions(mine, tmp_path, [("ana", (11.0,))])
        with open_store(url) as store:
            store.push(sealed(*(r for r in all_records(mine) if r.kind == "submission")))
        assert sync_with(theirs, url).waiting == 1
        add_racer(theirs, "ana")
        with theirs.transaction():
            (track_hash, name) = mine.query("SELECT track_hash, name FROM tracks")[0]
            ensure_track(theirs, track_hash, name)
        later = sync_with(theirs, url)
        assert (later.pulled, later.waiting) == (1, 0)
        assert len(views(theirs)["leaderboard"]) == 1
