"""Who is racing on this machine: the racer name offered when submitting from the app, and
the name recorded when a host closes a night.

The name is a local league setting (never shared: it lives in `sync_settings`, this
machine's own table), saved when a racer submits under a name; until then it is the
operating system's user name. Every front end asks here, so the app, the CLI and the
night screens agree on one person.
"""

from __future__ import annotations

import getpass
from typing import Final

from league.racers import check_name
from league.store import League
from league.sync.local import get_setting, set_setting

RACER_SETTING: Final = "racer"
FALLBACK_NAME: Final = "racer"  # when the operating system has no user name to give


def machine_user() -> str:
    """The operating system's user name (a container may have none)."""
    try:
        return check_name(getpass.getuser())
    except (OSError, KeyError, ValueError):
        return FALLBACK_NAME


def local_racer_name(league: League) -> str:
    """The racer saved for this machine, or the operating system's user name."""
    saved = get_setting(league, RACER_SETTING)
    return saved if saved else machine_user()


def save_local_racer_name(league: League, name: str) -> str:
    """Remember `name` (checked like any racer name; LeagueError if it cannot be one) as
    this machine's racer, and return it as stored."""
    checked = check_name(name)
    with league.transaction():
        set_setting(league, RACER_SETTING, checked)
    return checked
