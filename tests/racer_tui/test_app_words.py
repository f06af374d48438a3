"""Errors and notes from the libraries, as the app says them: a remedy the app offers
with a key is named by its key, and one it has no key for is left out, never shown as a
command to type in a shell."""

from __future__ import annotations

import io
import json
from dataclasses import replace
from pathlib import Path

import pytest

from league.errors import LeagueError
from league.nights import add_entrant, close_night, draw_heats, new_night
from league.opening import open_league
from league.races import record_race
from racer_tui.app.model_form import field_message
from racer_tui.app.screens.base import error_message
from racer_tui.app.words import APP_FIXES, in_app_words
from sim.foundation.remedies import Fix, Note
from sim.garage.clone import clone_model
from sim.garage.folder import ModelError, open_model
from sim.garage.options import new_model
from sim.tracks.catalog import resolve_track
from sim.tracks.errors import TrackError
from sim.training.drivers import RaceSetupError, resolve_driver
from tests.league.helpers import race_result


def test_every_remedy_a_library_names_has_the_apps_words() -> None:
    assert set(APP_FIXES) == set(Fix)
    assert not any("racer-tui" in words or "--" in words for words in APP_FIXES.values())


@pytest.mark.parametrize(
    ("error", "said"),
    [
        (
            LeagueError(
                "x: there are no evaluation metrics; evaluate the model first, or name a file "
                "with --evaluation.",
                problem="x: there are no evaluation metrics",
                fix=Fix.EVALUATE_MODEL,
            ),
            "X: there are no evaluation metrics; press v in the Garage to evaluate it.",
        ),
        (
            TrackError(
                "a track named 'club' is already imported; choose another name with --name.",
                problem="a track named 'club' is already imported",
                fix=Fix.RENAME,
            ),
            "A track named 'club' is already imported; choose another name.",
        ),
        (  # a remedy the app has no key for: the problem alone
            LeagueError("--model must name a garage model.", problem="the car must be a model"),
            "The car must be a model.",
        ),
    ],
)
def test_an_error_is_said_with_the_apps_remedy(error: Exception, said: str) -> None:
    assert error_message(error) == said


def test_an_unknown_model_points_to_the_garage() -> None:
    with pytest.raises(ModelError) as raised:
        open_model("nobody-made-this")
    said = error_message(raised.value)
    assert said.startswith("There is no model named 'nobody-made-this'")
    assert "the Garage (1) lists your models" in said and "racer-tui" not in said


def test_a_note_keeps_the_command_lines_words_and_the_app_says_its_own() -> None:
    note = Note("p; run `racer-tui train x`.", problem="p", fix=Fix.TRAIN_MODEL)
    assert str(note) == "p; run `racer-tui train x`."  # printed and serialised as before
    assert in_app_words(note) == "p; press t in the Garage to train it."
    assert in_app_words("a plain note") == "a plain note"


# --- library sentences that named a command: the command line says it, the app its key -----


def _in_the_app(said: str, *keys: str) -> None:
    assert all(key in said for key in keys), said
    assert "racer-tui" not in said and "--" not in said and "`" not in said, said


def test_closing_a_night_with_heats_waiting(tmp_path: Path) -> None:
    with open_league(tmp_path / "league.db") as league:
        night = new_night(league, resolve_track("beginner-oval"), name="friday")
        for racer in ("ada", "bob"):
            add_entrant(league, night, racer, "reference")
        draw_heats(league, night, seed=1)
        with pytest.raises(LeagueError) as raised:
            close_night(league, night, "host")
    assert str(raised.value) == (
        "league night 'friday' still has 2 heats to run; run them with `racer-tui night run`, "
        "or close anyway with --force."
    )
    said = error_message(raised.value)
    assert said == (
        "League night 'friday' still has 2 heats to run; run them (r), or press c again to "
        "close the night anyway."
    )
    _in_the_app(said, "(r)", "press c")


def test_a_recorded_race_submitted_again_with_other_content(tmp_path: Path) -> None:
    result = race_result("ana", [12.0])
    with open_league(tmp_path / "league.db") as league:
        record_race(league, result)
        with pytest.raises(LeagueError) as raised:
            record_race(league, replace(result, racer="bob"))
    assert str(raised.value) == (
        f"race {result.result_id} is already recorded with different content; a recorded "
        "race never changes (use `racer-tui correct` for corrections)."
    )
    said = error_message(raised.value)  # the app corrects nothing: the problem alone
    assert said == (
        f"Race {result.result_id} is already recorded with different content; a recorded "
        "race never changes."
    )
    _in_the_app(said)


