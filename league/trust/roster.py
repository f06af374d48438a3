"""The league's roster: whose signature counts, and for what.

The roster is a shared league table (`roster`, one record per act), so every machine
that holds the same records reads the same roster:

    found    the organiser's own key; the record with the fixed FOUNDER_ID, signed by
             that key. `sync init` writes it, and a store holds one (create-only), so
             the first organiser of a store is its organiser everywhere.
    propose  a racer's key and their racer name, signed by that key (proof that the
             racer holds it); made by the racer's first push. Proposing grants nothing;
             a key proposed twice (from two leagues on one machine) counts its first.
    admit    the organiser's word that a key belongs to a racer (role "racer"), or to a
             co-host (role "organiser": may run nights and sign any result, but never
             changes the roster).
    retire   the organiser's word that a key is no longer used (a racer's old laptop).
             The act lists what the key had signed (`kept`: a short digest per record,
             as the organiser's league held them); those still count, nothing else does,
             whatever date its ids claim.
    revoke   the organiser's word that a key was lost or misused: nothing it signed
             counts, before or after.

Only the founding key changes the roster, and it can be neither retired nor revoked: a
single owner, so every machine computes the same roster from the same acts whatever
order they arrived in, and no co-host (or a stolen co-host key) can admit anyone.

`refusal` is the one rule for every pulled record: None when its signer may have made
it, else the sentence that says why not (shown in quarantine).
"""

from __future__ import annotations

import hashlib
import json
import string
from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field
from typing import Any, Final

from league.store import League
from league.sync.local import get_setting
from league.sync.record import SyncRecord
from league.trust.keys import fingerprint

ROSTER_KIND: Final = "roster"
PIN_SETTING: Final = "organiser"  # sync_settings: the organiser's fingerprint, hex digits
ACTIONS: Final = ("found", "propose", "admit", "retire", "revoke")
ROLES: Final = ("organiser", "racer")
# Kinds only an organiser signs: the running of nights and seasons, corrections, and
# head-to-head races (each names several racers: no racer puts a result on another's
# record).
ORGANISER_KINDS: Final = frozenset(
    {
        "season",
        "night",
        "entrant",
        "heat",
        "night_closure",
        "night_change",
        "bracket",
        "correction",
        "head_to_head",
    }
)
# How a refusal names the kinds whose names are not words.
_KIND_WORDS: Final = {
    "night_closure": "night's closure",
    "night_change": "change to a night",
    "head_to_head": "head-to-head race",
}
# Kinds any admitted racer may sign, whoever they name: a track brought to the league,
# the map from a model to its stored bundle.
ANY_RACER_KINDS: Final = frozenset({"track", "bundle"})
# Kinds that belong to one racer, and the body field naming them.
OWNER_FIELD: Final = {
    "racer": "name",
    "racer_profile": "racer",
    "submission": "racer",
    "race": "racer",
    "model": "racer",  # a racer's word that a model is theirs (league.sync.models)
}

_CROCKFORD: Final = "0123456789ABCDEFGHJKMNPQRSTVWXYZ"
_ASCII_FOLD: Final = str.maketrans(string.ascii_uppercase, string.ascii_lowercase)


def _derived_id(label: bytes, value: str) -> str:
    digest = hashlib.sha256(label + value.encode("utf-8")).digest()
    number = int.from_bytes(digest[:16], "big") >> 2  # 126 bits: 26 characters
    return "".join(_CROCKFORD[(number >> shift) & 31] for shift in range(125, -1, -5))


# One fixed id, so a store (create-only) holds exactly one founding record.
FOUNDER_ID: Final = _derived_id(b"racer-tui league founder", "")


@dataclass(frozen=True)
class Act:
    """One roster row."""

    record_id: str
    action: str
    public_key: str
    racer: str | None
    role: str | None
    signed_by: str
    kept: str | None = None  # a retire act's JSON list of record digests
    # The league the act belongs to (the founding act's own random id): one organiser key
    # may found several leagues, and an admission in one must mean nothing in another.
    league: str | None = None

    @classmethod
    def from_body(cls, record_id: str, body: Mapping[str, Any]) -> Act:
        return cls(
            record_id,
            str(body["action"]),
            str(body["public_key"]),
            body.get("racer"),
            body.get("role"),
            str(body["signed_by"]),
            body.get("kept"),
            body.get("league"),
        )


