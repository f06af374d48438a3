"""`racer-tui racer keys | admit | retire | revoke`: who signs for whom in the league.

    racer-tui racer me [NAME]                            who races on this machine
    racer-tui racer keys [--json]                        every key the league knows
    racer-tui racer admit NAME [--key FP] [--organiser]  the organiser accepts a racer's key
    racer-tui racer retire NAME|FP                       an old key: its past results stay
    racer-tui racer revoke NAME|FP                       a lost key: all its results go

Registered under `racer` by league_commands; names come from other racers' machines, so
they are printed as plain text (Text cells), never as markup.
"""

from __future__ import annotations

import argparse
from typing import TYPE_CHECKING, Final

from rich import box
from rich.table import Table
from rich.text import Text

from racer_tui.cli.output import print_json, print_table

if TYPE_CHECKING:
    from league.store import League
    from league.trust.membership import KeyRow

    Actions = argparse._SubParsersAction[argparse.ArgumentParser]

ACTIONS: Final = ("me", "keys", "admit", "retire", "revoke")
_STATUS_WORDS: Final = {
    "founder": "organiser (founder)",
    "organiser": "organiser",
    "racer": "admitted",
    "proposed": "waiting for admission",
    "retired": "retired",
    "revoked": "revoked",
    "unknown": "not proposed yet",
}


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


def run(league: League, args: argparse.Namespace) -> int:
    from league.trust import membership
    from league.trust.keys import load_or_create_key

    action = args.racer_command
    if action == "me":
        return _me(league, args.name)
    key = load_or_create_key()
    if action == "keys":
        rows = membership.key_rows(league, key)
        if args.json:
            print_json([_json(row) for row in rows])
        else:
            _print_keys(rows)
        return 0
    if action == "admit":
        row = membership.admit(
            league, key, args.key or args.target, organiser=args.organiser, racer=args.racer
        )
        role = "an organiser" if row.status == "organiser" else f"racer {row.racer}'s"
        print(f"Admitted key {row.fingerprint} as {role} key.")
    else:
        end = membership.retire if action == "retire" else membership.revoke
        row = end(league, key, args.target)
        print(f"Key {row.fingerprint} ({row.racer or 'no racer'}) is {row.status} now.")
    print("Run `racer-tui sync` to share it with the league.")
    return 0


def _me(league: League, name: str | None) -> int:
    from league.local_racer import RACER_SETTING, save_local_racer_name
    from league.sync.local import get_setting

    if name is None:
        saved = get_setting(league, RACER_SETTING)
        print(f"This machine races as {saved}." if saved else "No racer name is saved here.")
        return 0
    saved = save_local_racer_name(league, name)
    from league.trust.keys import load_or_create_key
    from league.trust.roster import Roster

    status = Roster.load(league).status(load_or_create_key().public_hex)
    if status == "unknown":
        print(f"This machine races as {saved}; the next sync proposes its key under that name.")
    else:
        # The roster already names this key: a new local name does not change what it says.
        print(
            f"This machine races as {saved}. Its signing key is already known to the league "
            f"({status}); only the organiser changes whose key it is."
        )
    return 0


def _json(row: KeyRow) -> dict[str, object]:
    return {
        "public_key": row.public_key,
        "fingerprint": row.fingerprint,
        "racer": row.racer,
        "status": row.status,
        "this_machine": row.this_machine,
    }


def _print_keys(rows: list[KeyRow]) -> None:
    table = Table(title=Text("Signing keys"), box=box.SIMPLE_HEAD, pad_edge=False)
    for title in ("fingerprint", "racer", "status", ""):
        table.add_column(title)
    for row in rows:
        mine = "this machine" if row.this_machine else ""
        table.add_row(
            Text(row.fingerprint), Text(row.racer), Text(_STATUS_WORDS[row.status]), Text(mine)
        )
    print_table(table)
