"""Issue 42, point 12 and the Nights screen at 60x20: what a host hesitated over is said
where they look (a model still training, the rules for a physical car, standings that
rank physical and simulated laps together), and who is physical stays on screen."""

from __future__ import annotations

from typing import Any

from textual.app import App, ComposeResult
from textual.widgets import DataTable, Input, Static

from league.nights import PHYSICAL_RULES_NOTE, SIMULATED_UNDER_PHYSICAL_NOTE
from league.opening import open_league
from racer_tui.app.application import create_app
from racer_tui.app.screens.nights import MIXED_STANDINGS_NOTE, AddEntrantDialog, NightsScreen
from tests.racer_tui.screens.test_night_projector import a_night_with_one_heat_raced, record_heat
from tests.racer_tui.screens.tui_helpers import painted, settle


class DialogApp(App[None]):
    def __init__(self, dialog: AddEntrantDialog) -> None:
        super().__init__()
        self.dialog = dialog

    def compose(self) -> ComposeResult:
        yield Static()

    def on_mount(self) -> None:
        self.push_screen(self.dialog)


def no_add(request: Any) -> str:
    return ""


async def test_the_entrant_dialog_warns_of_a_model_still_training_and_of_physical_rules() -> None:
    dialog = AddEntrantDialog(
        ["ada", "bob"], no_add, training=frozenset({"ada"}), physical_rules=False
    )
    app = DialogApp(dialog)
    async with app.run_test(size=(80, 24)) as pilot:
        await pilot.pause()
        model = dialog.query_one("#entrant-model", Input)
        note = dialog.query_one("#entrant-note", Static)
        model.value = "ada"
        await pilot.pause()
        assert "ada is still training" in painted(note)
        model.value = "bob"
        await pilot.pause()
        assert painted(note).strip() == ""
        model.value = "physical:blue car"
        await pilot.pause()
        assert " ".join(painted(note).split()).startswith(PHYSICAL_RULES_NOTE[:40])


async def test_the_entrant_dialog_notes_a_simulated_car_under_the_physical_rules() -> None:
    dialog = AddEntrantDialog(["ada"], no_add, training=frozenset(), physical_rules=True)
    app = DialogApp(dialog)
    async with app.run_test(size=(80, 24)) as pilot:
        await pilot.pause()
        model = dialog.query_one("#entrant-model", Input)
        note = dialog.query_one("#entrant-note", Static)
        model.value = "reference"
        await pilot.pause()
        said = " ".join(painted(note).split())
        assert said.startswith(SIMULATED_UNDER_PHYSICAL_NOTE[:40])
        for typed in ("phys", "physical", "physical:blue car"):  # on its way to a real car
            model.value = typed
            await pilot.pause()
            assert painted(note).strip() == "", typed


async def test_night_standings_say_when_they_rank_physical_and_simulated_laps_together() -> None:
    night = a_night_with_one_heat_raced()  # bob drives a physical car
    with open_league() as league:
        record_heat(league, night, 1)
        record_heat(league, night, 2)
    app = create_app(start="league")
    async with app.run_test(size=(60, 20)) as pilot:
        await settle(pilot)
        await pilot.press("n")
        await settle(pilot)
        screen = app.screen
        assert isinstance(screen, NightsScreen)
        note = screen.query_one("#standings-note", Static)
        assert not note.has_class("-hidden")
        assert MIXED_STANDINGS_NOTE[1:] in " ".join(str(note.render()).split())
        heats = screen.query_one("#heats", DataTable)
        labels = [str(column.label) for column in heats.columns.values()]
        assert "car" in labels  # who is physical, at 60 columns too
        assert "phys…" in painted(heats)  # the kind first, the car's own end kept


async def test_standings_with_equal_scores_say_how_they_are_placed() -> None:
    """The host walk: two racers with the same figures had different places and points,
    with nothing saying why."""
    from league.nights import add_entrant, draw_heats, heats, new_night
    from league.races import record_race
    from racer_tui.app.screens.nights import TIE_NOTE
    from sim.foundation.home import data_home
    from sim.race.rules import RaceRules
    from sim.tracks.catalog import resolve_track
    from tests.league.helpers import race_result

    data_home().mkdir(parents=True, exist_ok=True)
    rules = RaceRules(window_seconds=60.0)
    with open_league() as league:
        night = new_night(league, resolve_track("beginner-oval"), rules=rules, name="tied")
        for racer in ("ana", "eve"):
            add_entrant(league, night, racer, "reference")
        draw_heats(league, night, seed=2)
        for heat in heats(league, night):
            result = race_result(heat.entrant.racer, [10.0], rules=rules)
            record_race(league, result, night.id, heat_id=heat.id)
    app = create_app(start="league")
    async with app.run_test(size=(80, 24)) as pilot:
        await settle(pilot)
        await pilot.press("n")
        await settle(pilot)
        screen = app.screen
        assert isinstance(screen, NightsScreen)
        note = screen.query_one("#standings-note", Static)
        assert not note.has_class("-hidden")
        assert TIE_NOTE[:40] in " ".join(str(note.render()).split())
