"""The shared-folder store (`dir:PATH`): one file per record, for network drives, synced
folders and USB sticks; no account needed.

Layout::

    PATH/racer-tui-store.json                       marker written by `sync init`
    PATH/records/<kind>/<shard>/<id>.json           an immutable record
    PATH/records/<kind>/<shard>/<id>.spare<n>.json  a spare copy of it (n = 1..8, see below)
    PATH/records/racer_profile/<shard>/<id>.v<version, 10 digits>.json
    PATH/tmp/.tmp-<host>-<boot>-<pid>-<random>     a record being written

`<shard>` is the id's last character (32 folders per kind, filled evenly), which keeps
every folder small enough for FAT32 USB sticks. Names are built only from the fixed kind
list and validated ids.

Writing is create-only and atomic: the record goes to a temporary file in `tmp/`
(fsynced), then `os.link(temp, final)` publishes it; link fails if the final name
exists, so two racers writing at once never overwrite each other, and a reader never sees
a partial file (temporary names do not match the record pattern). A push that is killed
leaves its temporary file behind; every push and pull removes, from the one `tmp/` folder,
those whose writer is gone: a process of this machine that no longer runs, or any file
older than `_DEAD_TEMP_S` by the file server's clock (a write takes milliseconds, so only
a dead writer's file gets that old, whichever machine it came from). Where the filesystem has
no hard links (FAT32/exFAT), the record is written with O_CREAT|O_EXCL to its final name
instead; readers then treat an incomplete file (not yet a whole JSON document) younger than
`pending_grace_s` as still being written and retry it on the next pull rather than
quarantining it. A whole record that fails its checks (an edited body, a recomputed hash
that does not match) is no write in flight: it is quarantined at once.

Spare copies: anyone who can write to the folder can overwrite or delete a record file,
so a record's maker checks its own records at each sync (league.sync.restore) and, when
the file under the record's name is gone or no longer its record, writes the record
again: under its own name if that is free, else as the first free spare copy. Pullers
read spares like any record file; a forged file beside a genuine spare is quarantined
(its seal fails) while the genuine copy reaches the boards.

Pull cursor: the set of record names already seen (compressed). Ids sort by *creation*
time, but a racer who was offline pushes old ids late, so a "newest id seen" watermark
would miss them; listing the folders and comparing with the seen set never does, and it
also picks up record files copied in by hand (from a USB stick, say). The cost is a
listing per pull and a cursor that grows with the store (~12 bytes per record).
"""

from __future__ import annotations

import contextlib
import errno
import os
import re
import secrets
import socket
import stat
import time
from collections import deque
from collections.abc import Callable, Iterable, Iterator, Sequence
from concurrent.futures import Future, ThreadPoolExecutor
from dataclasses import dataclass
from itertools import islice
from pathlib import Path
from typing import Final, TypeVar

import psutil

from league.sync.cursor import pack_cursor, unpack_cursor
from league.sync.errors import (
    CursorInvalidError,
    RecordInvalidError,
    StoreFolderMissingError,
    StoreIncompatibleError,
    StoreNotInitialisedError,
    StoreUnavailable,
    SyncError,
)
from league.sync.protocol import (
    DEFAULT_PAGE_SIZE,
    SPARE_SLOTS,
    Conflict,
    ContentConflict,
    ProgressCallback,
    PullPage,
    PushReport,
    RecordRef,
    VersionConflict,
    unique_records,
)
from league.sync.record import (
    KINDS,
    MAX_ENVELOPE_BYTES,
    VERSIONED_KINDS,
    Quarantined,
    SyncRecord,
    decode_envelope,
    encode_envelope,
    parse_json,
    quarantine,
)

