"""Errors and notes from the libraries, as the app says them: a remedy the app offers
with a key is named by its key, and one it has no key for is left out, never shown as a
command to type in a shell."""

from __future__ import annotations

import pytest

from league.errors import LeagueError
from racer_tui.screens.base import APP_FIXES, error_message, in_app_words
from sim.garage.folder import ModelError, open_model
from sim.remedies import Fix, Note
from sim.track_errors import TrackError


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
