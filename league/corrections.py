"""Corrections: new rows saying who changed what and why; the original rows never change.

- disqualify a lap of a race or a submission: the lap stops counting everywhere (best lap,
  averages, scores, standings), and the lap row itself stays as it was recorded;
- rename a racer: a new display name; the racer's name (the key every record uses) stays.
"""

from __future__ import annotations

from dataclasses import dataclass

from league.entries import refresh_entries
from league.errors import LeagueError
from league.racers import check_name, get_racer
from league.store import League, now_iso

MAX_REASON = 500


@dataclass(frozen=True)
class Correction:
    id: str
    kind: str
    target: str
    lap_number: int | None
    new_value: str | None
    reason: str
    made_by: str
    created_at: str


def _reason(text: str) -> str:
    reason = text.strip()
    if not reason or len(reason) > MAX_REASON or any(ch in reason for ch in "\x00\r"):
        raise LeagueError(f"--reason must say why, in 1 to {MAX_REASON} characters.")
    return reason


def disqualify_lap(league: League, entry_id: str, lap_number: int, *, reason: str, by: str) -> str:
    """Disqualify lap `lap_number` of race or submission `entry_id`; returns the correction id."""
    target = entry_id.strip().upper()
    why = _reason(reason)
    who = check_name(by, "name")
    with league.transaction():
        table = _lap_table(league, target)
        if table is None:
            raise LeagueError(
                f"there is no race or submission {entry_id!r}; the ids are in "
                "`racer-tui leaderboard --format json`."
            )
        laps_table, key = table
        if not league.query_one(
            f"SELECT 1 FROM {laps_table} WHERE {key} = ? AND number = ?", (target, lap_number)
        ):
            raise LeagueError(f"{target} has no lap {lap_number}; laps are numbered from 1.")
        if league.query_one(
            "SELECT 1 FROM corrections WHERE kind = 'disqualify_lap' AND target = ? "
            "AND lap_number = ?",
            (target, lap_number),
        ):
            raise LeagueError(f"lap {lap_number} of {target} is already disqualified.")
        correction_id = league.insert_record(
            "corrections",
            {
                "kind": "disqualify_lap",
                "target": target,
                "lap_number": lap_number,
                "new_value": None,
                "reason": why,
                "made_by": who,
                "created_at": now_iso(),
            },
        )
        refresh_entries(league.conn, [target])
    return correction_id


def _lap_table(league: League, entry_id: str) -> tuple[str, str] | None:
    if league.query_one("SELECT 1 FROM races WHERE id = ?", (entry_id,)):
        return "race_laps", "race_id"
    if league.query_one("SELECT 1 FROM submissions WHERE id = ?", (entry_id,)):
        return "submission_laps", "submission_id"
    return None


def rename_racer(
    league: League, racer: str, display_name: str, *, by: str, reason: str = "new display name"
) -> str:
    """Give racer `racer` a new display name; returns the correction id."""
    new_name = check_name(display_name, "display name")
    who = check_name(by, "name")
    why = _reason(reason)
    with league.transaction():
        found = get_racer(league, racer)
        if found.display_name == new_name:
            raise LeagueError(f"{found.name!r} is already shown as {new_name!r}.")
        return league.insert_record(
            "corrections",
            {
                "kind": "rename_racer",
                "target": found.name,
                "lap_number": None,
                "new_value": new_name,
                "reason": why,
                "made_by": who,
                "created_at": now_iso(),
            },
        )


def list_corrections(league: League, target: str | None = None) -> list[Correction]:
    where, params = ("WHERE target = ?", (target,)) if target else ("", ())
    return [
        Correction(
            row["id"],
            row["kind"],
            row["target"],
            row["lap_number"],
            row["new_value"],
            row["reason"],
            row["made_by"],
            row["created_at"],
        )
        for row in league.query(f"SELECT * FROM corrections {where} ORDER BY id", params)
    ]
