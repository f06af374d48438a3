"""A result belongs to the racer who drove it: model records, and the rule they carry.

A submission or race names its car by model hash. A `model` record is a racer's signed
word that a model hash is theirs: `{racer, model_name, model_hash, registered_at}`. Sync
makes one, before each push, for every model this machine's racer (`racer-tui racer me`)
raced or submitted with here and has not registered yet (`register_models`), dated by the
first result that used it; the roster lets a racer's key sign only their own
(league.trust.roster.OWNER_FIELD).

A pulled result signed by a racer (an organiser's results, a night's heats say, are the
organiser's word and need none) then must (`verdict`):

- not copy a result of another racer already here: a race with the same model, track,
  rules, seed and laps, or a submission of the same evaluation files;
- name a model no other racer registered before its racer did: the first model record
  this league saw for a model hash keeps it, whatever date a later one claims;
- name a model its racer registered, dated no later than the result; until that model
  record arrives, the result waits.

The reference driver ("reference:<track hash>") is everybody's: its results are re-driven
by anyone with the same seed, so they are neither registered nor copies. A DeepRacer
evaluation (source drfc or console) names its files' fingerprint as its model hash, and is
registered like any other model by the racer who submits it.
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from datetime import UTC, datetime
from typing import Any, Final, Literal

from league.local_racer import RACER_SETTING
from league.records import record_body
from league.rows import row_as
from league.store import League
from league.sync.dates import DATE_FIELD, DATE_TOLERANCE_MS, founded_ms, iso_ms
from league.sync.kinds import MODEL_KIND
from league.sync.local import add_conflict, body_text, get_setting
from league.sync.record import SyncRecord, make_record
from league.trust.roster import Roster, same_racer
from sim.foundation.ids import new_id

REFERENCE_PREFIX: Final = "reference:"


@dataclass(frozen=True)
class ModelInfo:
    record_id: str
    racer: str
    model_name: str
    model_hash: str
    registered_at: str


# A model record's body, in the order of sync_models' columns.
BODY_FIELDS: Final = ("racer", "model_name", "model_hash", "registered_at")


def model_body(racer: str, model_name: str, model_hash: str, registered_at: str) -> dict[str, Any]:
    """The body of a model record: the one shape every maker of one writes."""
    return dict(zip(BODY_FIELDS, (racer, model_name, model_hash, registered_at), strict=True))


def add_model(league: League, record: SyncRecord) -> None:
    body = record.body
    league.conn.execute(
        "INSERT INTO sync_models (record_id, racer, model_name, model_hash, registered_at, "
        "content_hash) VALUES (?, ?, ?, ?, ?, ?)",
        (
            record.record_id,
            body["racer"],
            body["model_name"],
            body["model_hash"],
            body["registered_at"],
            record.content_hash,
        ),
    )


def apply_pulled_model(
    league: League, store: str, record: SyncRecord
) -> Literal["inserted", "already", "conflict", "known"]:
    row = league.query_one(
        "SELECT content_hash, racer, model_name, model_hash, registered_at FROM sync_models "
        "WHERE record_id = ?",
        (record.record_id,),
    )
    if row is None:
        add_model(league, record)
        return "inserted"
    if row[0] == record.content_hash:
        return "already"
    local = model_body(*row[1:])
    new = add_conflict(
        league,
        store,
        MODEL_KIND,
        record.record_id,
        f"model record {record.record_id} differs here and in the store",
        local=(str(row[0]), 0, body_text(local)),
        remote=(record.content_hash, 0, body_text(record.body)),
    )
    return "conflict" if new else "known"


def is_here(league: League, record_id: str, content_hash: str) -> bool:
    row = league.query_one(
        "SELECT 1 FROM sync_models WHERE record_id = ? AND content_hash = ?",
        (record_id, content_hash),
    )
    return row is not None


def models(
    league: League, model_hash: str, revoked: frozenset[str] = frozenset()
) -> list[ModelInfo]:
    """The model records for `model_hash`, in the order this league first held them, but
    those signed by a `revoked` key (they count for nothing, as everything it signed)."""
    return [
        row_as(ModelInfo, row)
        for row in league.query(
            "SELECT record_id, racer, model_name, model_hash, registered_at FROM sync_models m "
            "WHERE model_hash = ? AND NOT EXISTS (SELECT 1 FROM sync_seals s WHERE s.kind = ? "
            "AND s.record_id = m.record_id AND s.signer IN (SELECT value FROM json_each(?))) "
            "ORDER BY seen",
            (model_hash, MODEL_KIND, json.dumps(sorted(revoked))),
        )
    ]


def unsent_models(league: League, store: str) -> list[tuple[str, str, dict[str, Any]]]:
    """(id, content hash, body) of each model record `store` is not known to hold
    (league.sync.outgoing sends them)."""
    rows = league.query(
        "SELECT record_id, content_hash, racer, model_name, model_hash, registered_at "
        "FROM sync_models m WHERE NOT EXISTS (SELECT 1 FROM sync_in_store s WHERE s.store = ? "
        "AND s.kind = ? AND s.record_id = m.record_id AND s.content_hash = m.content_hash) "
        "ORDER BY seen",
        (store, MODEL_KIND),
    )
    return [
        (record_id, digest, model_body(racer, model_name, model_hash, registered_at))
        for record_id, digest, racer, model_name, model_hash, registered_at in rows
    ]


def count_unsent(league: League, store: str) -> int:
    row = league.query_one(
        "SELECT count(*) FROM sync_models m WHERE NOT EXISTS (SELECT 1 FROM sync_in_store s "
        "WHERE s.store = ? AND s.kind = ? AND s.record_id = m.record_id "
        "AND s.content_hash = m.content_hash)",
        (store, MODEL_KIND),
    )
    return int(row[0]) if row else 0


# --- registering this machine's models ----------------------------------------------------


def register_models(league: League, signer: str) -> int:
    """Make a model record for every model this machine's racer raced or submitted with
    here (results `signer` sealed, or not sealed yet) and has not registered; returns how
    many were made. Each is dated by the first such result, and never before the league's
    founding (a result older than that does not count in it anyway). On an organiser's
    machine, also endorse each model's first owner seen here (`endorse_owners`)."""
    roster = Roster.load(league)
    made = endorse_if_organiser(league, signer, roster)
    racer = get_setting(league, RACER_SETTING)
    if not racer:
        return made
    founded = founded_ms(roster)
    first: dict[str, tuple[int, str, str]] = {}  # model hash -> (ms, its date, model name)
    rows = league.query(
        "SELECT 'race', id, model_hash, model_name, started_at FROM races WHERE racer = ?1 "
        "UNION ALL SELECT 'submission', id, model_hash, model_name, submitted_at "
        "FROM submissions WHERE racer = ?1",
        (racer,),
    )
    for kind, record_id, model_hash, model_name, dated in rows:
        if str(model_hash).startswith(REFERENCE_PREFIX) or _sealed_by_other(
            league, kind, record_id, signer
        ):
            continue
        try:
            ms, stamp = iso_ms(str(dated)), str(dated)
        except ValueError:
            continue
        if founded is not None and ms < founded - DATE_TOLERANCE_MS:
            ms, stamp = founded, _iso(founded)  # its results in this league are from then on
        if model_hash not in first or ms < first[model_hash][0]:
            first[model_hash] = (ms, stamp, str(model_name))
    with league.transaction():
        for model_hash, (ms, dated, model_name) in sorted(first.items()):
            if any(same_racer(info.racer, racer) for info in models(league, model_hash)):
                continue
            body = model_body(racer, model_name, model_hash, dated)
            add_model(league, make_record(MODEL_KIND, new_id(now_ms=ms), body))
            made += 1
    return made


