"""Race types cross machines: a signed object-avoidance race pulled from the shared store
lands on its track's object-avoidance board, never among the time trials, and a pulled
record whose rules give a race type bad values is refused in one sentence naming the key."""

from __future__ import annotations

import copy
import json
from pathlib import Path
from typing import Any

import pytest

from league.leaderboard import Filters, leaderboard
from league.race_types import OBJECT_AVOIDANCE, TIME_TRIAL
from league.races import record_race
from league.records import record_body
from league.store import League, now_iso
from league.sync.errors import RecordInvalidError
from league.sync.record import make_record
from league.sync.validate import check_record
from sim.foundation.ids import new_id
from sim.race.rules import preset_rules
from sim.tracks.catalog import resolve_track
from tests.league.helpers import race_result
from tests.league.sync.test_signed_results import HAIRPIN, Machine

BOXES = preset_rules("object-avoidance")
BOTS = preset_rules("head-to-bot")


@pytest.fixture
def machines(organiser_ana_viewer: dict[str, Machine]) -> dict[str, Machine]:
    """The organiser, racer ana (admitted) and a viewer, sharing a folder store."""
    return organiser_ana_viewer


def _boards(league: League) -> list[tuple[str, str, str, float | None]]:
    return [
        (row.track_name, row.race_type, row.racer, row.best_lap)
        for row in leaderboard(league, Filters())
    ]


def test_a_synced_object_avoidance_race_lands_on_its_own_board(
    machines: dict[str, Machine],
) -> None:
    ana, viewer = machines["ana"], machines["viewer"]
    # Raced now: a racer's result dated before the league was founded is not its own.
    track = resolve_track(HAIRPIN)
    boxed = race_result("ana", [9.0, 9.5], track=track, rules=BOXES, started_at=now_iso())
    record_race(ana.league, boxed)
    assert ana.sync().pushed >= 1

    pulled_now = viewer.sync()

    assert viewer.quarantine() == {} and pulled_now.quarantined == []
    assert _boards(viewer.league) == [
        (HAIRPIN, TIME_TRIAL, "ana", 11.8),
        (f"{HAIRPIN} (object avoidance)", OBJECT_AVOIDANCE, "ana", 9.0),
    ]
    pulled = record_body(viewer.league, "races", boxed.result_id)
    assert json.loads(pulled["rules"])["race_type"] == "object_avoidance"
    hairpin = resolve_track(HAIRPIN).content_hash
    only_trials = Filters(track_hash=hairpin, race_type=TIME_TRIAL)
    assert [row.best_lap for row in leaderboard(viewer.league, only_trials)] == [11.8]


def test_a_synced_object_avoidance_submission_lands_on_its_own_board(
    machines: dict[str, Machine], tmp_path: Path
) -> None:
    from league.assembler import assemble
    from league.submissions import submit
    from sim.deepracer.files import TRAINING_PARAMS, TrainingParams, write_training_params
    from tests.league.helpers import TRACK, model_folder

    ana, viewer = machines["ana"], machines["viewer"]
    folder = model_folder(tmp_path / "models", "boxes", laps=(9.5,))
    oval = resolve_track(TRACK)
    write_training_params(
        folder / TRAINING_PARAMS,
        TrainingParams(oval.name, race_type="OBJECT_AVOIDANCE", track_hash=oval.content_hash),
    )
    submit(ana.league, assemble(str(folder), "ana"))
    ana.sync()

    viewer.sync()

    assert viewer.quarantine() == {}
    assert (f"{TRACK} (object avoidance)", OBJECT_AVOIDANCE, "ana", 9.5) in _boards(viewer.league)


@pytest.mark.parametrize("bad", ["time_trial", "drag_race", 3])
def test_a_submission_naming_another_race_type_is_refused(
    league: League, tmp_path: Path, bad: object
) -> None:
    from league.assembler import assemble
    from league.submissions import submit
    from tests.league.helpers import model_folder

    made = submit(league, assemble(str(model_folder(tmp_path)), "ana"))
    body = record_body(league, "submissions", made.submission_id)
    check_record(make_record("submission", new_id(), {**body, "race_type": "head_to_bot"}))

    with pytest.raises(RecordInvalidError, match="its race_type is not one of"):
        check_record(make_record("submission", new_id(), {**body, "race_type": bad}))


# --- the rules of pulled records -------------------------------------------------------------


def _race_body(league: League, rules: Any) -> dict[str, Any]:
    result = race_result("ana", [10.0], rules=rules)
    record_race(league, result)
    return record_body(league, "races", result.result_id)


def test_races_and_nights_of_every_race_type_pass(league: League) -> None:
    from league.nights import new_night

    for rules in (BOXES, BOTS, preset_rules("league")):
        check_record(make_record("race", new_id(), _race_body(league, rules)))
        night = new_night(league, resolve_track(HAIRPIN), rules=rules)
        check_record(make_record("night", night.id, record_body(league, "nights", night.id)))


@pytest.mark.parametrize(
    ("change", "key"),
    [
        ({"race_type": "drag_race"}, "race_type"),
        ({"obstacles": 0}, "obstacles"),
        ({"obstacles": 11}, "obstacles"),
        ({"obstacles": "3"}, "obstacles"),
        ({"randomize_obstacles": "yes"}, "randomize_obstacles"),
        ({"race_type": "head_to_bot", "bots": 7}, "bots"),
        ({"race_type": "head_to_bot", "bot_speed": 40}, "bot_speed"),
        ({"race_type": "head_to_bot", "bot_lane_change": 1}, "bot_lane_change"),
        # Keys of another race type: ranked as this one, raced as nobody can tell.
        ({"race_type": "head_to_bot", "bots": 2, "obstacles": 3}, "obstacles"),
        ({"race_type": "time_trial"}, "obstacles"),
    ],
)
def test_bad_race_type_values_are_refused_in_one_sentence(
    league: League, change: dict[str, Any], key: str
) -> None:
    body = copy.deepcopy(_race_body(league, BOXES))
    body["rules"] = json.dumps({**json.loads(body["rules"]), **change})

    with pytest.raises(RecordInvalidError) as raised:
        check_record(make_record("race", new_id(), body))

    reason = str(raised.value)
    assert reason.startswith("its rules are ")
    assert key in reason
    assert ". " not in reason and ".)" not in reason  # one sentence, not one inside another


def test_a_pulled_head_to_head_race_or_night_is_refused(league: League) -> None:
    # A head-to-head race is one record of all its cars (league.head_to_heads); a race or
    # night with its rules was made by hand: its laps among rivals must not reach a time
    # trials' board.
    body = copy.deepcopy(_race_body(league, preset_rules("league")))
    rules = {**json.loads(body["rules"]), "race_type": "head_to_model", "lap_count": 3}
    body["rules"] = json.dumps(rules)
    with pytest.raises(
        RecordInvalidError, match="head-to-head race's, which a league keeps as one record"
    ):
        check_record(make_record("race", new_id(), body))
