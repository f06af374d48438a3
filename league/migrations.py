"""Ordered schema migrations, numbered by `PRAGMA user_version`.

Migration N (1-based) takes a version N-1 database to version N. All pending migrations
run at open in one transaction: a crash half-way leaves the old version intact. A
database whose version is newer than this code knows is refused, never modified.

Append new migrations to MIGRATIONS; never edit one that has shipped. A migration that
changes what the local leaderboard cache holds sets `rebuilds_cache`: the cache is then
rebuilt once, from the shared rows, after the last migration and in the same transaction,
by the function the opener passes (league.opening: the cache is built by modules that
stand on this one's schema, so this module does not import them).
"""

from __future__ import annotations

import sqlite3
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

from league.errors import LeagueError


@dataclass(frozen=True)
class Migration:
    description: str
    apply: Callable[[sqlite3.Connection], None]
    rebuilds_cache: bool = False


def _script(sql: str) -> Callable[[sqlite3.Connection], None]:
    def apply(conn: sqlite3.Connection) -> None:
        for statement in sql.split(";"):
            if statement.strip():
                conn.execute(statement)

    return apply


# Version 1: the shared rows. Racers and tracks are referenced by their natural keys (the
# racer's name, the track's content hash) so records from two machines join without
# remapping ids. Laps belong to their submission or race: they carry no id of their own
# and are part of the parent's content hash.
SHARED_TABLES = """
CREATE TABLE racers (
    id TEXT PRIMARY KEY,
    name TEXT NOT NULL UNIQUE COLLATE NOCASE,
    display_name TEXT NOT NULL,
    colour TEXT NOT NULL,
    created_at TEXT NOT NULL,
    content_hash TEXT NOT NULL
);
CREATE TABLE tracks (
    id TEXT PRIMARY KEY,
    track_hash TEXT NOT NULL UNIQUE,
    name TEXT NOT NULL,
    created_at TEXT NOT NULL,
    content_hash TEXT NOT NULL
);
CREATE TABLE seasons (
    id TEXT PRIMARY KEY,
    name TEXT NOT NULL UNIQUE COLLATE NOCASE,
    points TEXT NOT NULL,
    created_at TEXT NOT NULL,
    content_hash TEXT NOT NULL
);
CREATE TABLE nights (
    id TEXT PRIMARY KEY,
    name TEXT NOT NULL,
    track_hash TEXT NOT NULL REFERENCES tracks(track_hash),
    season_id TEXT REFERENCES seasons(id),
    rules TEXT NOT NULL,
    created_at TEXT NOT NULL,
    content_hash TEXT NOT NULL
);
CREATE INDEX nights_season ON nights(season_id);
CREATE TABLE night_entrants (
    id TEXT PRIMARY KEY,
    night_id TEXT NOT NULL REFERENCES nights(id),
    racer TEXT NOT NULL REFERENCES racers(name),
    model TEXT NOT NULL,
    created_at TEXT NOT NULL,
    content_hash TEXT NOT NULL
);
CREATE INDEX night_entrants_night ON night_entrants(night_id);
CREATE TABLE heats (
    id TEXT PRIMARY KEY,
    night_id TEXT NOT NULL REFERENCES nights(id),
    draw_id TEXT NOT NULL,
    draw_seed INTEGER NOT NULL,
    position INTEGER NOT NULL,
    entrant_id TEXT NOT NULL REFERENCES night_entrants(id),
    created_at TEXT NOT NULL,
    content_hash TEXT NOT NULL
);
CREATE INDEX heats_night ON heats(night_id, draw_id);
CREATE TABLE night_closures (
    id TEXT PRIMARY KEY,
    night_id TEXT NOT NULL UNIQUE REFERENCES nights(id),
    closed_by TEXT NOT NULL,
    created_at TEXT NOT NULL,
    content_hash TEXT NOT NULL
);
CREATE TABLE submissions (
    id TEXT PRIMARY KEY,
    racer TEXT NOT NULL REFERENCES racers(name),
    track_hash TEXT NOT NULL REFERENCES tracks(track_hash),
    model_name TEXT NOT NULL,
    model_hash TEXT NOT NULL,
    source TEXT NOT NULL,
    action_space TEXT,
    sensors TEXT,
    neural_network TEXT,
    training_algorithm TEXT,
    hyperparameters TEXT,
    training TEXT,
    evaluation_file TEXT NOT NULL,
    fingerprint TEXT NOT NULL,
    submitted_at TEXT NOT NULL,
    content_hash TEXT NOT NULL
);
CREATE INDEX submissions_racer ON submissions(racer);
CREATE TABLE submission_laps (
    submission_id TEXT NOT NULL REFERENCES submissions(id),
    number INTEGER NOT NULL,
    time_seconds REAL NOT NULL,
    completion REAL NOT NULL,
    status TEXT NOT NULL,
    offtracks INTEGER NOT NULL,
    crashes INTEGER NOT NULL,
    completed INTEGER NOT NULL,
    PRIMARY KEY (submission_id, number)
) WITHOUT ROWID;
CREATE TABLE races (
    id TEXT PRIMARY KEY,
    racer TEXT NOT NULL REFERENCES racers(name),
    track_hash TEXT NOT NULL REFERENCES tracks(track_hash),
    model_name TEXT NOT NULL,
    model_hash TEXT NOT NULL,
    night_id TEXT REFERENCES nights(id),
    heat_id TEXT REFERENCES heats(id),
    rules TEXT NOT NULL,
    seed INTEGER NOT NULL,
    started_at TEXT NOT NULL,
    total_offtracks INTEGER NOT NULL,
    content_hash TEXT NOT NULL
);
CREATE INDEX races_night ON races(night_id);
CREATE INDEX races_racer ON races(racer);
CREATE TABLE race_laps (
    race_id TEXT NOT NULL REFERENCES races(id),
    number INTEGER NOT NULL,
    time_seconds REAL NOT NULL,
    raw_seconds REAL NOT NULL,
    penalty_seconds REAL NOT NULL,
    offtracks INTEGER NOT NULL,
    valid INTEGER NOT NULL,
    started_at REAL NOT NULL,
    PRIMARY KEY (race_id, number)
) WITHOUT ROWID;
CREATE TABLE corrections (
    id TEXT PRIMARY KEY,
    kind TEXT NOT NULL CHECK (kind IN ('disqualify_lap', 'rename_racer')),
    target TEXT NOT NULL,
    lap_number INTEGER,
    new_value TEXT,
    reason TEXT NOT NULL,
    made_by TEXT NOT NULL,
    created_at TEXT NOT NULL,
    content_hash TEXT NOT NULL
);
CREATE INDEX corrections_target ON corrections(target)
"""