def endorse_if_organiser(league: League, signer: str, roster: Roster | None = None) -> int:
    """`endorse_owners` when `signer` is one of the league's organisers, else nothing."""
    organisers = (roster or Roster.load(league)).organisers
    return endorse_owners(league, signer) if signer in organisers else 0


def endorse_owners(league: League, signer: str) -> int:
    """The organiser's word on whose each model is: a copy, signed by `signer` (an organiser)
    when pushed, of the first model record this machine saw for each model hash. A machine
    pulling the store afresh sees every claim at once and cannot tell which came first; it
    takes an organiser's record over any racer's (`owner`)."""
    made, roster = 0, Roster.load(league)
    with league.transaction():
        rows = league.query(
            "SELECT m.model_hash FROM sync_models m GROUP BY m.model_hash HAVING NOT EXISTS "
            "(SELECT 1 FROM sync_models e JOIN sync_seals s ON s.kind = ? AND "
            "s.record_id = e.record_id WHERE e.model_hash = m.model_hash AND s.signer = ?)",
            (MODEL_KIND, signer),
        )
        for (model_hash,) in rows:
            first = owner(league, model_hash, roster)
            if first is None or _unsealed_here(league, model_hash):
                continue
            body = model_body(first.racer, first.model_name, model_hash, first.registered_at)
            when = iso_ms(first.registered_at)
            add_model(league, make_record(MODEL_KIND, new_id(now_ms=when), body))
            made += 1
    return made


def _unsealed_here(league: League, model_hash: str) -> bool:
    """Whether a model record for `model_hash` was made here and not pushed (signed) yet."""
    row = league.query_one(
        "SELECT 1 FROM sync_models m WHERE m.model_hash = ? AND NOT EXISTS "
        "(SELECT 1 FROM sync_seals s WHERE s.kind = ? AND s.record_id = m.record_id)",
        (model_hash, MODEL_KIND),
    )
    return row is not None


def owner(league: League, model_hash: str, roster: Roster) -> ModelInfo | None:
    """Whose `model_hash` is: the first model record an organiser signed, else the first
    this league saw (any racer's)."""
    claims = models(league, model_hash, frozenset(roster.revoked))
    organisers = roster.organisers
    if not claims:
        return None
    signed = {
        str(row[0])
        for row in league.query(
            "SELECT s.record_id FROM sync_seals s JOIN sync_models m "
            "ON m.record_id = s.record_id WHERE s.kind = ? AND m.model_hash = ? "
            "AND s.signer IN (SELECT value FROM json_each(?))",
            (MODEL_KIND, model_hash, json.dumps(sorted(organisers))),
        )
    }
    endorsed = [info for info in claims if info.record_id in signed]
    return (endorsed or claims)[0]