MARKER_NAME: Final = "racer-tui-store.json"
MARKER_FORMAT: Final = "racer-tui-sync-dir"
MARKER_VERSION: Final = 1
RECORDS_DIR: Final = "records"
SHARDS: Final = "0123456789ABCDEFGHJKMNPQRSTVWXYZ"
_CURSOR_TYPE: Final = "dir"
_NAME: Final = re.compile(
    r"(?P<id>[0-9A-HJKMNP-TV-Z]{26})(?:\.v(?P<version>\d{10})|\.spare(?P<spare>[1-8]))?\.json"
)
TEMP_DIR: Final = "tmp"
_TEMP_PREFIX: Final = ".tmp-"
_STALE_TEMP_S: Final = 24 * 3600
# Older than this, a temporary file's writer is dead: writing one record takes
# milliseconds, seconds on the slowest network drive.
_DEAD_TEMP_S: Final = 600.0
_NO_LINKS: Final = frozenset(
    {
        errno.EPERM,
        errno.ENOTSUP,
        errno.EOPNOTSUPP,
        errno.ENOSYS,
        errno.EMLINK,
        errno.EACCES,
        errno.EXDEV,
    }
)
# `.tmp-<host>-<boot>-<pid>-<random>`: who wrote a temporary file, so that a machine can
# tell its own dead writers' files at once (older names, `.tmp-<pid>-<random>`, age out).
_TEMP_NAME: Final = re.compile(
    r"\.tmp-(?P<writer>[A-Za-z0-9]{1,32}-\d{1,12})-(?P<pid>\d{1,10})-[0-9a-f]+"
)
# This machine since it started, as temporary names give it: letters and digits of its
# host name, and when it booted (a process id means something only on one machine, until
# it restarts; two Raspberry Pis are both "raspberrypi", but seldom booted the same second).
_MACHINE: Final = (
    f"{re.sub(r'[^A-Za-z0-9]', '', socket.gethostname())[:32] or 'host'}-{int(psutil.boot_time())}"
)
_O_NOFOLLOW: Final = getattr(os, "O_NOFOLLOW", 0)
_O_NONBLOCK: Final = getattr(os, "O_NONBLOCK", 0)
_O_BINARY: Final = getattr(os, "O_BINARY", 0)


@dataclass(frozen=True)
class _Listed:
    """A record file found by listing: `name` is `<kind>/<file name>`, the cursor's unit."""

    name: str
    path: str  # a Path only for the files a page reads: listings are large
    sort_key: tuple[str, str, str]


_Outcome = tuple[str, RecordRef] | Conflict
In = TypeVar("In")
Out = TypeVar("Out")