# Version 2: local-only tables, never synced, always rebuildable from the shared rows.
# `entries` caches each submission's and race's scores under every ranking method with
# corrections applied, clustered by (track, racer). `board` holds each racer's best entry
# per track and method, clustered by (method, track), so a track's leaderboard is one range
# scan. `race_traces` keeps the large per-step traces out of the shared rows.
LOCAL_TABLES = """
CREATE TABLE entries (
    entry_id TEXT NOT NULL,
    kind TEXT NOT NULL,
    racer TEXT NOT NULL,
    track_hash TEXT NOT NULL,
    model_name TEXT NOT NULL,
    night_id TEXT,
    recorded_at TEXT NOT NULL,
    laps_driven INTEGER NOT NULL,
    valid_laps INTEGER NOT NULL,
    offtracks INTEGER NOT NULL,
    best_lap REAL,
    average_lap REAL,
    native_method TEXT NOT NULL,
    score_best_lap REAL,
    offtracks_best_lap INTEGER NOT NULL,
    score_best_average REAL,
    offtracks_best_average INTEGER NOT NULL,
    score_total_time REAL,
    offtracks_total_time INTEGER NOT NULL,
    PRIMARY KEY (track_hash, racer, entry_id)
) WITHOUT ROWID;
CREATE UNIQUE INDEX entries_id ON entries(entry_id);
CREATE INDEX entries_night ON entries(night_id) WHERE night_id IS NOT NULL;
CREATE TABLE board (
    method TEXT NOT NULL,
    track_hash TEXT NOT NULL,
    unscored INTEGER NOT NULL,
    score REAL NOT NULL,
    scoring_offtracks INTEGER NOT NULL,
    valid_laps INTEGER NOT NULL,
    recorded_at TEXT NOT NULL,
    racer TEXT NOT NULL,
    entry_id TEXT NOT NULL,
    kind TEXT NOT NULL,
    model_name TEXT NOT NULL,
    night_id TEXT,
    best_lap REAL,
    average_lap REAL,
    offtracks INTEGER NOT NULL,
    laps_driven INTEGER NOT NULL,
    PRIMARY KEY (method, track_hash, racer)
) WITHOUT ROWID;
CREATE TABLE race_traces (
    race_id TEXT PRIMARY KEY REFERENCES races(id),
    format TEXT NOT NULL,
    data BLOB NOT NULL
)
"""

