"""What people do to the roster: found a league, propose their key, admit, retire, revoke.

Each act is a row of the shared `roster` table made here and signed with this machine's
key when it is pushed (roster.py says what each act means). Acts that need an organiser
are refused here, with one sentence, when this machine's key is not one: the league would
refuse them anyway, but only after a sync, and silently for the person who made them.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Final

from league.errors import LeagueError
from league.local_racer import local_racer_name
from league.records import store_record
from league.store import League, now_iso
from league.sync import incoming
from league.sync.local import STORE_SETTING, get_setting
from league.trust.keys import SigningKey, fingerprint
from league.trust.roster import FOUNDER_ID, Roster
from sim.ids import new_id

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
) -> None:
    body = {
        "action": action,
        "public_key": public_key,
        "racer": racer,
        "role": role,
        "signed_by": signed_by,
        "created_at": now_iso(),
    }
    store_record(league, "roster", record_id, body)


def found_league(league: League, key: SigningKey) -> bool:
    """Make this machine's key the league's organiser, unless the league has one already
    (then False: a second founder would be a conflict in every store)."""
    with league.transaction():
        if league.query_one("SELECT 1 FROM roster WHERE id = ?", (FOUNDER_ID,)) is not None:
            return False
        racer = local_racer_name(league) or None
        _act(
            league,
            FOUNDER_ID,
            action="found",
            public_key=key.public_hex,
            racer=racer,
            role="organiser",
            signed_by=key.public_hex,
        )
    return True


def propose_key(league: League, key: SigningKey) -> str | None:
    """Propose this machine's key for its racer, once; returns why it could not be
    proposed (no racer name yet), or None when it is proposed or needs no proposal."""
    roster = Roster.load(league)
    if roster.status(key.public_hex) != "unknown":
        return None
    racer = local_racer_name(league)
    if not racer:
        return (
            "this machine's signing key was not proposed to the organiser because it has no "
            "racer name yet; submit a result under your name, then sync again"
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
    return None


def _require_organiser(roster: Roster, key: SigningKey, what: str) -> None:
    if key.public_hex not in roster.organisers:
        raise LeagueError(
            f"only the league's organiser can {what}, and this machine's key "
            f"({key.fingerprint}) is not an organiser's; ask the organiser to run it."
        )


def find_key(league: League, target: str) -> tuple[str, str | None]:
    """The public key (and proposed racer) that `target` names: a racer's name whose key
    was proposed, or a fingerprint (at least 8 hex digits, spaces allowed)."""
    roster = Roster.load(league)
    digits = target.replace(" ", "").lower()
    known = {**roster.proposed, **roster.racer_of}
    if len(digits) >= MIN_FINGERPRINT_DIGITS and all(c in "0123456789abcdef" for c in digits):
        keys = {k for k in (*known, *roster.organisers) if k.startswith(digits)}
    else:
        keys = {k for k, racer in known.items() if racer.casefold() == target.casefold()}
    if not keys:
        raise LeagueError(
            f"no key proposed for {target!r}; the racer syncs once to propose theirs "
            "(`racer-tui racer keys` lists the keys this league knows)."
        )
    if len(keys) > 1:
        listed = ", ".join(sorted(fingerprint(k) for k in keys))
        raise LeagueError(
            f"{target!r} names {len(keys)} keys ({listed}); give the one you mean with --key."
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
    _require_organiser(roster, key, "admit keys")
    public, proposed = find_key(league, target)
    name = racer or proposed
    if not organiser and not name:
        raise LeagueError("say which racer this key belongs to with --racer NAME.")
    if public in roster.revoked:
        raise LeagueError(f"key {fingerprint(public)} was revoked and cannot be admitted again.")
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
        )
        incoming.retry_held(league)
    return _row(Roster.load(league), public, key)


def retire(league: League, key: SigningKey, target: str) -> KeyRow:
    """Retire a key: what it signed stays, nothing it signs from now on counts."""
    return _end(league, key, target, "retire")


def revoke(league: League, key: SigningKey, target: str) -> KeyRow:
    """Revoke a key: nothing it ever signed counts any more."""
    return _end(league, key, target, "revoke")


def _end(league: League, key: SigningKey, target: str, action: str) -> KeyRow:
    roster = Roster.load(league)
    _require_organiser(roster, key, f"{action} keys")
    public, racer = find_key(league, target)
    if public == roster.founder:
        raise LeagueError(f"the founding organiser's key cannot be {action}d.")
    with league.transaction():
        _act(
            league,
            new_id(),
            action=action,
            public_key=public,
            racer=racer,
            role=None,
            signed_by=key.public_hex,
        )
        # Results the key may no longer vouch for leave this league's boards now, not at
        # the next pull (the quarantine row names the league's store, when it has one).
        incoming.withdraw_refused(league, get_setting(league, STORE_SETTING) or "")
    return _row(Roster.load(league), public, key)


def key_rows(league: League, key: SigningKey) -> list[KeyRow]:
    """Every key the league knows, this machine's own included."""
    roster = Roster.load(league)
    keys = {roster.founder, *roster.organisers, *roster.proposed, *roster.racer_of, key.public_hex}
    keys |= set(roster.revoked) | set(roster.retired_at)
    rows = [_row(roster, public, key) for public in keys if public]
    return sorted(rows, key=lambda row: (row.racer.casefold(), row.public_key))


def _row(roster: Roster, public: str, key: SigningKey) -> KeyRow:
    racer = roster.racer_of.get(public) or roster.proposed.get(public) or ""
    if public == roster.founder:
        racer = roster.founder_racer or racer
    return KeyRow(
        public, fingerprint(public), racer, roster.status(public), public == key.public_hex
    )
