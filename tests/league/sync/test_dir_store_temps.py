"""A push that is killed leaves its temporary file in the shared folder; the next push or
pull removes it once its writer is gone, and never touches a live writer's, from this
machine or another."""

from __future__ import annotations

import errno
import os
import subprocess
import sys
from pathlib import Path

import pytest

from league.sync.dir_store import _MACHINE, TEMP_DIR, DirStore
from tests.league.sync.records import submission, submissions

TEN_MINUTES = 600.0


def _store(tmp_path: Path) -> DirStore:
    store = DirStore(tmp_path / "league")
    store.init()
    return store


def _older(path: Path, seconds: float) -> None:
    stat = path.stat()
    os.utime(path, (stat.st_atime - seconds, stat.st_mtime - seconds))


def _temp(store: DirStore, name: str, *, age: float = 0.0) -> Path:
    """A temporary file as a writer leaves it when it is killed between write and link."""
    folder = store.root / TEMP_DIR
    folder.mkdir(exist_ok=True)
    path = folder / name
    path.write_bytes(b'{"format": 2, "kind": "submiss')
    if age:
        _older(path, age)
    return path


def _dead_pid() -> int:
    """The id of a process that has ended (a killed push's)."""
    child = subprocess.run(
        [sys.executable, "-c", "import os; print(os.getpid())"],
        capture_output=True,
        text=True,
        check=True,
    )
    return int(child.stdout)


def _temps(store: DirStore) -> set[str]:
    return {path.name for path in store.root.rglob(".tmp-*")}


def test_a_killed_writers_temporary_file_is_gone_after_the_next_push(tmp_path: Path) -> None:
    store = _store(tmp_path)
    other_machine = _temp(
        store, ".tmp-laptop2-1764300000-4242-0a1b2c3d4e5f6071", age=TEN_MINUTES + 60
    )
    this_machine = _temp(store, f".tmp-{_MACHINE}-{_dead_pid()}-1a2b3c4d5e6f7081")

    report = store.push(submissions(2))

    assert len(report.pushed) == 2
    assert not other_machine.exists()
    assert not this_machine.exists()  # its process has ended: gone at once, young as it is
    assert _temps(store) == set()


def test_a_live_writers_temporary_file_is_kept(tmp_path: Path) -> None:
    store = _store(tmp_path)
    # Another machine writing right now, and a writer of this machine that is alive.
    other_machine = _temp(store, ".tmp-laptop2-1764300000-4242-0a1b2c3d4e5f6071", age=5.0)
    this_machine = _temp(store, f".tmp-{_MACHINE}-{os.getpid()}-1a2b3c4d5e6f7081")
    # A machine with this one's host name (two Raspberry Pis are both "raspberrypi"), booted
    # at another time: its process ids mean nothing here.
    host = _MACHINE.rpartition("-")[0]
    namesake = _temp(store, f".tmp-{host}-1234567-{_dead_pid()}-2a2b3c4d5e6f7081")

    store.push([submission(1)])
    store.pull()

    assert other_machine.exists() and this_machine.exists() and namesake.exists()


def test_a_pull_removes_dead_temporary_files_too(tmp_path: Path) -> None:
    store = _store(tmp_path)
    store.push([submission(1)])
    dead = _temp(store, ".tmp-laptop2-1764300000-4242-0a1b2c3d4e5f6071", age=TEN_MINUTES + 60)
    # Left beside the records by a racer-tui from before tmp/ (a push killed then).
    shard = next((store.root / "records" / "submission").iterdir())
    legacy = shard / ".tmp-4242-0a1b2c3d4e5f6071"
    legacy.write_bytes(b"half a record")
    _older(legacy, TEN_MINUTES + 60)

    DirStore(store.root).pull()

    assert not dead.exists() and not legacy.exists()


def test_a_read_only_share_is_still_pulled(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    store = _store(tmp_path)
    store.push(submissions(3))
    _temp(
        store, ".tmp-laptop2-1764300000-4242-0a1b2c3d4e5f6071", age=5.0
    )  # needs the server's clock

    def read_only(self: DirStore, path: Path, data: bytes, *, durable: bool = True) -> None:
        raise OSError(errno.EROFS, "Read-only file system")

    monkeypatch.setattr(DirStore, "_write_new", read_only)
    page = DirStore(store.root).pull()

    assert len(page.records) == 3