# Version 3: sync bookkeeping, local-only (league.sync.local explains each table). What a
# store holds, where the last pull stopped, and what sync set aside (conflicts, quarantined
# records, records waiting for the records they refer to, identity losers) is this
# machine's knowledge, never shared.
SYNC_TABLES = """
CREATE TABLE sync_settings (
    name TEXT PRIMARY KEY,
    value TEXT NOT NULL
);
CREATE TABLE sync_in_store (
    store TEXT NOT NULL,
    kind TEXT NOT NULL,
    record_id TEXT NOT NULL,
    content_hash TEXT NOT NULL,
    version INTEGER NOT NULL,
    PRIMARY KEY (store, kind, record_id)
) WITHOUT ROWID;
CREATE TABLE sync_cursors (
    store TEXT PRIMARY KEY,
    cursor TEXT NOT NULL,
    updated_at TEXT NOT NULL
);
CREATE TABLE sync_runs (
    store TEXT NOT NULL,
    direction TEXT NOT NULL,
    finished_at TEXT NOT NULL,
    summary TEXT NOT NULL,
    PRIMARY KEY (store, direction)
);
CREATE TABLE sync_conflicts (
    store TEXT NOT NULL,
    kind TEXT NOT NULL,
    record_id TEXT NOT NULL,
    detail TEXT NOT NULL,
    local_hash TEXT,
    local_version INTEGER NOT NULL,
    local_body TEXT,
    remote_hash TEXT,
    remote_version INTEGER NOT NULL,
    remote_body TEXT,
    found_at TEXT NOT NULL,
    PRIMARY KEY (store, kind, record_id)
);
CREATE TABLE sync_quarantine (
    store TEXT NOT NULL,
    location TEXT NOT NULL,
    reason TEXT NOT NULL,
    kind TEXT,
    record_id TEXT,
    excerpt TEXT NOT NULL,
    found_at TEXT NOT NULL,
    PRIMARY KEY (store, location)
);
CREATE TABLE sync_pending (
    kind TEXT NOT NULL,
    record_id TEXT NOT NULL,
    content_hash TEXT NOT NULL,
    body TEXT NOT NULL,
    waiting_for TEXT NOT NULL,
    received_at TEXT NOT NULL,
    PRIMARY KEY (kind, record_id)
);
CREATE TABLE sync_aliases (
    kind TEXT NOT NULL,
    record_id TEXT NOT NULL,
    canonical_id TEXT NOT NULL,
    content_hash TEXT NOT NULL,
    body TEXT NOT NULL,
    PRIMARY KEY (kind, record_id)
);
CREATE TABLE sync_profiles (
    profile_id TEXT PRIMARY KEY,
    racer TEXT NOT NULL,
    version INTEGER NOT NULL,
    content_hash TEXT NOT NULL,
    body TEXT NOT NULL,
    received_at TEXT
);
CREATE TABLE sync_bundles (
    record_id TEXT PRIMARY KEY,
    model_hash TEXT NOT NULL,
    sha256 TEXT NOT NULL,
    size INTEGER NOT NULL,
    name TEXT NOT NULL,
    content_hash TEXT NOT NULL
);
CREATE INDEX sync_bundles_model ON sync_bundles(model_hash)
"""

# Version 4: the app's "recorded races, newest first" list, all tracks or one, reads an
# index instead of sorting every race in the league.
RECENT_RACES = """
CREATE INDEX races_started ON races(started_at, id);
CREATE INDEX races_track_started ON races(track_hash, started_at, id)
"""

