"""Racers: the people in the league, keyed by their name.

A racer's `name` never changes (records from every machine refer to it); the name shown
on leaderboards is the display name, which a rename correction replaces. Names are plain
text: anything printable, shown literally (never as markup) by every front end.
"""

from __future__ import annotations

import hashlib
import re
from dataclasses import dataclass

from league.errors import LeagueError
from league.store import League, now_iso
from sim.foundation.plain_names import MAX_NAME_LENGTH, is_plain_name, look_alike_key, normalised
from sim.foundation.remedies import echoed

# Distinct, readable on dark and light terminals; a racer's default is picked by name.
PALETTE = (
    "#e6194b",
    "#3cb44b",
    "#ffe119",
    "#4363d8",
    "#f58231",
    "#911eb4",
    "#42d4f4",
    "#f032e6",
    "#bfef45",
    "#fabed4",
    "#469990",
    "#dcbeff",
)
HEX_COLOUR = re.compile(r"#[0-9a-fA-F]{6}")


@dataclass(frozen=True)
class Racer:
    id: str
    name: str
    display_name: str  # after renames
    colour: str
    created_at: str


def check_name(text: str, what: str = "racer name") -> str:
    """`text` as kept (NFKC, stripped: see sim.foundation.plain_names), or LeagueError saying what a
    name may contain."""
    name = normalised(text)
    if not is_plain_name(name):
        raise LeagueError(
            f"{echoed(text)} cannot be a {what}: use 1 to {MAX_NAME_LENGTH} printable characters "
            "(no line breaks, control characters or invisible characters)."
        )
    return name


def look_alike(league: League, name: str) -> str | None:
    """An existing racer whose name a reader could not tell from `name`, if any."""
    key = look_alike_key(name)
    for row in league.query("SELECT name, display_name FROM racers"):
        for existing in (str(row["name"]), str(row["display_name"])):
            if existing != name and look_alike_key(existing) == key:
                return existing
    return None


def check_colour(text: str) -> str:
    if not HEX_COLOUR.fullmatch(text):
        raise LeagueError(f"colour {echoed(text)} must be #rrggbb, for example {PALETTE[0]}.")
    return text.lower()


def default_colour(name: str) -> str:
    digest = hashlib.sha256(name.casefold().encode("utf-8")).digest()
    return PALETTE[digest[0] % len(PALETTE)]


def find_racer(league: League, name: str) -> Racer | None:
    """The racer called `name` (case-insensitive), or whose display name it is."""
    row = league.query_one("SELECT * FROM racers WHERE name = ?", (name.strip(),))
    if row is None:
        names = display_names(league)
        matches = [key for key, shown in names.items() if shown.casefold() == name.casefold()]
        if len(matches) != 1:
            return None
        row = league.query_one("SELECT * FROM racers WHERE name = ?", (matches[0],))
        if row is None:
            return None
    shown = display_names(league, row["name"]).get(row["name"], row["display_name"])
    return Racer(row["id"], row["name"], shown, row["colour"], row["created_at"])


def get_racer(league: League, name: str) -> Racer:
    racer = find_racer(league, name)
    if racer is None:
        raise LeagueError(
            f"there is no racer called {echoed(name)}; add one with `racer-tui racer add NAME` "
            "or submit with --racer NAME."
        )
    return racer


def add_racer(
    league: League, name: str, *, display_name: str | None = None, colour: str | None = None
) -> Racer:
    """A new racer; LeagueError if the name is taken."""
    clean = check_name(name)
    with league.transaction():
        if league.query_one("SELECT 1 FROM racers WHERE name = ?", (clean,)):
            raise LeagueError(
                f"there is already a racer called {echoed(clean)}; pick another name."
            )
        ensure_racer(league, clean, display_name=display_name, colour=colour)
    return get_racer(league, clean)


def ensure_racer(
    league: League, name: str, *, display_name: str | None = None, colour: str | None = None
) -> str:
    """The stored spelling of racer `name`, adding the racer first if there is none.

    Call inside a transaction. Names match case-insensitively, so "Ana" and "ana" are one
    racer and records always carry the first spelling.
    """
    clean = check_name(name)
    row = league.query_one("SELECT name FROM racers WHERE name = ?", (clean,))
    if row is not None:
        return str(row["name"])
    similar = look_alike(league, clean)
    if similar is not None:
        raise LeagueError(
            f"{echoed(clean)} looks like the racer {echoed(similar)}; if that is you, use "
            "exactly that name, otherwise choose a name that looks different."
        )
    shown = check_name(display_name, "display name") if display_name else clean
    league.insert_record(
        "racers",
        {
            "name": clean,
            "display_name": shown,
            "colour": check_colour(colour) if colour else default_colour(clean),
            "created_at": now_iso(),
        },
    )
    return clean


def display_names(league: League, name: str | None = None) -> dict[str, str]:
    """Racer name -> the name to show, with the latest rename correction applied."""
    where, params = ("WHERE name = ?", (name,)) if name is not None else ("", ())
    shown = {
        row["name"]: row["display_name"]
        for row in league.query(f"SELECT name, display_name FROM racers {where}", params)
    }
    renames = league.query(
        "SELECT r.name, c.new_value FROM corrections c JOIN racers r ON r.name = c.target "
        f"WHERE c.kind = 'rename_racer' {'AND r.name = ?' if name is not None else ''} "
        "ORDER BY c.created_at, c.id",
        (name,) if name is not None else (),
    )
    for row in renames:
        shown[row["name"]] = row["new_value"]
    return shown


def display_names_overrides(league: League) -> dict[str, str]:
    """Racer name -> display name, only for racers shown under another name than their
    own (set when added, or by a rename correction; the latest rename wins). Small, so a
    leaderboard of thousands of racers looks names up here instead of joining."""
    shown = {
        row[0]: row[1]
        for row in league.query("SELECT name, display_name FROM racers WHERE display_name <> name")
    }
    renames = league.query(
        "SELECT r.name, c.new_value FROM corrections c JOIN racers r ON r.name = c.target "
        "WHERE c.kind = 'rename_racer' ORDER BY c.created_at, c.id"
    )
    shown.update((row[0], row[1]) for row in renames)
    return shown


def list_racers(league: League) -> list[Racer]:
    shown = display_names(league)
    return [
        Racer(row["id"], row["name"], shown[row["name"]], row["colour"], row["created_at"])
        for row in league.query("SELECT * FROM racers ORDER BY name COLLATE NOCASE")
    ]
