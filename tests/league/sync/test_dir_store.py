"""The shared-folder store's own duties: its layout, atomic create-only files, hostile
folder contents, a missing drive, and filesystems without hard links."""

from __future__ import annotations

import errno
import json
import os
from pathlib import Path

import pytest

from league.sync.dir_store import MARKER_NAME, DirStore
from league.sync.errors import (
    CursorInvalidError,
    StoreIncompatibleError,
    StoreNotInitialisedError,
    StoreUnavailable,
)
from league.sync.protocol import RecordStore
from league.sync.record import encode_envelope
from tests.league.sync.records import keys, profile, submission, submissions
from tests.league.sync.test_store_contract import pull_all

A_DAY_AGO = 86_400.0


def _store(tmp_path: Path, **options: object) -> DirStore:
    store = DirStore(tmp_path / "league", **options)  # type: ignore[arg-type]
    store.init()
    return store


def _age(path: Path) -> None:
    """Make a file look as if it had been there for a day (no longer being written)."""
    stat = path.stat()
    os.utime(path, (stat.st_atime - A_DAY_AGO, stat.st_mtime - A_DAY_AGO))


def test_records_are_plain_json_files_named_by_kind_and_id(tmp_path: Path) -> None:
    store = _store(tmp_path)
    record = submission(1)
    store.push([record, profile(2, 1, "Ada")])
    path = store.root / "records" / "submission" / record.record_id[-1] / f"{record.record_id}.json"
    assert path.read_bytes() == encode_envelope(record)
    profile_files = list((store.root / "records" / "racer_profile").rglob("*.json"))
    assert [file.name.split(".")[1] for file in profile_files] == ["v0000000001"]
    leftovers = [file for file in store.root.rglob(".tmp-*")]
    assert leftovers == []


def test_a_missing_folder_is_a_clear_unavailable_error(tmp_path: Path) -> None:
    store = DirStore(tmp_path / "usb-stick" / "league")
    with pytest.raises(StoreUnavailable, match=r"is not there, nor .*usb-stick: check") as error:
        store.push(submissions(1))
    assert "sync init" not in str(error.value)  # it could not set a store up there either
    with pytest.raises(StoreUnavailable, match="does not exist"):
        store.init()  # never creates a folder where a drive should be mounted
    assert not (tmp_path / "usb-stick").exists()


def test_a_folder_that_was_never_initialised_says_how_to_fix_it(tmp_path: Path) -> None:
    (tmp_path / "plain").mkdir()
    with pytest.raises(StoreNotInitialisedError, match="sync init"):
        DirStore(tmp_path / "plain").pull()


def test_a_folder_set_up_by_something_else_is_refused(tmp_path: Path) -> None:
    (tmp_path / "other").mkdir()
    (tmp_path / "other" / MARKER_NAME).write_text('{"format": "racer-tui-sync-dir", "version": 9}')
    with pytest.raises(StoreIncompatibleError, match="newer racer-tui"):
        DirStore(tmp_path / "other").push([])


def test_malformed_files_are_quarantined_and_the_rest_is_pulled(tmp_path: Path) -> None:
    store = _store(tmp_path)
    good = submissions(3)
    store.push(good)
    shard = store.root / "records" / "submission" / "0"
    shard.mkdir(parents=True, exist_ok=True)
    bad_json = shard / "01J00000000000000000000000.json"
    bad_json.write_bytes(b"{ this is not json \x1b[2J")
    tampered = submission(40, best_lap_s=0.001)
    wrong_hash = store.root / "records" / "submission" / tampered.record_id[-1]
    wrong_hash.mkdir(parents=True, exist_ok=True)
    tampered_path = wrong_hash / f"{tampered.record_id}.json"
    tampered_path.write_bytes(encode_envelope(tampered).replace(b"0.001", b"0.002"))
    misplaced = submission(41)
    misplaced_path = shard / "01J00000000000000000000010.json"
    misplaced_path.write_bytes(encode_envelope(misplaced))
    for path in (bad_json, tampered_path, misplaced_path):
        _age(path)
    (shard / ".tmp-123-abc").write_bytes(b"half a rec")  # a push in progress: ignored
    (shard / "notes.txt").write_text("ignored")

    pulled = pull_all(DirStore(store.root))

    assert keys(pulled.records) == keys(good)
    reasons = sorted(item.reason for item in pulled.quarantined)
    assert len(reasons) == 3
    assert any("not valid JSON" in reason for reason in reasons)
    assert any("does not match the body" in reason for reason in reasons)
    assert any("another record's name" in reason for reason in reasons)
    assert all("\x1b" not in item.excerpt for item in pulled.quarantined)
    # Quarantined once: the next pull does not report them again.
    assert pull_all(DirStore(store.root), pulled.cursor).quarantined == []