class DirStore:
    """A store in a shared folder. Thread-safe for one push or pull at a time."""

    def __init__(
        self,
        root: Path,
        *,
        workers: int = 8,
        durable: bool = True,
        pending_grace_s: float = 60.0,
        use_hard_links: bool = True,
    ) -> None:
        self.root = Path(root)
        self.workers = workers
        self.durable = durable
        self.pending_grace_s = pending_grace_s
        self._use_hard_links = use_hard_links

    @property
    def description(self) -> str:
        return f"the shared folder {self.root}"

    def __enter__(self) -> DirStore:
        return self

    def __exit__(self, *exc_info: object) -> None:
        self.close()

    def close(self) -> None:
        """Nothing is held open between calls."""

    # -- set-up -------------------------------------------------------------------------

    def init(self) -> None:
        """Create the folder and its marker (the parent folder must exist); idempotent."""
        if not self.root.parent.is_dir():
            raise StoreUnavailable(
                f"cannot create {self.root}: the folder {self.root.parent} does not exist "
                "(check that the drive or synced folder is connected)"
            )
        try:
            self.root.mkdir(exist_ok=True)
        except FileExistsError:
            raise SyncError(f"{self.root} is a file, not a folder: choose a folder path") from None
        except OSError as exc:
            raise StoreUnavailable(f"cannot create the shared folder {self.root}: {exc}") from None
        marker = self.root / MARKER_NAME
        if not marker.exists():
            data = f'{{"format":"{MARKER_FORMAT}","version":{MARKER_VERSION}}}\n'.encode()
            self._publish(marker, data)
        self._check_ready()
        self._sweep_stale_temps()
        self._sweep_dead_temps()

    def _check_ready(self) -> None:
        if not self.root.is_dir():
            if self.root.parent.is_dir():
                raise StoreFolderMissingError(
                    f"the shared folder {self.root} is not there: check that the drive or "
                    "synced folder is connected, or create the store with `racer-tui sync init`"
                )
            # Not even the folder it would be made in: nothing can set a store up there.
            raise StoreUnavailable(
                f"the shared folder {self.root} is not there, nor {self.root.parent}: check "
                "that the drive or synced folder is connected and that the path is right"
            )
        marker = self.root / MARKER_NAME
        try:
            with marker.open("rb") as handle:
                raw = handle.read(4096)
        except FileNotFoundError:
            raise StoreNotInitialisedError(
                f"{self.root} is not a racer-tui store yet: run `racer-tui sync init "
                f"dir:{self.root}` first"
            ) from None
        except OSError as exc:
            raise StoreUnavailable(f"cannot read {marker}: {exc.strerror}") from None
        try:
            data = parse_json(raw)
        except RecordInvalidError:
            data = None
        if not isinstance(data, dict) or data.get("format") != MARKER_FORMAT:
            raise StoreIncompatibleError(
                f"{marker} was not written by racer-tui: choose another folder"
            )
        if data.get("version") != MARKER_VERSION:
            raise StoreIncompatibleError(
                f"{self.root} was set up by a newer racer-tui: update racer-tui to sync with it"
            )

    def _sweep_stale_temps(self) -> None:
        """Remove temporary files left by pushes killed more than a day ago."""
        cutoff = time.time() - _STALE_TEMP_S
        for folder in self._shard_dirs():
            for entry in _scan(folder):
                if entry.name.startswith(_TEMP_PREFIX):
                    with contextlib.suppress(OSError):
                        if entry.stat(follow_symlinks=False).st_mtime < cutoff:
                            os.unlink(entry.path)

    def _sweep_dead_temps(self) -> None:
        """Remove the temporary files in `tmp/` whose writer is gone (a push that was
        killed): a process of this machine that no longer runs, or, from any machine, a
        file older than _DEAD_TEMP_S by the file server's clock. A live writer's file is
        never touched, wherever it runs."""
        entries = [e for e in _scan(self.root / TEMP_DIR) if e.name.startswith(_TEMP_PREFIX)]
        undecided: list[os.DirEntry[str]] = []
        for entry in entries:
            match = _TEMP_NAME.fullmatch(entry.name)
            if match and match["writer"] == _MACHINE and not psutil.pid_exists(int(match["pid"])):
                with contextlib.suppress(OSError):
                    os.unlink(entry.path)
            else:
                undecided.append(entry)
        if not undecided:
            return
        cutoff = self._server_now() - _DEAD_TEMP_S
        for entry in undecided:
            with contextlib.suppress(OSError):
                if entry.stat(follow_symlinks=False).st_mtime < cutoff:
                    os.unlink(entry.path)

    def _server_now(self) -> float:
        """The time by the clock that stamps the folder's files (a network drive's server,
        which a machine's own clock may be minutes away from): a new file's mtime."""
        probe = self._temp_path()
        self._write_new(probe, b"", durable=False)
        try:
            return probe.stat().st_mtime
        finally:
            with contextlib.suppress(OSError):
                os.unlink(probe)

    def _temp_path(self) -> Path:
        folder = self.root / TEMP_DIR
        folder.mkdir(exist_ok=True)
        return folder / f"{_TEMP_PREFIX}{_MACHINE}-{os.getpid()}-{secrets.token_hex(8)}"

    # -- push ---------------------------------------------------------------------------

    def push(
        self, records: Iterable[SyncRecord], progress: ProgressCallback | None = None
    ) -> PushReport:
        self._check_ready()
        with self._folder_errors("write to"):
            self._sweep_dead_temps()
            return self._push(records, progress)

    def _push(self, records: Iterable[SyncRecord], progress: ProgressCallback | None) -> PushReport:
        unique, repeats, conflicts = unique_records(records)
        pushed: list[RecordRef] = []
        skipped: list[RecordRef] = list(repeats)
        found: list[Conflict] = list(conflicts)
        for done, outcome in enumerate(self._run_parallel(self._push_one, unique), start=1):
            if isinstance(outcome, ContentConflict | VersionConflict):
                found.append(outcome)
            elif outcome[0] == "pushed":
                pushed.append(outcome[1])
            else:
                skipped.append(outcome[1])
            if progress is not None:
                progress(done, len(unique))
        if self.durable and pushed:
            for folder in {
                self._path_for(ref.kind, ref.record_id, ref.version).parent for ref in pushed
            }:
                _fsync_dir(folder)
        return PushReport(tuple(pushed), tuple(skipped), tuple(found))

    def _push_one(self, record: SyncRecord) -> _Outcome:
        ref = RecordRef.of(record)
        final = self._path_for(record.kind, record.record_id, record.version)
        if record.kind in VERSIONED_KINDS:
            stale = self._stale_version(record, final)
            if stale is not None:
                return stale
        elif final.exists():  # a re-push: compare without writing anything
            return self._compare_existing(record, final)
        if self._publish(final, encode_envelope(record)):
            return ("pushed", ref)
        return self._compare_existing(record, final)

    def _stale_version(self, record: SyncRecord, final: Path) -> _Outcome | None:
        """Why a versioned record may not be written now, or None if it may."""
        if final.exists():
            return self._compare_existing(record, final)
        versions = self._versions_of(record.kind, record.record_id)
        if not versions or max(versions) == record.version - 1:
            return None
        latest = max(versions)
        held = self._read(self._path_for(record.kind, record.record_id, latest))
        remote_hash = held.content_hash if isinstance(held, SyncRecord) else None
        return VersionConflict(
            record.kind, record.record_id, record.version, latest, record.content_hash, remote_hash
        )

    def _compare_existing(self, record: SyncRecord, final: Path) -> _Outcome:
        held = self._read_settled(final)
        if isinstance(held, SyncRecord) and held.content_hash == record.content_hash:
            return ("skipped", RecordRef.of(record))
        remote_hash = held.content_hash if isinstance(held, SyncRecord) else None
        if record.kind in VERSIONED_KINDS:
            return VersionConflict(
                record.kind,
                record.record_id,
                record.version,
                record.version,
                record.content_hash,
                remote_hash,
            )
        return ContentConflict(record.kind, record.record_id, record.content_hash, remote_hash)

    def _read_settled(self, path: Path) -> SyncRecord | Quarantined | None:
        """Read a record another writer may still be writing (only without hard links)."""
        held = self._read(path)
        for delay in (0.01, 0.05, 0.2):
            if isinstance(held, SyncRecord):
                break
            time.sleep(delay)  # a non-link writer finishes within milliseconds
            held = self._read(path)
        return held

    def _publish(self, final: Path, data: bytes) -> bool:
        """Create `final` holding `data` atomically; False if it already exists."""
        final.parent.mkdir(parents=True, exist_ok=True)
        if self._use_hard_links:
            temp = self._temp_path()
            self._write_new(temp, data)
            try:
                os.link(temp, final)
                return True
            except FileExistsError:
                return False
            except OSError as exc:
                if exc.errno not in _NO_LINKS:
                    raise
                self._use_hard_links = False  # e.g. FAT32/exFAT: fall back below
            finally:
                with contextlib.suppress(OSError):
                    os.unlink(temp)
        try:
            self._write_new(final, data)
        except FileExistsError:
            return False
        return True

    def _write_new(self, path: Path, data: bytes, *, durable: bool = True) -> None:
        """Write a new file (fails if it exists); removes it again if writing fails."""
        fd = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_EXCL | _O_BINARY, 0o644)
        try:
            try:
                view = memoryview(data)
                while view:
                    view = view[os.write(fd, view) :]
                if self.durable and durable:
                    os.fsync(fd)
            finally:
                os.close(fd)
        except BaseException:
            with contextlib.suppress(OSError):
                os.unlink(path)
            raise

    # -- spare copies (league.sync.restore) ----------------------------------------------

    def held_copies(
        self, keys: Sequence[tuple[str, str]], *, spares: bool = False
    ) -> dict[tuple[str, str], list[SyncRecord]]:
        """The whole records the folder holds under each (kind, id): the file under the
        record's own name, and with `spares` its spare copies too. A file that is not a
        whole record of that kind and id is no copy of it (it is left to the pull to
        quarantine)."""
        self._check_ready()
        wanted = [
            (key, self._path_for(key[0], key[1], 0, spare))
            for key in keys
            if key[0] not in VERSIONED_KINDS
            for spare in (range(SPARE_SLOTS + 1) if spares else (0,))
        ]
        copies: dict[tuple[str, str], list[SyncRecord]] = {key: [] for key in keys}
        with self._folder_errors("read"):
            found = list(self._run_parallel(self._read, [path for _, path in wanted]))
        for (key, _), held in zip(wanted, found, strict=True):
            if isinstance(held, SyncRecord) and held.key == key:
                copies[key].append(held)
        return copies

    def write_spare(self, record: SyncRecord) -> str | None:
        """Write `record` again: under its own name if that is free (its file was deleted),
        else as the first free spare copy. Where it went, or None when every name is
        taken."""
        self._check_ready()
        if record.kind in VERSIONED_KINDS:
            return None
        data = encode_envelope(record)
        with self._folder_errors("write to"):
            for spare in range(SPARE_SLOTS + 1):
                path = self._path_for(record.kind, record.record_id, 0, spare)
                if self._publish(path, data):
                    if self.durable:
                        _fsync_dir(path.parent)
                    return str(path.relative_to(self.root))
        return None

    # -- pull ---------------------------------------------------------------------------

    def pull(self, cursor: str | None = None, limit: int = DEFAULT_PAGE_SIZE) -> PullPage:
        self._check_ready()
        with self._folder_errors("read"):
            with contextlib.suppress(OSError):  # a read-only share can still be pulled
                self._sweep_dead_temps()
            return self._pull(cursor, limit)

    def _pull(self, cursor: str | None, limit: int) -> PullPage:
        seen, deferred = _load_cursor(cursor)
        candidates = [
            listed
            for listed in self._list_records()
            if listed.name not in seen and listed.name not in deferred
        ]
        page = candidates[: max(1, limit)]
        records: list[SyncRecord] = []
        quarantined: list[Quarantined] = []
        now = time.time()
        for listed, (outcome, mtime) in zip(
            page, self._run_parallel(self._read_with_mtime, page), strict=True
        ):
            if outcome is None:
                continue  # removed since the listing; nothing to pull
            if (
                isinstance(outcome, Quarantined)
                and outcome.partial
                and now - mtime < self.pending_grace_s
            ):
                deferred.add(listed.name)  # probably still being written (no hard links)
                continue
            checked = _check_name(outcome, listed) if isinstance(outcome, SyncRecord) else outcome
            if isinstance(checked, SyncRecord):
                records.append(checked)
            else:
                quarantined.append(checked)
            seen.add(listed.name)
        more = len(candidates) > len(page)
        if not more:
            deferred = set()  # the next pull tries files that were still being written
        state = {"seen": sorted(seen), "deferred": sorted(deferred)}
        return PullPage(tuple(records), tuple(quarantined), pack_cursor(_CURSOR_TYPE, state), more)

    def _list_records(self) -> list[_Listed]:
        listed: list[_Listed] = []
        temps: list[os.DirEntry[str]] = []
        for kind in KINDS:
            kind_dir = self.root / RECORDS_DIR / kind
            for shard in SHARDS:
                for entry in _scan(kind_dir / shard):
                    match = _NAME.fullmatch(entry.name)
                    if match is None or not entry.is_file(follow_symlinks=False):
                        if entry.name.startswith(_TEMP_PREFIX):
                            temps.append(entry)
                        continue  # temporary files, conflicted copies, anything foreign
                    order = match["version"] or (f"spare{match['spare']}" if match["spare"] else "")
                    listed.append(
                        _Listed(f"{kind}/{entry.name}", entry.path, (match["id"], kind, order))
                    )
        listed.sort(key=lambda item: item.sort_key)  # creation order, for a readable pull
        _remove_dead_legacy_temps(temps)
        return listed

    def _read_with_mtime(self, listed: _Listed) -> tuple[SyncRecord | Quarantined | None, float]:
        return self._read_file(Path(listed.path))

    def _read(self, path: Path) -> SyncRecord | Quarantined | None:
        return self._read_file(path)[0]

    def _read_file(self, path: Path) -> tuple[SyncRecord | Quarantined | None, float]:
        """Decode one record file; never follows symlinks or blocks on a device or FIFO."""
        where = str(path.relative_to(self.root)) if path.is_relative_to(self.root) else path.name
        try:
            fd = os.open(path, os.O_RDONLY | _O_NOFOLLOW | _O_NONBLOCK | _O_BINARY)
        except FileNotFoundError:
            return None, 0.0
        except OSError as exc:
            return quarantine(f"it cannot be opened ({exc.strerror})", where, b""), 0.0
        try:
            info = os.fstat(fd)
            if not stat.S_ISREG(info.st_mode):
                return quarantine("it is not a regular file", where, b""), info.st_mtime
            chunks: list[bytes] = []
            remaining = MAX_ENVELOPE_BYTES + 1
            while remaining > 0:
                chunk = os.read(fd, min(remaining, 1 << 20))
                if not chunk:
                    break
                chunks.append(chunk)
                remaining -= len(chunk)
        except OSError as exc:
            return quarantine(f"it cannot be read ({exc.strerror})", where, b""), 0.0
        finally:
            os.close(fd)
        return decode_envelope(b"".join(chunks), where), info.st_mtime

    # -- helpers ------------------------------------------------------------------------

    @contextlib.contextmanager
    def _folder_errors(self, action: str) -> Iterator[None]:
        """A full disk, a read-only share or a dropped network drive: one sentence."""
        try:
            yield
        except OSError as exc:
            raise StoreUnavailable(
                f"cannot {action} the shared folder {self.root} ({exc.strerror or exc}): "
                "check that it is connected, writable and not full, then sync again"
            ) from None

    def _path_for(self, kind: str, record_id: str, version: int, spare: int = 0) -> Path:
        # kind and record_id come from a validated SyncRecord: never a foreign string.
        if kind in VERSIONED_KINDS:
            name = f"{record_id}.v{version:010d}.json"
        else:
            name = f"{record_id}{f'.spare{spare}' if spare else ''}.json"
        return self.root / RECORDS_DIR / kind / record_id[-1] / name

    def _versions_of(self, kind: str, record_id: str) -> list[int]:
        folder = self.root / RECORDS_DIR / kind / record_id[-1]
        versions = []
        for entry in _scan(folder):
            match = _NAME.fullmatch(entry.name)
            if match and match["id"] == record_id and match["version"]:
                versions.append(int(match["version"]))
        return versions

    def _shard_dirs(self) -> Iterator[Path]:
        for kind in KINDS:
            for shard in SHARDS:
                yield self.root / RECORDS_DIR / kind / shard

    def _run_parallel(self, work: Callable[[In], Out], items: list[In]) -> Iterator[Out]:
        """Run `work` over `items` on a thread pool (file I/O waits, especially on network
        drives), yielding results in order. At most two items per thread are handed out
        ahead of the results taken: with all of them handed out at once, a starved caller
        found a push of 40 records wholly written by the time its Ctrl+C came at the tenth.
        On Ctrl+C, queued work is cancelled and only records already being written finish,
        each one whole."""
        if len(items) <= 1 or self.workers <= 1:
            yield from (work(item) for item in items)
            return
        pool = ThreadPoolExecutor(max_workers=self.workers, thread_name_prefix="dir-store")
        waiting = iter(items)
        try:
            ahead: deque[Future[Out]] = deque(
                pool.submit(work, item) for item in islice(waiting, 2 * self.workers)
            )
            while ahead:
                result = ahead.popleft().result()
                ahead.extend(pool.submit(work, item) for item in islice(waiting, 1))
                yield result
        finally:
            pool.shutdown(wait=True, cancel_futures=True)


