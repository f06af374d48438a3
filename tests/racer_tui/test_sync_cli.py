"""`racer-tui sync` from the command line: an organiser's init, each racer's set and sync,
status with conflicts and quarantined records, names shown literally, and one-sentence
errors with exit code 2 when the store is missing or down."""

from __future__ import annotations

import json
import os
import socket
from pathlib import Path

import pytest

from league.opening import open_league
from racer_tui.cli.main import main
from tests.league.helpers import model_folder

MARKUP_NAME = "[bold red]x"


@pytest.fixture(autouse=True)
def wide_terminal(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("COLUMNS", "200")  # rich tables wide enough that nothing wraps


def run_cli(capsys: pytest.CaptureFixture[str], *args: str) -> tuple[int, str, str]:
    code = main(list(args))
    out, err = capsys.readouterr()
    return code, out, err


def submit(
    capsys: pytest.CaptureFixture[str], tmp_path: Path, db: str, racer: str, lap: float
) -> None:
    folder = model_folder(tmp_path / f"{Path(db).stem}-{lap}", "car", laps=(lap,))
    code, _, err = run_cli(capsys, "submit", str(folder), "--racer", racer, "--db", db)
    assert code == 0, err


@pytest.fixture
def store(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> str:
    url = f"dir:{tmp_path / 'league-share'}"
    code, out, _ = run_cli(capsys, "sync", "init", url)
    assert code == 0
    assert f"racer-tui sync set {url}" in out
    return url


def test_two_racers_sync_through_a_shared_folder_and_see_names_literally(
    capsys: pytest.CaptureFixture[str], tmp_path: Path, store: str
) -> None:
    first, second = str(tmp_path / "first.db"), str(tmp_path / "second.db")
    submit(capsys, tmp_path, first, MARKUP_NAME, 11.0)
    submit(capsys, tmp_path, second, "bob", 12.0)
    for db in (first, second):
        assert run_cli(capsys, "sync", "set", store, "--db", db)[0] == 0

    code, out, _ = run_cli(capsys, "sync", "--db", first)
    assert code == 0
    # Racer, track and submission; pulled: the founding record (this machine's key is the
    # organiser's, so it proposes nothing).
    assert out.startswith(f"Synced with {store}: pushed 3, pulled 1, skipped 0, 0 conflicts")
    code, out, _ = run_cli(capsys, "sync", "--db", second, "--json")
    summary = json.loads(out)
    assert (summary["pushed"], summary["pulled"], summary["aliased"]) == (3, 4, 1)
    assert summary["notes"] == []
    assert run_cli(capsys, "sync", "--pull", "--db", first)[0] == 0

    boards = [run_cli(capsys, "leaderboard", "--db", db)[1] for db in (first, second)]
    assert boards[0] == boards[1]
    assert MARKUP_NAME in boards[1]  # pulled from the other machine, printed as typed
    _, out, _ = run_cli(capsys, "sync", "--push", "--db", second)
    assert "pushed 0" in out

    code, out, _ = run_cli(capsys, "sync", "status", "--db", second)
    assert code == 0
    assert f"Store: {store}" in out and "Conflicts: none." in out
    status = json.loads(run_cli(capsys, "sync", "status", "--db", second, "--json")[1])
    assert status["to_push"] == 0 and status["runs"]["pull"]["summary"]["pulled"] == 4


def test_status_shows_quarantined_records_literally(
    capsys: pytest.CaptureFixture[str], tmp_path: Path, store: str
) -> None:
    db = str(tmp_path / "league.db")
    folder = Path(store.removeprefix("dir:")) / "records" / "racer" / "Z"
    folder.mkdir(parents=True)
    junk = folder / "01M7YFZPX152TMAJ036HERQMZZ.json"
    junk.write_text(f'{{"name": "{MARKUP_NAME}", "oops"')
    os.utime(junk, (1_700_000_000, 1_700_000_000))
    code, out, _ = run_cli(capsys, "sync", "--store", store, "--db", db)
    assert code == 0 and "1 quarantined" in out
    assert run_cli(capsys, "sync", "set", store, "--db", db)[0] == 0
    code, out, _ = run_cli(capsys, "sync", "status", "--db", db)
    assert "Quarantined (1)" in out
    assert MARKUP_NAME in out and "01M7YFZPX152TMAJ036HERQMZZ" in out


def test_syncing_without_a_store_says_how_to_set_one(
    capsys: pytest.CaptureFixture[str], tmp_path: Path
) -> None:
    code, out, err = run_cli(capsys, "sync", "--db", str(tmp_path / "league.db"))
    assert code == 2 and out == ""
    assert err.count("\n") == 1 and "racer-tui sync set STORE" in err
    code, _, err = run_cli(
        capsys, "sync", "set", "s3://bucket/prefix", "--db", str(tmp_path / "league.db")
    )
    assert code == 2 and "--bundles" in err


def _closed_port() -> int:
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        return int(probe.getsockname()[1])


@pytest.mark.parametrize("kind", ["dir", "dynamodb"])
def test_a_store_that_is_down_is_one_sentence_and_changes_nothing(
    capsys: pytest.CaptureFixture[str],
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
    kind: str,
) -> None:
    monkeypatch.setenv("AWS_ACCESS_KEY_ID", "testing")
    monkeypatch.setenv("AWS_SECRET_ACCESS_KEY", "testing")
    monkeypatch.setenv("AWS_EC2_METADATA_DISABLED", "true")
    db = str(tmp_path / "league.db")
    submit(capsys, tmp_path, db, "ana", 11.0)
    if kind == "dir":
        url = f"dir:{tmp_path / 'usb-stick-not-plugged-in' / 'league'}"
    else:
        url = f"dynamodb://league?region=eu-west-1&endpoint=http://127.0.0.1:{_closed_port()}"
    assert run_cli(capsys, "sync", "set", url, "--db", db)[0] == 0
    with open_league(Path(db)) as league:
        before = list(league.conn.iterdump())

    code, out, err = run_cli(capsys, "sync", "--db", db)
    assert code == 2 and out == ""
    assert err.startswith("racer-tui: ") and err.count("\n") == 1
    assert ("not there" in err) if kind == "dir" else ("cannot reach" in err)
    with open_league(Path(db)) as league:
        after = list(league.conn.iterdump())
    # No record changed; only the failure is noted, and `sync status` says so.
    assert [line for line in after if "last_failure" not in line] == before
    code, out, _ = run_cli(capsys, "sync", "status", "--db", db)
    assert code == 0 and "The last sync failed at" in out


def test_the_progress_bars_take_both_directions(capsys: pytest.CaptureFixture[str]) -> None:
    from racer_tui.cli.sync_commands.running import _progress

    with _progress(True) as update:
        assert update is not None
        update("push", 0, 10)
        update("push", 10, 10)
        update("pull", 500, None)  # a pull learns its total only on its last page
        update("pull", 800, 800)
    with _progress(False) as nothing:
        assert nothing is None  # scripts and --json get no bar
    assert capsys.readouterr().out == ""  # bars go to stderr, never into piped output
