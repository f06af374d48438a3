"""`racer-tui racer me | keys | admit | retire | revoke` run: who races on this machine and
who signs for whom in the league (the parsers are `key_parsers`). Names come from other
racers' machines, so they are printed as plain text (Text cells), never as markup."""

from __future__ import annotations

import argparse
from typing import Final

from rich import box
from rich.table import Table
from rich.text import Text

from league.local_racer import RACER_SETTING, save_local_racer_name
from league.store import League
from league.sync.local import get_setting
from league.trust import membership
from league.trust.keys import load_or_create_key
from league.trust.membership import KeyRow
from league.trust.roster import Roster
from racer_tui.cli.output import print_json, print_table

_STATUS_WORDS: Final = {
    "founder": "organiser (founder)",
    "organiser": "organiser",
    "racer": "admitted",
    "proposed": "waiting for admission",
    "retired": "retired",
    "revoked": "revoked",
    "unknown": "not proposed yet",
}


def run(league: League, args: argparse.Namespace) -> int:

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

    if name is None:
        saved = get_setting(league, RACER_SETTING)
        print(f"This machine races as {saved}." if saved else "No racer name is saved here.")
        return 0
    saved = save_local_racer_name(league, name)

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