def test_a_folder_that_is_not_a_model(tmp_path: Path) -> None:
    stranger = tmp_path / "stranger"
    stranger.mkdir()
    with pytest.raises(ModelError) as raised:
        open_model(str(stranger))
    problem = f"{stranger}/model/model_metadata.json does not exist, so {stranger} is not a model"
    assert str(raised.value) == (
        f"{problem} folder; give a garage model name, or bring in a DeepRacer download with "
        "`racer-tui model import PATH`."
    )
    said = error_message(raised.value)
    assert said == (
        f"{problem} folder; give a garage model's name, or import the folder in the Garage "
        "(i there)."
    )
    _in_the_app(said, "(i there)")
    # A night's entrant is checked when added: the league keeps the remedy.
    with open_league(tmp_path / "league.db") as league:
        night = new_night(league, resolve_track("beginner-oval"), name="friday")
        with pytest.raises(LeagueError) as entered:
            add_entrant(league, night, "ada", str(stranger))
    assert str(entered.value) == str(raised.value)
    assert error_message(entered.value) == said


UNKNOWN_TRACK_REMEDY = (
    "; give a name that `racer-tui tracks list` shows, or the path of a DeepRacer .npy file "
    "(`racer-tui tracks import FILE` keeps one)."
)


def test_a_track_that_is_not_here() -> None:
    with pytest.raises(TrackError) as raised:
        resolve_track("zzqxw")
    assert str(raised.value) == "there is no track named 'zzqxw'" + UNKNOWN_TRACK_REMEDY
    said = error_message(raised.value)
    assert (
        said
        == "There is no track named 'zzqxw'; import its .npy file on the Tracks screen (i there)."
    )
    _in_the_app(said, "(i there)")
    # The model editor's track field says it the app's way too.
    message = field_message(raised.value)
    assert message == str(raised.value)
    _in_the_app(in_app_words(message), "(i there)")


def test_a_models_track_that_is_not_here() -> None:
    folder = new_model("rookie")
    params = folder.training_params_file
    params.write_text(params.read_text().replace("reinvent_base", "zzqxw"))
    with pytest.raises(ModelError) as raised:
        folder.track()
    assert str(raised.value) == (
        "model 'rookie' trains on track 'zzqxw': there is no track named 'zzqxw'"
        + UNKNOWN_TRACK_REMEDY
    )
    said = error_message(raised.value)
    assert said == (
        "Model 'rookie' trains on track 'zzqxw': there is no track named 'zzqxw'; press e in "
        "the Garage to choose another (i on the Tracks screen imports a DeepRacer .npy track)."
    )
    _in_the_app(said, "press e")
    # A clone of it (c in the Garage) fails on the track the same way, with the remedy.
    with pytest.raises(ModelError) as cloned:
        clone_model(folder, "rookie-2")
    assert str(cloned.value) == "there is no track named 'zzqxw'" + UNKNOWN_TRACK_REMEDY
    _in_the_app(error_message(cloned.value), "(i there)")


def test_a_race_views_driver_keeps_the_libraries_remedy() -> None:
    track = resolve_track("beginner-oval")
    with pytest.raises(RaceSetupError) as missing:
        resolve_driver("nobody-made-this", track)
    assert str(missing.value) == (
        "there is no model named 'nobody-made-this'; `racer-tui model list` shows your models "
        "and `racer-tui model new NAME` creates one."
    )
    _in_the_app(error_message(missing.value), "the Garage (1)")
    new_model("rookie")  # never trained
    with pytest.raises(RaceSetupError) as untrained:
        resolve_driver("rookie", track)
    assert str(untrained.value) == (
        "cannot race 'rookie': model 'rookie' has no trained policy yet; train it first with "
        "`racer-tui train rookie`."
    )
    said = error_message(untrained.value)
    assert said == (
        "Cannot race 'rookie': model 'rookie' has no trained policy yet; press t in the Garage "
        "to train it."
    )
    _in_the_app(said, "press t")


def test_the_garage_says_a_failed_runs_remedy_the_apps_way() -> None:
    """The trainer's state file keeps a failure's remedy apart; the Garage's training facts
    say it with the app's key, and a file naming no known remedy keeps its message."""
    from rich.console import Console

    from racer_tui.app.widgets.model_detail import ModelDetail
    from sim.garage.summary import training_summary

    folder = new_model("rookie")
    state = {
        "state": "failed",
        "message": "p; give a name that `racer-tui tracks list` shows",
        "problem": "model 'rookie' trains on track 'zzqxw'",
        "fix": "CHOOSE_TRACK",
    }

    def facts() -> str:
        console = Console(width=200, record=True, file=io.StringIO())
        console.print(ModelDetail._training(training_summary(folder)))
        return console.export_text()

    folder.training_state_file.write_text(json.dumps(state))
    shown = facts()
    assert "model 'rookie' trains on track 'zzqxw'; press e in the Garage" in shown
    assert "racer-tui" not in shown
    folder.training_state_file.write_text(json.dumps({**state, "fix": "NOT_A_FIX"}))
    assert "`racer-tui tracks list`" in facts()