# Version 5: which simulator's physics produced a submission's or race's laps (see
# sim.physics.labels). NULL in rows recorded before: racer-tui's physics 1, or DeepRacer's
# for its own evaluation files. The leaderboard cache is keyed by physics too, so it is
# made again (it is rebuilt from the shared rows).
PHYSICS = """
ALTER TABLE submissions ADD COLUMN physics TEXT;
ALTER TABLE races ADD COLUMN physics TEXT;
DROP TABLE board;
DROP TABLE entries;
CREATE TABLE entries (
    entry_id TEXT NOT NULL,
    kind TEXT NOT NULL,
    racer TEXT NOT NULL,
    track_hash TEXT NOT NULL,
    physics TEXT NOT NULL,
    model_name TEXT NOT NULL,
    night_id TEXT,
    recorded_at TEXT NOT NULL,
    laps_driven INTEGER NOT NULL,
    valid_laps INTEGER NOT NULL,
    offtracks INTEGER NOT NULL,
    best_lap REAL,
    average_lap REAL,
    native_method TEXT NOT NULL,
    score_best_lap REAL,
    offtracks_best_lap INTEGER NOT NULL,
    score_best_average REAL,
    offtracks_best_average INTEGER NOT NULL,
    score_total_time REAL,
    offtracks_total_time INTEGER NOT NULL,
    PRIMARY KEY (track_hash, racer, entry_id)
) WITHOUT ROWID;
CREATE UNIQUE INDEX entries_id ON entries(entry_id);
CREATE INDEX entries_night ON entries(night_id) WHERE night_id IS NOT NULL;
CREATE TABLE board (
    method TEXT NOT NULL,
    track_hash TEXT NOT NULL,
    physics TEXT NOT NULL,
    unscored INTEGER NOT NULL,
    score REAL NOT NULL,
    scoring_offtracks INTEGER NOT NULL,
    valid_laps INTEGER NOT NULL,
    recorded_at TEXT NOT NULL,
    racer TEXT NOT NULL,
    entry_id TEXT NOT NULL,
    kind TEXT NOT NULL,
    model_name TEXT NOT NULL,
    night_id TEXT,
    best_lap REAL,
    average_lap REAL,
    offtracks INTEGER NOT NULL,
    laps_driven INTEGER NOT NULL,
    PRIMARY KEY (method, track_hash, physics, racer)
) WITHOUT ROWID
"""

# Version 6: signed results (league.trust). The roster is a shared table: one row per act
# (found, propose, admit, retire, revoke), whose signer is named in `signed_by`. Every
# record's seal (made here at push, or pulled) is kept in sync_seals so it travels with
# the record to any other store. A pulled record the roster does not allow is quarantined
# with the whole record in `held`, and tried again when the roster changes. sync_replays
# remembers which races were re-run here (league.trust.replay) and what came out. Records
# that were waiting (sync_pending) were pulled unsigned: they are quarantined, never let in.
SIGNED_RESULTS = """
CREATE TABLE roster (
    id TEXT PRIMARY KEY,
    action TEXT NOT NULL,
    public_key TEXT NOT NULL,
    racer TEXT COLLATE NOCASE,
    role TEXT,
    signed_by TEXT NOT NULL,
    kept TEXT,
    league TEXT,
    created_at TEXT NOT NULL,
    content_hash TEXT NOT NULL
);
CREATE TABLE sync_seals (
    kind TEXT NOT NULL,
    record_id TEXT NOT NULL,
    version INTEGER NOT NULL,
    content_hash TEXT NOT NULL,
    signer TEXT NOT NULL,
    signature TEXT NOT NULL,
    PRIMARY KEY (kind, record_id, version, content_hash)
) WITHOUT ROWID;
CREATE TABLE sync_replays (
    race_id TEXT PRIMARY KEY,
    content_hash TEXT NOT NULL,
    outcome TEXT NOT NULL,
    detail TEXT NOT NULL,
    checked_at TEXT NOT NULL
);
ALTER TABLE sync_quarantine ADD COLUMN held TEXT;
INSERT OR REPLACE INTO sync_quarantine (store, location, reason, kind, record_id, excerpt,
    found_at)
SELECT '', kind || ' ' || record_id, 'it was pulled before results were signed and is not '
    || 'signed, so nobody can tell who made it', kind, record_id, substr(body, 1, 120),
    received_at FROM sync_pending;
DELETE FROM sync_pending
"""