def _sealed_by_other(league: League, kind: str, record_id: str, signer: str) -> bool:
    row = league.query_one(
        "SELECT 1 FROM sync_seals WHERE kind = ? AND record_id = ? AND signer <> ?",
        (kind, record_id, signer),
    )
    return row is not None


def _iso(ms: int) -> str:
    return datetime.fromtimestamp(ms / 1000, UTC).strftime("%Y-%m-%dT%H:%M:%S.%f")[:-3] + "Z"


def local_refusal(league: League, racer: str, model_hash: str) -> str | None:
    """Why `racer` may not submit with this model here (the rule for a pulled submission:
    another racer registered it first, as a model record pulled from the league says), or
    None. The same evaluation under two names on one machine is the host's own doing."""
    if model_hash.startswith(REFERENCE_PREFIX):
        return None
    first = owner(league, model_hash, Roster.load(league))
    if first is not None and not same_racer(first.racer, racer):
        return f"its model {model_hash[:12]} is racer {first.racer}'s (they registered it first)"
    return None


# --- the rule for pulled results ----------------------------------------------------------


@dataclass(frozen=True)
class Verdict:
    """A pulled result that cannot go in yet (`wait`) or ever (`refuse`), and why."""

    action: Literal["wait", "refuse"]
    reason: str


def verdict(league: League, record: SyncRecord, roster: Roster) -> Verdict | None:
    """None when a pulled submission or race may go in as far as its model is concerned."""
    if record.kind not in ("race", "submission"):
        return None
    body = record.body
    racer, model_hash = str(body["racer"]), str(body["model_hash"])
    if model_hash.startswith(REFERENCE_PREFIX) or _signer(league, record) in roster.organisers:
        return None
    copied = _copied(league, record)
    if copied is not None:
        return Verdict("refuse", copied)
    claims = models(league, model_hash, frozenset(roster.revoked))
    first = owner(league, model_hash, roster)
    if first is not None and not same_racer(first.racer, racer):
        return Verdict(
            "refuse",
            f"it names model {model_hash[:12]}, which racer {first.racer} registered first "
            f"(model record {first.record_id}): it copies {first.racer}'s model, and a result "
            "belongs to the racer who drove it",
        )
    own = [info for info in claims if same_racer(info.racer, racer)]
    if not own:
        return Verdict(
            "wait",
            f"racer {racer}'s model record for model {model_hash[:12]} (a result names a model "
            "its racer registered)",
        )
    dated = iso_ms(str(body[DATE_FIELD[record.kind]]))
    if all(iso_ms(info.registered_at) > dated + DATE_TOLERANCE_MS for info in own):
        return Verdict(
            "refuse",
            f"racer {racer} registered its model {model_hash[:12]} only after this result "
            f"(on {own[0].registered_at[:16]}), so it cannot have been driven with it",
        )
    return None


def _signer(league: League, record: SyncRecord) -> str | None:
    if record.seal is not None:
        return record.seal.signer
    row = league.query_one(
        "SELECT signer FROM sync_seals WHERE kind = ? AND record_id = ? AND content_hash = ?",
        (record.kind, record.record_id, record.content_hash),
    )
    return None if row is None else str(row[0])


def _copied(league: League, record: SyncRecord) -> str | None:
    """Why `record` is a copy of another racer's result here, or None."""
    body = record.body
    if record.kind == "submission":
        found = _copied_submission(
            league,
            str(body["racer"]),
            str(body["model_hash"]),
            str(body["track_hash"]),
            body["laps"],
            but=record.record_id,
        )
        if found is None:
            return None
        return (
            f"it copies racer {found[1]}'s submission {found[0]} (the same model, track and "
            "laps under another name)"
        )
    rows = league.query(
        "SELECT id, racer FROM races WHERE model_hash = ? AND seed = ? AND track_hash = ? "
        "AND rules = ? AND racer <> ? AND id <> ? ORDER BY id",
        (
            body["model_hash"],
            body["seed"],
            body["track_hash"],
            body["rules"],
            body["racer"],
            record.record_id,
        ),
    )
    for race_id, other in rows:
        if record_body(league, "races", race_id)["laps"] == body["laps"]:
            return (
                f"it copies racer {other}'s race {race_id} (the same model, track, rules, seed "
                "and laps under another name)"
            )
    return None


def _copied_submission(
    league: League,
    racer: str,
    model_hash: str,
    track_hash: str,
    laps: Any,
    *,
    but: str = "",
) -> tuple[str, str] | None:
    """(id, racer) of another racer's submission here with this model, track and laps."""
    rows = league.query(
        "SELECT id, racer FROM submissions WHERE model_hash = ? AND track_hash = ? "
        "AND racer <> ? AND id <> ? ORDER BY id",
        (model_hash, track_hash, racer, but),
    )
    for submission_id, other in rows:
        if record_body(league, "submissions", submission_id)["laps"] == laps:
            return str(submission_id), str(other)
    return None