def same_racer(one: str, other: str) -> bool:
    """Whether two names are one racer, as the league's tables compare them (SQLite's
    NOCASE: ASCII letters only, so "Jeß" and "Jess" are two racers)."""
    return one.translate(_ASCII_FOLD) == other.translate(_ASCII_FOLD)


def record_digest(kind: str, record_id: str, version: int, content_hash: str) -> str:
    """What a retire act lists per record the retired key may still have signed: 16 hex
    digits of a hash over the record's identity and content (short, so thousands fit)."""
    text = f"{kind} {record_id} {version} {content_hash}"
    return hashlib.sha256(text.encode("ascii")).hexdigest()[:16]


@dataclass
class Roster:
    """Who may sign what, read from the roster rows."""

    founder: str | None = None
    founder_racer: str | None = None
    organisers: set[str] = field(default_factory=set)
    racer_of: dict[str, str] = field(default_factory=dict)  # admitted key -> racer name
    proposed: dict[str, str] = field(default_factory=dict)  # key -> the name it proposed
    kept: dict[str, frozenset[str]] = field(default_factory=dict)  # retired key -> digests
    revoked: set[str] = field(default_factory=set)
    league: str | None = None  # the founding act's league id
    # The organiser's fingerprint as the racer was told it (`sync set --organiser`): a
    # founding record with another key is refused, whoever wrote it to the store first.
    pinned: str | None = None
    impostor: str | None = None  # a founder this league holds that is not the pinned one

    @classmethod
    def from_acts(cls, acts: Iterable[Act]) -> Roster:
        roster = cls()
        ordered = sorted(acts, key=lambda act: act.record_id)
        for act in ordered:
            if act.action == "found" and act.record_id == FOUNDER_ID:
                roster.founder, roster.founder_racer = act.public_key, act.racer
                roster.league = act.league
            elif act.action == "propose" and act.racer is not None:
                roster.proposed.setdefault(act.public_key, act.racer)
        founder = roster.founder
        if founder is None:
            return roster
        # Only the founder's acts for this league count (the pull holds any other), and
        # never against the founder itself.
        own = [
            a
            for a in ordered
            if a.signed_by == founder and a.public_key != founder and a.league == roster.league
        ]
        roster.revoked = {act.public_key for act in own if act.action == "revoke"}
        for act in own:
            if act.public_key in roster.revoked:
                continue
            if act.action == "retire" and act.public_key not in roster.kept:
                roster.kept[act.public_key] = frozenset(_digests(act.kept))
            elif act.action == "admit" and act.role == "racer" and act.racer is not None:
                roster.racer_of.setdefault(act.public_key, act.racer)
        admitted = {a.public_key for a in own if a.action == "admit" and a.role == "organiser"}
        roster.organisers = {founder} | (admitted - roster.revoked - set(roster.kept))
        return roster

    @classmethod
    def load(cls, league: League) -> Roster:
        rows = league.query(
            "SELECT id, action, public_key, racer, role, signed_by, kept, league FROM roster "
            "ORDER BY id"
        )
        roster = cls.from_acts(Act(*row) for row in rows)
        pinned = get_setting(league, PIN_SETTING)
        if pinned is None:
            return roster
        if roster.founder is None or roster.founder.startswith(pinned):
            roster.pinned = pinned
            return roster
        # Not the organiser the racer was told: as if the league had none (nothing counts).
        impostor = cls(proposed=roster.proposed, pinned=pinned, impostor=roster.founder)
        return impostor

    def status(self, key: str) -> str:
        """One word for `key`: founder, organiser, racer, retired, revoked, proposed, unknown."""
        if key in self.revoked:
            return "revoked"
        if key in self.kept:
            return "retired"
        if key == self.founder:
            return "founder"
        if key in self.organisers:
            return "organiser"
        if key in self.racer_of:
            return "racer"
        if key in self.proposed:
            return "proposed"
        return "unknown"

    def refusal(self, record: SyncRecord) -> str | None:
        """None if the record's signer may have made it, else why not: one sentence that
        names the racer the record claims to be for (the caller names the record)."""
        owner = _owner(record)
        theirs = f"it is racer {owner}'s, but " if owner else "it is "
        if record.seal is None:
            return f"{theirs}not signed, so nobody can tell who made it"
        signer = record.seal.signer
        if record.kind == ROSTER_KIND:
            return self._roster_refusal(record, signer)
        if self.impostor is not None and self.pinned is not None:
            return (
                f"{theirs}unchecked: the store's organiser key {fingerprint(self.impostor)} is "
                f"not the one you were told ({fingerprint(self.pinned)}); check with your organiser"
            )
        if self.founder is None:
            return (
                f"{theirs}unchecked: this league has no organiser yet (its organiser sets "
                "the store up once: s on the Sync screen, or `racer-tui sync init STORE`)"
            )
        key = f"key {fingerprint(signer)}"
        if signer in self.revoked:
            return f"{theirs}signed with {key}, which the organiser revoked"
        kept = self.kept.get(signer)
        if kept is not None:
            digest = record_digest(
                record.kind, record.record_id, record.version, record.content_hash
            )
            if digest in kept:
                return None  # signed before the key was retired, while it counted
            return (
                f"{theirs}signed with {key}, which the organiser retired; only what it had "
                "signed before then counts"
            )
        if signer in self.organisers:
            return None
        racer = self.racer_of.get(signer)
        if racer is None:
            proposed = self.proposed.get(signer)
            offer = (
                f"proposed for racer {proposed}: the organiser compares the fingerprint "
                f"with {proposed}, then admits it (a on the Sync screen, or "
                f"`racer-tui racer admit {proposed}`)"
                if proposed
                else "nobody has proposed it"
            )
            return f"{theirs}signed with {key}, which the organiser has not admitted yet ({offer})"
        if record.kind in ORGANISER_KINDS or (
            record.kind == "race" and record.body.get("night_id")
        ):
            made = (
                "a league night's race"
                if record.kind == "race"
                else f"a {_KIND_WORDS.get(record.kind, record.kind)}"
            )
            return f"it is signed by racer {racer}, but only an organiser makes {made}"
        if owner is not None and not same_racer(owner, racer):
            return f"it claims to be racer {owner}'s, but it is signed with racer {racer}'s key"
        shown = record.body.get("display_name")
        if record.kind == "racer" and isinstance(shown, str) and not same_racer(shown, racer):
            # Else an admitted "eve" could appear as "Ana" on every board.
            return (
                f"it is signed by racer {racer} but shows them as {shown}; only the organiser "
                "renames racers"
            )
        return None

    def _roster_refusal(self, record: SyncRecord, signer: str) -> str | None:
        act = Act.from_body(record.record_id, record.body)
        what = f"its {act.action} of key {fingerprint(act.public_key)}"
        if signer != act.signed_by:
            return (
                f"{what} names its signer as {fingerprint(act.signed_by)} but is signed "
                f"by {fingerprint(signer)}"
            )
        if act.action == "found" and self.pinned and not act.public_key.startswith(self.pinned):
            return (
                f"{what} names another organiser than the one this league was told "
                f"({fingerprint(self.pinned)}): check the store with your organiser"
            )
        if act.action in ("found", "propose"):
            return None  # self-signed (validate.py checks signed_by == public_key)
        if self.founder is None:
            return f"{what} is unchecked: this league has no organiser yet"
        if signer != self.founder:
            return (
                f"{what} is signed by key {fingerprint(signer)}, but only the organiser's "
                "own key changes the roster"
            )
        return None


def _digests(text: str | None) -> list[str]:
    """A retire act's list (validate.py checked its form when it was pulled)."""
    if not text:
        return []
    values = json.loads(text)
    return [value for value in values if isinstance(value, str)]


def _owner(record: SyncRecord) -> str | None:
    field_name = OWNER_FIELD.get(record.kind)
    value = record.body.get(field_name) if field_name else None
    return value if isinstance(value, str) else None