def test_an_unreadable_fresh_file_is_retried_not_quarantined(tmp_path: Path) -> None:
    """Without hard links a writer fills the final name in place; a reader that catches it
    half-written must wait for the next pull rather than quarantine it."""
    store = _store(tmp_path)
    record = submission(7)
    path = store.root / "records" / "submission" / record.record_id[-1] / f"{record.record_id}.json"
    path.parent.mkdir(parents=True)
    full = encode_envelope(record)
    path.write_bytes(full[: len(full) // 2])

    first = pull_all(DirStore(store.root))
    assert first.records == [] and first.quarantined == []

    path.write_bytes(full)
    assert keys(pull_all(DirStore(store.root), first.cursor).records) == keys([record])


def test_a_fresh_but_whole_record_that_was_tampered_with_is_quarantined_at_once(
    tmp_path: Path,
) -> None:
    """A whole JSON record that fails its checks is no write in flight: an edited lap
    time with the old hash is reported on the first pull, not after a minute's silence."""
    store = _store(tmp_path)
    record = submission(7)
    store.push([record])
    path = store.root / "records" / "submission" / record.record_id[-1] / f"{record.record_id}.json"
    tampered = json.loads(path.read_bytes())
    tampered["body"]["racer"] = "mallory"  # the stated hash no longer matches
    path.write_text(json.dumps(tampered))
    first = pull_all(DirStore(store.root))
    assert first.records == []
    (item,) = first.quarantined
    assert "content hash does not match" in item.reason


def test_special_files_and_symlinks_are_never_followed(tmp_path: Path) -> None:
    store = _store(tmp_path)
    shard = store.root / "records" / "racer" / "0"
    shard.mkdir(parents=True)
    secret = tmp_path / "secret.txt"
    secret.write_text("private")
    (shard / "01J00000000000000000000000.json").symlink_to(secret)
    os.mkfifo(shard / "01J00000000000000000000020.json")  # would block a naive reader

    pulled = pull_all(DirStore(store.root))

    assert pulled.records == []
    assert all("private" not in item.excerpt for item in pulled.quarantined)


def test_without_hard_links_records_are_still_created_exactly_once(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    def no_links(source: object, target: object) -> None:
        raise OSError(errno.EPERM, "Operation not permitted")  # what vfat/exFAT answer

    monkeypatch.setattr(os, "link", no_links)
    store = _store(tmp_path)
    records = submissions(10)
    assert len(store.push(records).pushed) == 10
    again = DirStore(store.root).push([*records, submission(3, best_lap_s=1.0)])
    assert len(again.skipped) == 10 and len(again.conflicts) == 1
    assert keys(pull_all(DirStore(store.root)).records) == keys(records)


def test_a_cursor_from_another_store_is_refused(tmp_path: Path) -> None:
    store: RecordStore = _store(tmp_path)
    with pytest.raises(CursorInvalidError, match="pull from the start"):
        store.pull("not-a-cursor")


def test_a_full_disk_is_one_clear_sentence_and_leaves_no_partial_files(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    store = _store(tmp_path)
    real_write = os.write

    def disk_full(fd: int, data: bytes) -> int:
        if len(data) > 100:
            raise OSError(errno.ENOSPC, "No space left on device")
        return real_write(fd, data)

    with monkeypatch.context() as patch:
        patch.setattr(os, "write", disk_full)
        with pytest.raises(StoreUnavailable, match="No space left on device"):
            store.push(submissions(3))
    assert [path for path in (store.root / "records").rglob("*") if path.is_file()] == []
    assert pull_all(DirStore(store.root)).records == []
