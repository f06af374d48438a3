"""What people do to the roster: found a league, propose their key, admit, retire, revoke.

Each act is a row of the shared `roster` table made here and signed with this machine's
key when it is pushed (roster.py says what each act means). Acts only the organiser makes
are refused here, with one sentence, when this machine's key did not found the league:
the league would refuse them anyway, but only after a sync, and silently for the person
who made them.
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from typing import Final

from league.errors import LeagueError
from league.local_racer import RACER_SETTING
from league.racers import look_alike
from league.records import store_record
from league.store import League, now_iso
from league.sync import incoming
from league.sync.local import STORE_SETTING, get_setting
from league.sync.validate import MAX_KEPT
from league.trust.keys import SigningKey, fingerprint
from league.trust.roster import FOUNDER_ID, Roster, record_digest, same_racer
from sim.foundation.ids import new_id
from sim.foundation.plain_names import look_alike_key
from sim.foundation.remedies import Fix, Note, echoed

MIN_FINGERPRINT_DIGITS: Final = 8


@dataclass(frozen=True)
class KeyRow:
    """One key the league knows, as `racer-tui racer keys` lists it."""

    public_key: str
    fingerprint: str
    racer: str  # "" when nobody is named
    status: str  # roster.Roster.status
    this_machine: bool


def _act(
    league: League,
    record_id: str,
    *,
    action: str,
    public_key: str,
    racer: str | None,
    role: str | None,
    signed_by: str,
    kept: str | None = None,
    league_id: str | None = None,
) -> None:
    body = {
        "action": action,
        "public_key": public_key,
        "racer": racer,
        "role": role,
        "signed_by": signed_by,
        "kept": kept,
        "league": league_id,
        "created_at": now_iso(),
    }
    store_record(league, "roster", record_id, body)


def found_league(league: League, key: SigningKey) -> bool:
    """Make this machine's key the league's organiser, unless the league has one already
    (then False: a second founder would be a conflict in every store)."""
    with league.transaction():
        if league.query_one("SELECT 1 FROM roster WHERE id = ?", (FOUNDER_ID,)) is not None:
            return False
        racer = get_setting(league, RACER_SETTING)
        _act(
            league,
            FOUNDER_ID,
            action="found",
            public_key=key.public_hex,
            racer=racer,
            role="organiser",
            signed_by=key.public_hex,
            league_id=new_id(),
        )
    return True


def propose_key(league: League, key: SigningKey) -> tuple[bool, str | None]:
    """Propose this machine's key for its racer, once. Returns whether a proposal was made
    now, and why it could not be (no racer name saved yet) or None."""
    roster = Roster.load(league)
    if roster.status(key.public_hex) != "unknown":
        return False, None
    # Only the name this machine's racer gave (never the league's latest racer, who may
    # be anybody): the organiser admits the key under it.
    racer = get_setting(league, RACER_SETTING)
    if not racer:
        problem = (
            "this machine's signing key was not proposed to the organiser because no racer "
            "name is saved here yet"
        )
        return False, Note(
            f"{problem}; run `racer-tui racer me NAME` (or submit from the app under your "
            "name), then sync again",
            problem=problem,
            fix=Fix.SET_RACER_NAME,
        )
    with league.transaction():
        _act(
            league,
            new_id(),
            action="propose",
            public_key=key.public_hex,
            racer=racer,
            role="racer",
            signed_by=key.public_hex,
        )
    return True, None


def _require_founder(roster: Roster, key: SigningKey, what: str) -> None:
    if key.public_hex != roster.founder:
        raise LeagueError(
            f"only the league's organiser can {what}, and this machine's key "
            f"({key.fingerprint}) is not the one that founded the league; ask the organiser "
            "to run it."
        )


def find_key(league: League, target: str) -> tuple[str, str | None]:
    """The public key (and proposed racer) that `target` names: a racer's name whose key
    was proposed, or a fingerprint (at least 8 hex digits, spaces allowed)."""
    roster = Roster.load(league)
    digits = target.replace(" ", "").lower()
    known = {**roster.proposed, **roster.racer_of}
    # A racer's name first: a name may look like hex ("20240501").
    keys = {k for k, racer in known.items() if same_racer(racer, target)}
    if not keys and len(digits) >= MIN_FINGERPRINT_DIGITS:
        keys = {k for k in (*known, *roster.organisers) if k.startswith(digits)}
    if not keys:
        raise LeagueError(
            f"no key proposed for {echoed(target)}; the racer syncs once to propose theirs "
            "(`racer-tui racer keys` lists the keys this league knows)."
        )
    if len(keys) > 1:
        listed = ", ".join(sorted(fingerprint(k) for k in keys))
        raise LeagueError(
            f"{echoed(target)} names {len(keys)} keys ({listed}); give the one you mean with --key."
        )
    public = keys.pop()
    return public, known.get(public)


def admit(
    league: League,
    key: SigningKey,
    target: str,
    *,
    organiser: bool = False,
    racer: str | None = None,
) -> KeyRow:
    """Admit the key `target` names, as its racer's (or as an organiser's)."""
    roster = Roster.load(league)
    _require_founder(roster, key, "admit keys")
    public, proposed = find_key(league, target)
    name = racer or proposed
    if not organiser and not name:
        raise LeagueError("say which racer this key belongs to with --racer NAME.")
    if name:
        _refuse_look_alike(league, roster, name)
    status = roster.status(public)
    if status in ("revoked", "retired"):
        raise LeagueError(
            f"key {fingerprint(public)} was {status} and cannot be admitted again; the racer's "
            "machine makes a new key when its key file is moved aside."
        )
    if status in ("racer", "organiser", "founder"):
        raise LeagueError(f"key {fingerprint(public)} is admitted already.")
    with league.transaction():
        role = "organiser" if organiser else "racer"
        _act(
            league,
            new_id(),
            action="admit",
            public_key=public,
            racer=name,
            role=role,
            signed_by=key.public_hex,
            league_id=roster.league,
        )
        incoming.retry_held(league)
    return _row(Roster.load(league), public, key)


def _refuse_look_alike(league: League, roster: Roster, name: str) -> None:
    """A key admitted under a name a reader cannot tell from another racer's would let its
    racer pose as them on every leaderboard (Cyrillic а for a, a zero-width space...)."""
    wanted = look_alike_key(name)
    others = {*roster.racer_of.values(), roster.founder_racer or ""}
    found = look_alike(league, name)
    if found:
        others.add(found)
    for other in sorted(others):
        if other and not same_racer(other, name) and look_alike_key(other) == wanted:
            apart = f"{echoed(name)} cannot be told apart from racer {echoed(other)}"
            problem = (
                f"{apart} on a leaderboard; ask the racer to choose another name and sync again"
            )
            raise LeagueError(
                f"{apart} on a leaderboard; ask the "
                "racer to choose another name (`racer-tui racer me NAME`, then sync), or admit "
                "the key under another name with --racer.",
                problem=problem,
            )


def retire(league: League, key: SigningKey, target: str) -> KeyRow:
    """Retire a key: what it signed stays, nothing it signs from now on counts."""
    return _end(league, key, target, "retire")


def revoke(league: League, key: SigningKey, target: str) -> KeyRow:
    """Revoke a key: nothing it ever signed counts any more."""
    return _end(league, key, target, "revoke")


def _end(league: League, key: SigningKey, target: str, action: str) -> KeyRow:
    roster = Roster.load(league)
    _require_founder(roster, key, f"{action} keys")
    public, racer = find_key(league, target)
    if public == roster.founder:
        raise LeagueError(f"the founding organiser's key cannot be {action}d.")
    if roster.status(public) in ("revoked", "retired"):
        raise LeagueError(f"key {fingerprint(public)} is {roster.status(public)} already.")
    kept = _kept(league, public) if action == "retire" else None
    with league.transaction():
        _act(
            league,
            new_id(),
            action=action,
            public_key=public,
            racer=racer,
            role=None,
            signed_by=key.public_hex,
            kept=kept,
            league_id=roster.league,
        )
        # Results the key may no longer vouch for leave this league's boards now, not at
        # the next pull (the quarantine row names the league's store, when it has one).
        incoming.withdraw_refused(league, get_setting(league, STORE_SETTING) or "")
    return _row(Roster.load(league), public, key)


def _kept(league: League, public: str) -> str:
    """The digests of every record `public` signed that this league accepted: what a
    retirement keeps (ids are the signer's to choose, so a date cannot say what came
    before; the list can)."""
    rows = league.query(
        "SELECT kind, record_id, version, content_hash FROM sync_seals WHERE signer = ?",
        (public,),
    )
    if len(rows) > MAX_KEPT:
        raise LeagueError(
            f"that key signed {len(rows)} records, more than a retirement can list "
            f"({MAX_KEPT}); revoke it instead, or ask its racer to keep using it."
        )
    return json.dumps(sorted(record_digest(*row) for row in rows))


def key_rows(league: League, key: SigningKey) -> list[KeyRow]:
    """Every key the league knows, this machine's own included."""
    roster = Roster.load(league)
    keys = {roster.founder, *roster.organisers, *roster.proposed, *roster.racer_of, key.public_hex}
    keys |= set(roster.revoked) | set(roster.kept)
    rows = [_row(roster, public, key) for public in keys if public]
    return sorted(rows, key=lambda row: (row.racer.casefold(), row.public_key))


def _row(roster: Roster, public: str, key: SigningKey) -> KeyRow:
    racer = roster.racer_of.get(public) or roster.proposed.get(public) or ""
    if public == roster.founder:
        racer = roster.founder_racer or racer
    return KeyRow(
        public, fingerprint(public), racer, roster.status(public), public == key.public_hex
    )
