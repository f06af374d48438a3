"""The Coach view: from the Garage (a model's evaluated lap) and from a finished race, the
lap against the limit lap sector by sector, at 80x24."""

from __future__ import annotations

from textual.app import App
from textual.widgets import DataTable, Static

from racer_tui.app.application import create_app
from racer_tui.app.screens.coach import CoachScreen
from racer_tui.app.screens.race_screen import RaceScreen, RaceSetup
from racer_tui.app.widgets.coach_map import CoachMap
from sim.garage.folder import open_model
from sim.garage.options import new_model
from sim.race.driver import ReferenceRaceDriver
from sim.race.rules import RaceRules
from sim.tracks.catalog import resolve_track
from sim.training.evaluation import evaluate_model
from tests.racer_tui.screens.test_race_screen import worked_out
from tests.racer_tui.screens.tui_helpers import Notifications, painted, settle


def evaluated_model(name: str, track: str = "hairpin-circuit") -> None:
    """A garage model whose latest evaluation is two laps of the reference driver."""
    new_model(name, track=track)
    folder = open_model(name)
    evaluate_model(folder, trials=2, driver=ReferenceRaceDriver(folder.track()))


def sentence(screen: CoachScreen) -> str:
    return str(screen.query_one("#coach-sentence", Static).render())


async def test_the_garage_coaches_a_models_evaluated_lap_sector_by_sector() -> None:
    evaluated_model("ada")
    app = create_app(start="garage")
    async with app.run_test(size=(80, 24)) as pilot:
        await settle(pilot)
        await pilot.press("o")
        screen = app.screen
        assert isinstance(screen, CoachScreen)
        await settle(pilot)
        assert screen.coaching is not None
        report = screen.coaching.report
        summary = " ".join(painted(screen.query_one("#coach-summary")).split())
        assert f"{report.seconds:.3f} s, {report.gap_words}" in summary
        table = screen.query_one("#coach-sectors", DataTable)
        assert table.row_count == len(report.sectors)
        worst = report.ranked()[0]
        assert table.get_row_at(0)[0].plain == worst.sector.name
        assert table.get_row_at(0)[1].plain == f"{worst.lost:+.2f} s"
        # The worst sector is chosen first: its sentence, and its name on the map.
        assert sentence(screen).startswith(f"{worst.sector.name}: ")
        assert worst.sector.name in painted(screen.query_one(CoachMap))
        assert "speed" in painted(screen.query_one("#coach-speed"))
        await pilot.press("down")
        second = report.ranked()[1]
        assert sentence(screen).startswith(f"{second.sector.name}: ")
        await pilot.press("escape")
        assert not isinstance(app.screen, CoachScreen)


async def test_a_model_without_an_evaluation_is_sent_to_evaluate_first() -> None:
    new_model("ada")
    app = create_app(start="garage")
    async with app.run_test(size=(80, 24)) as pilot:
        await settle(pilot)
        notes = Notifications(app)
        await pilot.press("o")
        assert not isinstance(app.screen, CoachScreen)
        assert "press t to train it first" in notes.text("warning")  # untrained: train first


async def test_a_coaching_that_fails_says_why_in_the_view() -> None:
    def fails() -> None:
        raise ValueError("the lap does not go round the whole track.")

    app: App[None] = App()
    async with app.run_test(size=(80, 24)) as pilot:
        screen = CoachScreen("ada", "latest evaluation", fails)  # type: ignore[arg-type]
        await app.push_screen(screen)
        await settle(pilot)
        shown = painted(screen.query_one("#coach-summary"))
        assert "The lap does not go round the whole track." in shown
        assert "Esc goes back" in shown


async def test_a_finished_race_coaches_its_best_lap() -> None:
    track = resolve_track("beginner-oval")
    race = RaceScreen(RaceSetup(track=track, rules=RaceRules(window_seconds=30.0), racer="cy"))
    app: App[None] = App()
    async with app.run_test(size=(80, 24)) as pilot:
        await app.push_screen(race)
        await worked_out(pilot, race)
        notes = Notifications(app)
        await pilot.press("o")  # not yet: the view has not shown the finish
        assert app.screen is race and "e shows its end" in notes.text("warning")
        await pilot.press("e")
        await pilot.pause()
        facts = " ".join(painted(race.query_one("#race-facts")).split())
        assert "o coaches its best lap" in facts
        await pilot.press("o")
        coach = app.screen
        assert isinstance(coach, CoachScreen)
        await settle(pilot)
        assert race.result is not None and race.result.best_lap is not None
        best = race.result.best_lap
        assert coach.coaching is not None
        assert coach.coaching.report.label == f"lap {best.number}"
        assert coach.coaching.report.seconds == best.time_seconds
        assert painted(coach.query_one("#coach-title")).startswith(
            f"Coach · cy on beginner-oval, lap {best.number}"
        )