# Version 7: a host's changes to a night before it runs, as rows of their own (nothing is
# edited in place): an entrant withdrawn before their heat, a night deleted before any
# heat was raced. `target` is the entrant's id, or the night's for a deletion.
NIGHT_CHANGES = """
CREATE TABLE night_changes (
    id TEXT PRIMARY KEY,
    night_id TEXT NOT NULL REFERENCES nights(id),
    action TEXT NOT NULL,
    target TEXT NOT NULL,
    made_by TEXT NOT NULL,
    created_at TEXT NOT NULL,
    content_hash TEXT NOT NULL
);
CREATE INDEX night_changes_night ON night_changes(night_id)
"""

# Version 8: the day a night is held (DREM's eventDate), which may differ from the day it
# was opened in racer-tui. NULL for nights opened before: they are held on the day they
# were opened.
NIGHT_DATE = """
ALTER TABLE nights ADD COLUMN held_on TEXT
"""

# Version 9: a track's leaderboard read in ranking order from one covering index: no sort of
# its rows and no lookup of each in the board (league.leaderboard._board_rows).
BOARD_ORDER = """
CREATE INDEX board_in_order ON board (
    method, track_hash, physics, unscored, score, scoring_offtracks, valid_laps DESC,
    recorded_at, racer, entry_id, kind, model_name, night_id, best_lap, average_lap,
    offtracks, laps_driven
)
"""

# Version 10: DeepRacer's race type (time trial, object avoidance, head-to-bot) of each
# entry, from its race's rules (a submission is a time trial): laps among boxes or bots
# are ranked on a board of their own, as laps of other physics are. The shared rows do not
# change (a race's rules already say its type; every row recorded before is a time trial).
# The cache tables are made again with the column, the board keyed and read in order by
# it after the track, and rebuilt from the shared rows.
RACE_TYPES = """
DROP TABLE board;
DROP TABLE entries;
CREATE TABLE entries (
    entry_id TEXT NOT NULL,
    kind TEXT NOT NULL,
    racer TEXT NOT NULL,
    track_hash TEXT NOT NULL,
    physics TEXT NOT NULL,
    race_type TEXT NOT NULL,
    model_name TEXT NOT NULL,
    night_id TEXT,
    recorded_at TEXT NOT NULL,
    laps_driven INTEGER NOT NULL,
    valid_laps INTEGER NOT NULL,
    offtracks INTEGER NOT NULL,
    best_lap REAL,
    average_lap REAL,
    native_method TEXT NOT NULL,
    score_best_lap REAL,
    offtracks_best_lap INTEGER NOT NULL,
    score_best_average REAL,
    offtracks_best_average INTEGER NOT NULL,
    score_total_time REAL,
    offtracks_total_time INTEGER NOT NULL,
    PRIMARY KEY (track_hash, racer, entry_id)
) WITHOUT ROWID;
CREATE UNIQUE INDEX entries_id ON entries(entry_id);
CREATE INDEX entries_night ON entries(night_id) WHERE night_id IS NOT NULL;
CREATE TABLE board (
    method TEXT NOT NULL,
    track_hash TEXT NOT NULL,
    race_type TEXT NOT NULL,
    physics TEXT NOT NULL,
    unscored INTEGER NOT NULL,
    score REAL NOT NULL,
    scoring_offtracks INTEGER NOT NULL,
    valid_laps INTEGER NOT NULL,
    recorded_at TEXT NOT NULL,
    racer TEXT NOT NULL,
    entry_id TEXT NOT NULL,
    kind TEXT NOT NULL,
    model_name TEXT NOT NULL,
    night_id TEXT,
    best_lap REAL,
    average_lap REAL,
    offtracks INTEGER NOT NULL,
    laps_driven INTEGER NOT NULL,
    PRIMARY KEY (method, track_hash, race_type, physics, racer)
) WITHOUT ROWID;
CREATE INDEX board_in_order ON board (
    method, track_hash, race_type, physics, unscored, score, scoring_offtracks,
    valid_laps DESC, recorded_at, racer, entry_id, kind, model_name, night_id, best_lap,
    average_lap, offtracks, laps_driven
)
"""

