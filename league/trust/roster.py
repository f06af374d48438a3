"""The league's roster: whose signature counts, and for what.

The roster is a shared league table (`roster`, one record per act), so every machine
that holds the same records reads the same roster:

    found    the organiser's own key; the record with the fixed FOUNDER_ID, signed by
             that key. `sync init` writes it, and a store holds one (create-only), so
             the first organiser of a store is its organiser everywhere.
    propose  a racer's key and their racer name, signed by that key (proof that the
             racer holds it); made by the racer's first push. Proposing grants nothing;
             a key proposed twice (from two leagues on one machine) counts its first.
    admit    an organiser's word that a key belongs to a racer (role "racer"), or to
             another organiser (role "organiser": a co-host who runs nights).
    retire   an organiser's word that a key is no longer used (a racer's old laptop):
             what it signed before stays, nothing it signs later counts.
    revoke   an organiser's word that a key was lost or misused: nothing it signed
             counts, before or after. The founder's key cannot be revoked.

Every act is a signed record: `signed_by` names the key that must have signed it, and
the pull checks the seal against it. Organisers are the founder plus every key admitted
as organiser by an organiser, revoked keys excluded (computed to a fixed point, so the
order records arrive in never matters).

`refusal` is the one rule for every pulled record: None when its signer may have made
it, else the sentence that says why not (shown in quarantine).
"""

from __future__ import annotations

import hashlib
from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field
from typing import Any, Final

from league.store import League
from league.sync.record import SyncRecord
from league.trust.keys import fingerprint

ROSTER_KIND: Final = "roster"
ACTIONS: Final = ("found", "propose", "admit", "retire", "revoke")
ROLES: Final = ("organiser", "racer")
# Kinds only an organiser signs: the running of nights and seasons, and corrections.
ORGANISER_KINDS: Final = frozenset(
    {"season", "night", "entrant", "heat", "night_closure", "correction"}
)
# Kinds any admitted racer may sign, whoever they name: a track brought to the league,
# the map from a model to its stored bundle.
ANY_RACER_KINDS: Final = frozenset({"track", "bundle"})
# Kinds that belong to one racer, and the body field naming them.
OWNER_FIELD: Final = {
    "racer": "name",
    "racer_profile": "racer",
    "submission": "racer",
    "race": "racer",
}

_CROCKFORD: Final = "0123456789ABCDEFGHJKMNPQRSTVWXYZ"


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

    @classmethod
    def from_body(cls, record_id: str, body: Mapping[str, Any]) -> Act:
        return cls(
            record_id,
            str(body["action"]),
            str(body["public_key"]),
            body.get("racer"),
            body.get("role"),
            str(body["signed_by"]),
        )


@dataclass
class Roster:
    """Who may sign what, read from the roster rows."""

    founder: str | None = None
    founder_racer: str | None = None
    organisers: set[str] = field(default_factory=set)
    racer_of: dict[str, str] = field(default_factory=dict)  # admitted key -> racer name
    proposed: dict[str, str] = field(default_factory=dict)  # key -> the name it proposed
    retired_at: dict[str, str] = field(default_factory=dict)  # key -> the retire act's id
    revoked: set[str] = field(default_factory=set)

    @classmethod
    def from_acts(cls, acts: Iterable[Act]) -> Roster:
        roster = cls()
        ordered = sorted(acts, key=lambda act: act.record_id)
        for act in ordered:
            if act.action == "found" and act.record_id == FOUNDER_ID:
                roster.founder, roster.founder_racer = act.public_key, act.racer
            elif act.action == "propose" and act.racer is not None:
                roster.proposed.setdefault(act.public_key, act.racer)
        if roster.founder is None:
            return roster
        # Revocations count if an organiser signed them, revoked or not (an organiser
        # cannot escape a revocation by revoking its revoker); the founder stays.
        ever = _organisers(roster.founder, ordered, revoked=set())
        roster.revoked = {
            act.public_key
            for act in ordered
            if act.action == "revoke" and act.signed_by in ever and act.public_key != roster.founder
        }
        roster.organisers = _organisers(roster.founder, ordered, roster.revoked)
        for act in ordered:
            if act.signed_by not in roster.organisers or act.public_key in roster.revoked:
                continue
            if act.action == "admit" and act.role == "racer" and act.racer is not None:
                roster.racer_of.setdefault(act.public_key, act.racer)
            elif act.action == "retire" and act.public_key != roster.founder:
                roster.retired_at.setdefault(act.public_key, act.record_id)
        return roster

    @classmethod
    def load(cls, league: League) -> Roster:
        rows = league.query(
            "SELECT id, action, public_key, racer, role, signed_by FROM roster ORDER BY id"
        )
        return cls.from_acts(Act(*(str(v) if v is not None else None for v in row)) for row in rows)  # type: ignore[arg-type]

    def status(self, key: str) -> str:
        """One word for `key`: founder, organiser, racer, retired, revoked, proposed, unknown."""
        if key in self.revoked:
            return "revoked"
        if key in self.retired_at:
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
        if self.founder is None:
            return (
                f"{theirs}unchecked: this league has no organiser yet (its organiser runs "
                "`racer-tui sync init STORE` once)"
            )
        key = f"key {fingerprint(signer)}"
        if signer in self.revoked:
            return f"{theirs}signed with {key}, which the organiser revoked"
        retired = self.retired_at.get(signer)
        if retired is not None and (record.version > 0 or record.record_id > retired):
            return f"{theirs}signed with {key} after the organiser retired that key"
        if signer in self.organisers:
            return None
        racer = self.racer_of.get(signer)
        if racer is None:
            proposed = self.proposed.get(signer)
            offer = (
                f"proposed for racer {proposed}: the organiser runs "
                f"`racer-tui racer admit {proposed}`"
                if proposed
                else "nobody has proposed it"
            )
            return f"{theirs}signed with {key}, which the organiser has not admitted yet ({offer})"
        if record.kind in ORGANISER_KINDS or (
            record.kind == "race" and record.body.get("night_id")
        ):
            made = "a league night's race" if record.kind == "race" else f"a {record.kind}"
            return f"it is signed by racer {racer}, but only an organiser makes {made}"
        if owner is not None and owner.casefold() != racer.casefold():
            return f"it claims to be racer {owner}'s, but it is signed with racer {racer}'s key"
        return None

    def _roster_refusal(self, record: SyncRecord, signer: str) -> str | None:
        act = Act.from_body(record.record_id, record.body)
        what = f"its {act.action} of key {fingerprint(act.public_key)}"
        if signer != act.signed_by:
            return (
                f"{what} names its signer as {fingerprint(act.signed_by)} but is signed "
                f"by {fingerprint(signer)}"
            )
        if act.action in ("found", "propose"):
            return None  # self-signed (validate.py checks signed_by == public_key)
        if self.founder is None:
            return f"{what} is unchecked: this league has no organiser yet"
        if signer not in self.organisers:
            return f"{what} is signed by key {fingerprint(signer)}, which is not an organiser's"
        return None


def _organisers(founder: str, acts: list[Act], revoked: set[str]) -> set[str]:
    organisers = {founder}
    grown = True
    while grown:
        grown = False
        for act in acts:
            if (
                act.action == "admit"
                and act.role == "organiser"
                and act.signed_by in organisers
                and act.public_key not in organisers
                and act.public_key not in revoked
            ):
                organisers.add(act.public_key)
                grown = True
    return organisers


def _owner(record: SyncRecord) -> str | None:
    field_name = OWNER_FIELD.get(record.kind)
    value = record.body.get(field_name) if field_name else None
    return value if isinstance(value, str) else None
