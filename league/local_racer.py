"""Who is racing on this machine: the racer name offered when submitting from the app, and
the name recorded when a host closes a night.

The name is a local league setting (never shared: it lives in `sync_settings`, this
machine's own table), saved when a racer submits under a name; until then it is the
league's most recent racer, and in an empty league nobody (the front end asks). Never the
operating system's user name: on a shared laptop that is nobody's racer name ("root").
Every front end asks here, so the app, the CLI and the night screens agree on one person.
"""

from __future__ import annotations

from typing import Final

from league.racers import check_name
from league.store import League
from league.sync.local import get_setting, set_setting

RACER_SETTING: Final = "racer"
HOST_NAME: Final = "host"  # who closes a night when nobody has given a name yet


def local_racer_name(league: League) -> str:
    """The racer saved for this machine, else the league's most recent racer, else ""."""
    saved = get_setting(league, RACER_SETTING)
    return saved if saved else last_racer(league)


def last_racer(league: League) -> str:
    """The racer of the league's most recent submission or race ("" in an empty league)."""
    row = league.query_one(
        "SELECT racer FROM (SELECT racer, submitted_at AS at FROM submissions "
        "UNION ALL SELECT racer, started_at AS at FROM races) ORDER BY at DESC LIMIT 1"
    )
    return str(row[0]) if row is not None else ""


def save_local_racer_name(league: League, name: str) -> str:
    """Remember `name` (checked like any racer name; LeagueError if it cannot be one) as
    this machine's racer, and return it as stored."""
    checked = check_name(name)
    with league.transaction():
        set_setting(league, RACER_SETTING, checked)
    return checked