# Version 11: the race type of a submission, from its model's training_params.yaml (an
# object-avoidance model's evaluation drives among its boxes): NULL for a time trial, as
# every submission made before, so their records keep their content hashes. The cache is
# unchanged (every submission there is a time trial).
SUBMISSION_RACE_TYPES = """
ALTER TABLE submissions ADD COLUMN race_type TEXT
"""

# Version 12: a race that cannot be re-run here is "unverifiable", as every board says of it
# (league.trust.standing), no longer "skipped": the verdicts remembered before are renamed,
# so `sync verify` tries them again as it always has and no reader meets the old word.
UNVERIFIABLE_REPLAYS = """
UPDATE sync_replays SET outcome = 'unverifiable' WHERE outcome = 'skipped'
"""

# Version 13: whose model is whose (league.sync.models). A model record is a racer's signed
# word that a model hash is theirs, made for every model they race or submit with; `seen`
# numbers them in the order this league first held them, so when two racers claim one
# model the first seen keeps it whatever date the second one's record claims. A pulled
# result's first sighting here (sync_first_seen) bounds the time it ranks by in a tie
# (league.sync.dates): a date written earlier than the league could have seen it wins nothing.
MODEL_RECORDS = """
CREATE TABLE sync_models (
    seen INTEGER PRIMARY KEY,
    record_id TEXT NOT NULL UNIQUE,
    racer TEXT NOT NULL COLLATE NOCASE,
    model_name TEXT NOT NULL,
    model_hash TEXT NOT NULL,
    registered_at TEXT NOT NULL,
    content_hash TEXT NOT NULL
);
CREATE INDEX sync_models_hash ON sync_models(model_hash, seen);
CREATE TABLE sync_first_seen (
    entry_id TEXT PRIMARY KEY,
    seen_at TEXT NOT NULL
) WITHOUT ROWID
"""

# Version 14: a pulled result is checked against every other racer's result with its model
# and seed (a race) or its model and track (a submission), so it is not a copy
# (league.sync.models): found through an index each, not by reading every result.
COPY_LOOKUPS = """
CREATE INDEX races_model ON races(model_hash, seed);
CREATE INDEX submissions_model ON submissions(model_hash, track_hash)
"""

# Version 15: every reset DeepRacer counts in a lap (simapp's reset_count, which DeepRacer on
# AWS's rankings add up): a race lap's crashes (before, only inside its penalty seconds) and
# reversals, a submission lap's immobilized and reversed counts beside its off-tracks and
# crashes. NULL when none, and left out of a record's laps then (league.records), so every
# lap stored before keeps its content hash and most new laps look as they always did.
LAP_RESETS = """
ALTER TABLE race_laps ADD COLUMN crashes INTEGER;
ALTER TABLE race_laps ADD COLUMN reversals INTEGER;
ALTER TABLE submission_laps ADD COLUMN immobilized INTEGER;
ALTER TABLE submission_laps ADD COLUMN reversals INTEGER
"""

# Version 16: the policy runtime that drove a race (sim.training.runtimes): a
# race is judged by replay only where policies compute as they did. NULL for the reference
# driver, a physical car and every race recorded before, and left out of their records
# then. A replay's verdict keeps this machine's runtime when it had one to compare.
POLICY_RUNTIME = """
ALTER TABLE races ADD COLUMN runtime TEXT;
ALTER TABLE sync_replays ADD COLUMN runtime TEXT
"""

# One shared row per head-to-head race (league.head_to_heads): its cars (in finishing
# order, each with its laps) and incidents are JSON lists in the row, so the race is one
# signed record and never half here.
HEAD_TO_HEADS = """
CREATE TABLE head_to_heads (
    id TEXT PRIMARY KEY,
    track_hash TEXT NOT NULL REFERENCES tracks(track_hash),
    rules TEXT NOT NULL,
    seed INTEGER NOT NULL,
    started_at TEXT NOT NULL,
    clock REAL NOT NULL,
    cars TEXT NOT NULL,
    incidents TEXT NOT NULL,
    night_id TEXT REFERENCES nights(id),
    match_id TEXT,
    physics TEXT NOT NULL,
    content_hash TEXT NOT NULL
);
CREATE INDEX head_to_heads_track ON head_to_heads(track_hash, started_at);
CREATE INDEX head_to_heads_night ON head_to_heads(night_id)
"""