def _check_name(record: SyncRecord, listed: _Listed) -> SyncRecord | Quarantined:
    """A record must sit under its own name (or one of its spare copies' names), or
    create-only per id would mean nothing."""
    kind, _, file_name = listed.name.partition("/")
    match = _NAME.fullmatch(file_name)
    spare = match["spare"] if match else None
    if record.kind in VERSIONED_KINDS:
        expected = f"{record.record_id}.v{record.version:010d}.json"
    else:
        expected = f"{record.record_id}{f'.spare{spare}' if spare else ''}.json"
    if (
        record.kind != kind
        or file_name != expected
        or Path(listed.path).parent.name != record.record_id[-1]
    ):
        return quarantine(
            f"it holds {record.kind} {record.record_id} under another record's name",
            listed.name,
            file_name,
        )
    return record


def _remove_dead_legacy_temps(temps: list[os.DirEntry[str]]) -> None:
    """Temporary files that racer-tui before `tmp/` left beside the records (a killed push):
    gone once old enough that no writer can still hold them."""
    cutoff = time.time() - _DEAD_TEMP_S
    for entry in temps:
        with contextlib.suppress(OSError):
            if entry.stat(follow_symlinks=False).st_mtime < cutoff:
                os.unlink(entry.path)


def _load_cursor(cursor: str | None) -> tuple[set[str], set[str]]:
    if cursor is None:
        return set(), set()
    state = unpack_cursor(_CURSOR_TYPE, cursor)
    seen, deferred = state.get("seen"), state.get("deferred")
    if not isinstance(seen, list) or not isinstance(deferred, list):
        raise CursorInvalidError(
            "the saved sync position is damaged: pull from the start to rebuild it"
        )
    return {str(name) for name in seen}, {str(name) for name in deferred}


def _scan(folder: Path) -> list[os.DirEntry[str]]:
    try:
        with os.scandir(folder) as entries:
            return list(entries)
    except (FileNotFoundError, NotADirectoryError):
        return []


def _fsync_dir(folder: Path) -> None:
    """Make new names durable (POSIX); Windows cannot open a folder for fsync."""
    if os.name != "posix":
        return
    try:
        fd = os.open(folder, os.O_RDONLY)
    except OSError:
        return
    try:
        with contextlib.suppress(OSError):
            os.fsync(fd)
    finally:
        os.close(fd)
