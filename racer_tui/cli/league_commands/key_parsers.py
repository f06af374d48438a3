"""`racer-tui racer keys | admit | retire | revoke`: who signs for whom in the league.

    racer-tui racer me [NAME]                            who races on this machine
    racer-tui racer keys [--json]                        every key the league knows
    racer-tui racer admit NAME [--key FP] [--organiser]  the organiser accepts a racer's key
    racer-tui racer retire NAME|FP                       an old key: its past results stay
    racer-tui racer revoke NAME|FP                       a lost key: all its results go

Registered under `racer` by league_commands; run by `league_commands.keys`.
"""

from __future__ import annotations

import argparse
from typing import TYPE_CHECKING, Final

if TYPE_CHECKING:
    Actions = argparse._SubParsersAction[argparse.ArgumentParser]

ACTIONS: Final = ("me", "keys", "admit", "retire", "revoke")


def register(actions: Actions, db: argparse.ArgumentParser) -> None:
    me = actions.add_parser(
        "me",
        parents=[db],
        help="this machine's racer name (the name its signing key is proposed under)",
    )
    me.add_argument("name", nargs="?", help="save this name (default: show the saved one)")
    keys = actions.add_parser(
        "keys", parents=[db], help="signing keys: whose they are, which are admitted"
    )
    keys.add_argument("--json", action="store_true")
    admit = actions.add_parser(
        "admit",
        parents=[db],
        help="accept a racer's key (the organiser)",
        description="Accept the key a racer proposed when they first synced, so their "
        "results reach every leaderboard. Compare its fingerprint with the racer's own "
        "`racer-tui racer keys` before admitting it.",
    )
    admit.add_argument("target", metavar="NAME", help="the racer's name, or a key fingerprint")
    admit.add_argument("--key", metavar="FP", help="the fingerprint, when NAME has several keys")
    admit.add_argument("--racer", help="the racer the key belongs to (default: the proposed name)")
    admit.add_argument(
        "--organiser", action="store_true", help="admit it as a co-organiser who runs nights"
    )
    for name, what in (
        ("retire", "stop accepting a key from now on; what it signed before stays"),
        ("revoke", "stop accepting a key and everything it ever signed"),
    ):
        end = actions.add_parser(name, parents=[db], help=f"{what} (the organiser)")
        end.add_argument("target", metavar="NAME|FP", help="the racer's name or a fingerprint")
