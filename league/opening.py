"""Opening the league database: the one way every command connects to it.

`open_league()` connects, refuses a database written by a newer racer-tui (before
touching it: not even the journal mode changes), turns on WAL and foreign keys, and runs
the pending migrations; when one of them changed what the leaderboard cache holds, it
rebuilds the cache in the same transaction. It lives above league.store (the League it
returns), league.migrations and league.entries (the cache), which know nothing of it.
"""

from __future__ import annotations

import sqlite3
import time
from pathlib import Path

from league.entries import rebuild_entries
from league.errors import LeagueError
from league.migrations import check_version, migrate
from league.store import League, default_db_path

BUSY_TIMEOUT_MS = 10_000


def _use_wal(conn: sqlite3.Connection) -> None:
    """Put the database in WAL mode, waiting for any other racer-tui switching it too.

    SQLite answers a journal-mode change that meets another connection's lock with "database
    is locked" at once, without its busy handler: several workers opening a new league
    together would otherwise refuse it.
    """
    deadline = time.monotonic() + BUSY_TIMEOUT_MS / 1000
    while True:
        try:
            conn.execute("PRAGMA journal_mode = WAL")
            return
        except sqlite3.OperationalError as error:
            if "locked" not in str(error) or time.monotonic() > deadline:
                raise
            time.sleep(0.01)


def open_league(db_path: Path | None = None) -> League:
    """Open (creating and migrating as needed) the league database at `db_path`.

    The default is `default_db_path()`: league.db in the data folder, or RACER_TUI_LEAGUE.
    Raises LeagueError for a file that is not a league database or was written by a newer
    racer-tui; such files are left untouched.
    """
    path = Path(db_path) if db_path is not None else default_db_path()
    if not path.parent.is_dir():
        raise LeagueError(
            f"cannot create league database {path}: folder {path.parent} does not exist; "
            "create it or choose another --db path."
        )
    if path.is_dir():
        raise LeagueError(f"{path} is a folder, not a league database file; give a file path.")
    try:
        conn = sqlite3.connect(path, isolation_level=None, timeout=BUSY_TIMEOUT_MS / 1000)
    except sqlite3.Error as error:
        raise LeagueError(f"cannot open league database {path}: {error}.") from None
    conn.row_factory = sqlite3.Row
    try:
        check_version(conn, path)  # before any statement that could write
        conn.execute(f"PRAGMA busy_timeout = {BUSY_TIMEOUT_MS}")
        _use_wal(conn)
        conn.execute("PRAGMA synchronous = NORMAL")
        conn.execute("PRAGMA foreign_keys = ON")
        # The cache is rebuilt here, not by the migrations: it is made by modules that
        # stand on the store, so migrations (below them) only say when it is due.
        migrate(conn, rebuild_cache=rebuild_entries)
    except sqlite3.DatabaseError as error:
        conn.close()
        raise LeagueError(
            f"{path} is not a usable league database ({error}); choose another --db file."
        ) from None
    except BaseException:
        conn.close()
        raise
    return League(path, conn)


FileStamp = tuple[int, int] | None  # a file's modification time and size; None: no file


def league_stamp(db_path: Path | None = None) -> tuple[FileStamp, FileStamp]:
    """The database and its write-ahead log as the file system last saw them: a screen that
    shows the league compares stamps to notice, without a query, that another process (the
    command line, a sync) wrote to it. In WAL mode every commit touches the log, and a
    checkpoint that empties it touches the database."""
    path = Path(db_path) if db_path is not None else default_db_path()
    return _file_stamp(path), _file_stamp(path.with_name(path.name + "-wal"))


def _file_stamp(path: Path) -> FileStamp:
    try:
        status = path.stat()
    except OSError:
        return None
    return status.st_mtime_ns, status.st_size
