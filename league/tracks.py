"""Tracks in the league, identified by content hash: the same track imported twice, or
under two names, is one track row (the first name it was seen under)."""

from __future__ import annotations

from dataclasses import dataclass

from league.errors import LeagueError
from league.store import League, now_iso
from sim.tracks.catalog import resolve_track
from sim.tracks.track import Track, TrackError


@dataclass(frozen=True)
class LeagueTrack:
    track_hash: str
    name: str


def ensure_track(league: League, track_hash: str, name: str) -> LeagueTrack:
    """The league's row for this track, adding it first if new (call inside a transaction)."""
    row = league.query_one("SELECT name FROM tracks WHERE track_hash = ?", (track_hash,))
    if row is not None:
        return LeagueTrack(track_hash, str(row["name"]))
    league.insert_record(
        "tracks", {"track_hash": track_hash, "name": name, "created_at": now_iso()}
    )
    return LeagueTrack(track_hash, name)


def track_for(league: League, spec: str) -> LeagueTrack:
    """A track the league knows, by name or content hash, else through the track catalog.

    Looking in the league first finds tracks that came from other racers' machines.
    """
    rows = league.query(
        "SELECT track_hash, name FROM tracks WHERE name = ? COLLATE NOCASE OR track_hash = ?",
        (spec, spec),
    )
    if len(rows) == 1:
        return LeagueTrack(rows[0]["track_hash"], rows[0]["name"])
    track = _catalog_track(spec)
    row = league.query_one("SELECT name FROM tracks WHERE track_hash = ?", (track.content_hash,))
    return LeagueTrack(track.content_hash, str(row["name"]) if row else track.name)


def _catalog_track(spec: str) -> Track:
    try:
        return resolve_track(spec)
    except TrackError as error:
        raise LeagueError(str(error)) from None


def track_names(league: League) -> dict[str, str]:
    return {row["track_hash"]: row["name"] for row in league.query("SELECT * FROM tracks")}
