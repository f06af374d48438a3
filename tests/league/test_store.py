"""The league database: opened the same way everywhere, migrated at open, refused when it
is newer or not a league, and every change all-or-nothing."""

from __future__ import annotations

import sqlite3
from pathlib import Path

import pytest

from league.errors import LeagueError
from league.leaderboard import Filters, leaderboard
from league.migrations import MIGRATIONS, SCHEMA_VERSION
from league.opening import open_league
from league.store import League, default_db_path
from sim.foundation.ids import content_hash, new_id
from sim.tracks.catalog import resolve_track
from tests.league.helpers import TRACK


def test_a_new_league_is_at_the_latest_version_with_wal_and_foreign_keys(
    league: League, league_path: Path
) -> None:
    assert league.query_one("PRAGMA user_version")[0] == SCHEMA_VERSION
    assert league.query_one("PRAGMA journal_mode")[0] == "wal"
    assert league.query_one("PRAGMA foreign_keys")[0] == 1
    with pytest.raises(sqlite3.IntegrityError):  # an entrant of a night that does not exist
        league.conn.execute(
            "INSERT INTO night_entrants VALUES ('X', 'no-night', 'nobody', 'm', 't', 'h')"
        )


def test_the_default_database_lives_in_the_data_home(racer_home: Path) -> None:
    assert default_db_path() == racer_home / "league.db"
    with open_league() as opened:
        assert opened.path == racer_home / "league.db"
    assert (racer_home / "league.db").is_file()


def _v1_database(path: Path) -> None:
    """A league as racer-tui's first schema left it: shared rows only, no cache."""
    conn = sqlite3.connect(path)
    MIGRATIONS[0].apply(conn)
    track = resolve_track(TRACK)
    conn.execute(
        "INSERT INTO racers VALUES (?, 'ana', 'Ana', '#e6194b', '2024-01-01T00:00:00.000Z', ?)",
        (new_id(), content_hash({"name": "ana"})),
    )
    conn.execute(
        "INSERT INTO tracks VALUES (?, ?, ?, '2024-01-01T00:00:00.000Z', 'h')",
        (new_id(), track.content_hash, track.name),
    )
    submission = new_id()
    conn.execute(
        "INSERT INTO submissions (id, racer, track_hash, model_name, model_hash, source, "
        "evaluation_file, fingerprint, submitted_at, content_hash) "
        "VALUES (?, 'ana', ?, 'old-car', 'mh', 'racer-tui', 'evaluation-1.json', 'fp', "
        "'2024-01-02T00:00:00.000Z', 'ch')",
        (submission, track.content_hash),
    )
    for number, seconds in enumerate((14.0, 13.25, 13.5), start=1):
        conn.execute(
            "INSERT INTO submission_laps VALUES (?, ?, ?, 100, 'Lap complete', 0, 0, 1)",
            (submission, number, seconds),
        )
    conn.execute("PRAGMA user_version = 1")
    conn.commit()
    conn.close()


def test_an_old_version_database_is_upgraded_and_its_rows_rank(league_path: Path) -> None:
    _v1_database(league_path)
    with open_league(league_path) as upgraded:
        assert upgraded.query_one("PRAGMA user_version")[0] == SCHEMA_VERSION
        rows = leaderboard(upgraded, Filters())
    assert [(row.display_name, row.model, row.best_lap, row.valid_laps) for row in rows] == [
        ("Ana", "old-car", 13.25, 3)
    ]


def test_a_newer_database_is_refused_and_left_untouched(league_path: Path) -> None:
    conn = sqlite3.connect(league_path)
    conn.execute("CREATE TABLE future (x)")
    conn.execute(f"PRAGMA user_version = {SCHEMA_VERSION + 1}")
    conn.commit()
    conn.close()
    before = league_path.read_bytes()
    with pytest.raises(LeagueError, match="newer") as error:
        open_league(league_path)
    assert "upgrade racer-tui" in str(error.value)
    assert league_path.read_bytes() == before
    assert not league_path.with_name("league.db-wal").exists()


def test_a_database_that_is_not_a_league_is_refused(tmp_path: Path) -> None:
    other = tmp_path / "other.db"
    conn = sqlite3.connect(other)
    conn.execute("CREATE TABLE notes (text)")
    conn.commit()
    conn.close()
    with pytest.raises(LeagueError, match="not a racer-tui league"):
        open_league(other)
    garbage = tmp_path / "garbage.db"
    garbage.write_bytes(b"this is not sqlite at all, just some bytes" * 100)
    with pytest.raises(LeagueError, match="not a usable league database"):
        open_league(garbage)


def test_a_db_path_in_a_missing_folder_is_a_clear_error(tmp_path: Path) -> None:
    with pytest.raises(LeagueError, match="does not exist"):
        open_league(tmp_path / "nowhere" / "league.db")


def test_a_failed_transaction_leaves_nothing(league: League) -> None:
    with pytest.raises(RuntimeError), league.transaction():
        league.insert_record(
            "racers",
            {"name": "ana", "display_name": "ana", "colour": "#000000", "created_at": "t"},
        )
        raise RuntimeError("interrupted")
    assert league.query("SELECT * FROM racers") == []


def test_shared_rows_carry_an_id_and_the_hash_of_their_content(league: League) -> None:
    with league.transaction():
        row_id = league.insert_record(
            "racers",
            {"name": "ana", "display_name": "ana", "colour": "#000000", "created_at": "t"},
        )
    row = league.query_one("SELECT * FROM racers WHERE id = ?", (row_id,))
    assert len(row_id) == 26
    assert row["content_hash"] == content_hash(
        {"name": "ana", "display_name": "ana", "colour": "#000000", "created_at": "t"}
    )


def _open_together(path: Path, openers: int) -> list[BaseException]:
    """Open `path` from `openers` threads released at once; what each raised."""
    import threading

    failures: list[BaseException] = []
    start = threading.Barrier(openers)

    def opener() -> None:
        start.wait()
        try:
            open_league(path).close()
        except BaseException as error:  # collected for the test's assertion
            failures.append(error)

    threads = [threading.Thread(target=opener) for _ in range(openers)]
    for thread in threads:
        thread.start()
    for thread in threads:
        thread.join()
    return failures


def test_racer_tuis_creating_one_league_together_all_open_it(tmp_path: Path) -> None:
    """The app's first start opens a new league from several workers at once: while one
    creates it, another must never take the fresh tables for a database that is not a
    league."""
    for attempt in range(40):
        assert _open_together(tmp_path / f"new-{attempt}.db", 6) == [], attempt
