"""Submitting to the league from the app: a race from the Races section, or a garage
model's latest evaluation (what `racer-tui submit MODEL --racer NAME` does).

Both need the person: `RacerPrompt` asks once per app session (whichever section asks
first), in a dialog prefilled with this machine's racer (league.local_racer: the name last
submitted under, else the user name), and remembers the answer until the app quits.
The league work runs in thread workers and reuses the library's calls
(league.races.record_race_as, league.submissions.submit_model); where the entry lands is
told by league.board_place in one sentence.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from textual.message import Message
from textual.screen import Screen

from league.board_place import board_place, place_sentence
from league.errors import LeagueError
from league.local_racer import local_racer_name, save_local_racer_name
from league.opening import open_league
from league.race_types import race_type_of
from league.racers import check_name
from league.races import record_race_as
from league.submissions import submit_model
from racer_tui.app.screens.dialogs import InputDialog
from racer_tui.app.session import remember_racer, session_racer
from racer_tui.app.widgets.model_detail import seconds_text
from sim.foundation.plural import counted
from sim.race.result import RaceResult


def racer_name_problem(text: str) -> str | None:
    """What is wrong with `text` as a racer name, or None."""
    try:
        check_name(text)
    except LeagueError as error:
        message = str(error)
        return message[:1].upper() + message[1:]
    return None


class RacerPrompt:
    """Who is submitting from a screen: asked the first time in the app, then remembered."""

    def __init__(self, screen: Screen[Any], db_path: Path | None = None) -> None:
        self.screen = screen
        self.db_path = db_path

    @property
    def racer(self) -> str | None:
        """The racer confirmed in this app session, if any yet."""
        return session_racer(self.screen.app)

    def then(self, what: str, action: Callable[[str], None]) -> None:
        """Call `action(racer)` once the racer's name is confirmed in a dialog, prefilled
        with the name confirmed last in this app (or the league's saved or last racer), so a
        host submitting for several racers changes it there. `what` says what is being
        submitted, at the top of the dialog."""
        app = self.screen.app
        confirmed = self.racer

        def read_saved_name() -> None:  # a database read: off the UI thread
            name = confirmed
            if name is None:
                with open_league(self.db_path) as league:
                    name = local_racer_name(league)
            app.call_from_thread(self._ask, what, name, action)

        self.screen.run_worker(
            read_saved_name, thread=True, group="racer-name", exclusive=True, exit_on_error=False
        )

    def _ask(self, what: str, name: str, action: Callable[[str], None]) -> None:
        dialog = InputDialog(
            "Submit to the league",
            f"{what} The leaderboard lists it under your racer name (plain text):",
            value=name,
            confirm_label="Submit",
            check=racer_name_problem,
        )

        def answered(racer: str | None) -> None:
            if racer is not None:
                remember_racer(self.screen.app, racer)
                action(racer)

        self.screen.app.push_screen(dialog, answered)


# --- a race of the Races section -----------------------------------------------------------


@dataclass
class RaceSubmitted(Message):
    """A race is in the league now; `sentence` says where it stands."""

    result_id: str
    racer: str
    sentence: str


def submit_race(result: RaceResult, racer: str, db_path: Path | None) -> RaceSubmitted:
    """Run in a worker: record `result` (with its trace, so it replays) as `racer`'s race."""
    with open_league(db_path) as league:
        name = save_local_racer_name(league, racer)
        race_id = record_race_as(league, result, name)
        place = board_place(league, name, result.track_hash, race_type=race_type_of(result.rules))
    best = result.best_lap
    lap = f"best lap {seconds_text(best.time_seconds)}" if best is not None else "no valid lap"
    sentence = (
        f"Submitted {name}'s race with {result.model_name} on {result.track_name} ({lap}). "
        + place_sentence(place, race_id)
    )
    return RaceSubmitted(race_id, name, sentence)


# --- a garage model's latest evaluation ------------------------------------------------------


def submit_evaluation(
    model: str, racer: str, db_path: Path | None, *, allow_stale: bool = False
) -> str:
    """Run in a worker: what `racer-tui submit MODEL --racer NAME` does; returns the
    sentence to show. `allow_stale`: the racer confirmed an evaluation older than the
    model's last training."""
    with open_league(db_path) as league:
        name = save_local_racer_name(league, racer)
        submission, outcome = submit_model(league, model, name, allow_stale=allow_stale)
        place = board_place(
            league, submission.racer, submission.track_hash, race_type=submission.race_type
        )
    where = place_sentence(place, outcome.submission_id)
    if outcome.duplicate:
        return (
            f"{model}'s latest evaluation is already in the league for {name}; evaluate it "
            f"again to submit a new result. {where}"
        )
    best = submission.best_lap
    lap = "no completed lap" if best is None else f"best lap {seconds_text(best)}"
    completed = len(submission.completed_laps)
    return (
        f"Submitted {model} for {name} on {submission.track_name}: {lap}, {completed} of "
        f"{counted(len(submission.laps), 'trial')} completed. {where}"
    )


def submit_model_from(
    screen: Screen[Any], prompt: RacerPrompt, model: str, *, allow_stale: bool = False
) -> None:
    """Ask who is racing, then submit `model`'s latest evaluation in a worker; the outcome
    is a notification (a failure too: the screen shows failed workers)."""

    def submit(racer: str) -> None:
        def work() -> None:
            sentence = submit_evaluation(model, racer, prompt.db_path, allow_stale=allow_stale)
            screen.app.notify(sentence, title="League", timeout=12, markup=False)

        screen.run_worker(work, thread=True, group="league-submit", exit_on_error=False)

    prompt.then(f"{model}'s latest evaluation goes to the league.", submit)