# One shared row per knock-out bracket of a night (league.bracket_records): its format, its
# seeds (the night's entrant ids, best qualifier first) and its matches' rules. Its matches
# are head-to-head races naming the night and the match. Not unique per night: two machines
# may each draw one before they sync, and the first drawn counts.
BRACKETS = """
CREATE TABLE brackets (
    id TEXT PRIMARY KEY,
    night_id TEXT NOT NULL REFERENCES nights(id),
    format TEXT NOT NULL,
    seeds TEXT NOT NULL,
    rules TEXT NOT NULL,
    created_at TEXT NOT NULL,
    content_hash TEXT NOT NULL
);
CREATE INDEX brackets_night ON brackets(night_id, created_at)
"""

MIGRATIONS: tuple[Migration, ...] = (
    Migration("shared league rows", _script(SHARED_TABLES)),
    Migration("local leaderboard cache and race traces", _script(LOCAL_TABLES), True),
    Migration("sync bookkeeping", _script(SYNC_TABLES)),
    Migration("recent races index", _script(RECENT_RACES)),
    Migration("physics of results", _script(PHYSICS), True),
    Migration("signed results", _script(SIGNED_RESULTS)),
    Migration("night changes", _script(NIGHT_CHANGES)),
    Migration("night dates", _script(NIGHT_DATE)),
    Migration("leaderboard in ranking order", _script(BOARD_ORDER)),
    Migration("race types of results", _script(RACE_TYPES), True),
    Migration("race types of submissions", _script(SUBMISSION_RACE_TYPES)),
    Migration("unverifiable replays", _script(UNVERIFIABLE_REPLAYS)),
    Migration("model records", _script(MODEL_RECORDS)),
    Migration("copy lookups", _script(COPY_LOOKUPS)),
    Migration("resets of laps", _script(LAP_RESETS)),
    Migration("policy runtimes of races", _script(POLICY_RUNTIME)),
    Migration("head-to-head races", _script(HEAD_TO_HEADS)),
    Migration("night brackets", _script(BRACKETS)),
)
SCHEMA_VERSION = len(MIGRATIONS)


def user_version(conn: sqlite3.Connection) -> int:
    return int(conn.execute("PRAGMA user_version").fetchone()[0])


def check_version(conn: sqlite3.Connection, path: Path) -> None:
    """Refuse a database from a newer racer-tui, or one that is not a league at all."""
    # One statement, so one snapshot: read apart, another racer-tui creating the league
    # could commit between them, and its fresh tables with the version read before would
    # look like a database that is not a league.
    version, tables = conn.execute(
        "SELECT (SELECT user_version FROM pragma_user_version), "
        "(SELECT count(*) FROM sqlite_master WHERE type = 'table')"
    ).fetchone()
    if version > SCHEMA_VERSION:
        raise LeagueError(
            f"league database {path} has schema version {version}, newer than the "
            f"{SCHEMA_VERSION} this racer-tui knows; upgrade racer-tui to open it "
            "(the file was not changed)."
        )
    if version == 0 and tables:
        raise LeagueError(
            f"{path} is an SQLite database but not a racer-tui league; "
            "choose another --db file (the file was not changed)."
        )


def migrate(conn: sqlite3.Connection, rebuild_cache: Callable[[sqlite3.Connection], None]) -> int:
    """Bring the database to SCHEMA_VERSION; returns how many migrations ran.

    `rebuild_cache` (league.opening passes league.entries.rebuild_entries) runs once after
    the last migration when one of them `rebuilds_cache`, in the same transaction.
    """
    if user_version(conn) == SCHEMA_VERSION:
        return 0
    conn.execute("BEGIN IMMEDIATE")
    try:
        start = user_version(conn)  # again, under the write lock: another process may have won
        pending = MIGRATIONS[start:]
        for migration in pending:
            migration.apply(conn)
        if any(migration.rebuilds_cache for migration in pending):
            rebuild_cache(conn)
        conn.execute(f"PRAGMA user_version = {SCHEMA_VERSION}")
    except BaseException:
        if conn.in_transaction:
            conn.execute("ROLLBACK")
        raise
    conn.execute("COMMIT")
    return len(pending)
