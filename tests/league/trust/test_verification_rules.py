"""The organiser's `verification` rule (which results a night's standings count): stored
only when set, so every rules written before keep their form and content hash; checked in
one sentence; refused when a pulled night or race carries a bad value."""

from __future__ import annotations

import json

import pytest

from league.nights import new_night
from league.records import record_body
from league.store import League
from league.sync.errors import RecordInvalidError
from league.sync.record import make_record
from league.sync.validate import check_record
from sim.race.rules import DEFAULT_RULES, RulesError, Verification, rules_from_mapping
from sim.tracks.catalog import resolve_track


def test_any_is_the_default_and_leaves_the_stored_form_unchanged() -> None:
    assert DEFAULT_RULES.verification is Verification.ANY
    assert "verification" not in DEFAULT_RULES.to_dict()
    assert "verified" not in DEFAULT_RULES.describe()


@pytest.mark.parametrize("level", ["verifiable", "replayed", " Replayed "])
def test_a_verification_rule_round_trips_and_is_described(level: str) -> None:
    rules = rules_from_mapping({"verification": level})
    assert rules.verification.value == level.strip().lower()
    assert rules.to_dict()["verification"] == rules.verification.value
    assert rules_from_mapping(json.loads(json.dumps(rules.to_dict()))) == rules
    assert rules.describe().endswith(f"({rules.verification.words})")


@pytest.mark.parametrize("bad", ["trust me", 1, True, None])
def test_a_bad_verification_value_is_one_sentence(bad: object) -> None:
    with pytest.raises(RulesError) as raised:
        rules_from_mapping({"verification": bad})
    assert str(raised.value) == (
        f"verification must be one of any, verifiable, replayed (which results count), not {bad!r}."
    )


def test_a_pulled_night_with_the_rule_passes_and_with_a_bad_value_is_refused(
    league: League,
) -> None:
    rules = rules_from_mapping({"verification": "replayed"})
    night = new_night(league, resolve_track("hairpin-circuit"), rules=rules)
    body = record_body(league, "nights", night.id)
    check_record(make_record("night", night.id, body))

    forged = {**body, "rules": json.dumps({**json.loads(body["rules"]), "verification": "all"})}
    with pytest.raises(RecordInvalidError) as raised:
        check_record(make_record("night", night.id, forged))
    assert str(raised.value).startswith("its rules are not race rules (verification must be")
