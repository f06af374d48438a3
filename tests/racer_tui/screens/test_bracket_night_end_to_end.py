"""Issue 46's bracket night, whole, without leaving the app: four entrants (a garage model,
the same model as a bundle file, `reference`, and the garage model again) qualify in
time-trial heats, the standings seed a knock-out, its three matches are raced live to the
final, the projector shows the bracket at every step, and closing the night gives season
points in the bracket's order.

The model is `tests/racer_tui/data/vector-lapper.racer-bundle`: a vector model racer-tui
trained for 3 minutes on reinvent_base (issue 46's opponent benchmark, seed 1, "alone"),
kept because an untrained policy sets no lap and so qualifies for nothing."""

from __future__ import annotations

from pathlib import Path
from typing import Any

from textual.pilot import Pilot
from textual.widgets import Input, Select

from league.bracket_records import read_bracket
from league.nights import list_nights
from league.opening import open_league
from league.seasons import new_season
from racer_tui.app.application import create_app
from racer_tui.app.screens.dialogs import ConfirmDialog
from racer_tui.app.screens.head_to_head_screen import HeadToHeadScreen
from racer_tui.app.screens.night_bracket import DrawBracketDialog
from racer_tui.app.screens.nights import AddEntrantDialog, NewNightDialog, NightsScreen
from racer_tui.app.screens.race_screen import RECORDED, RaceScreen
from sim.foundation.home import data_home
from sim.garage.importing import import_model
from tests.racer_tui.screens.test_night_end_to_end import projector_shows
from tests.racer_tui.screens.test_nights import table_rows, the_nights_screen
from tests.racer_tui.screens.tui_helpers import Notifications, settle, wait_for

LAPPER = Path(__file__).parent.parent / "data" / "vector-lapper.racer-bundle"


async def open_the_night(pilot: Pilot[Any], rules: Path) -> NightsScreen:
    nights = await the_nights_screen(pilot)
    await pilot.press("o")
    await settle(pilot)
    dialog = pilot.app.screen
    assert isinstance(dialog, NewNightDialog)
    dialog.query_one("#night-track", Select).value = "reinvent_base"
    dialog.query_one("#night-name", Input).value = "Knockout"
    dialog.query_one("#night-rules", Input).value = str(rules)
    await pilot.press("ctrl+s")
    await wait_for(pilot, lambda: pilot.app.screen is nights)
    return nights


async def race_a_heat_to_its_finish(pilot: Pilot[Any], nights: NightsScreen) -> None:
    await pilot.press("r")
    await wait_for(pilot, lambda: isinstance(pilot.app.screen, RaceScreen))
    view = pilot.app.screen
    assert isinstance(view, RaceScreen)
    await wait_for(pilot, lambda: bool(view.ticks))  # racing: e has a race to jump through
    await pilot.press("e", "y")  # the finish at once, asked
    await wait_for(pilot, lambda: view.recording == RECORDED)  # on the night as it finished
    await pilot.press("escape")
    await wait_for(pilot, lambda: pilot.app.screen is nights)


async def race_a_match_to_its_finish(pilot: Pilot[Any], nights: NightsScreen) -> None:
    await pilot.press("r")
    await wait_for(pilot, lambda: isinstance(pilot.app.screen, HeadToHeadScreen))
    view = pilot.app.screen
    assert isinstance(view, HeadToHeadScreen)
    await wait_for(pilot, lambda: bool(view.ticks))
    await pilot.press("e")
    assert isinstance(pilot.app.screen, ConfirmDialog)
    await pilot.press("y")
    await wait_for(pilot, lambda: view.at_end and view.result is not None)
    await pilot.press("escape")
    await wait_for(pilot, lambda: pilot.app.screen is nights)


async def test_a_bracket_night_of_four_from_qualifying_to_season_points(tmp_path: Path) -> None:
    data_home().mkdir(parents=True, exist_ok=True)
    import_model(LAPPER, name="lapper")
    rules = tmp_path / "night.yaml"
    rules.write_text("window_seconds: 20\npenalty_seconds: 2\nmax_offtracks_per_lap: 3\n")
    with open_league() as league:
        new_season(league, "spring", points=(10, 6, 4, 2))
    app = create_app(start="league")
    async with app.run_test(size=(80, 24)) as pilot:
        notes = Notifications(app)
        nights = await open_the_night(pilot, rules)
        entries = (("ada", "lapper"), ("bob", str(LAPPER)), ("cy", "reference"))
        for racer, car in (*entries, ("dee", "lapper")):
            await pilot.press("a")
            assert isinstance(app.screen, AddEntrantDialog)
            await pilot.press(*racer, "enter", *car, "enter")
            await settle(pilot)
        assert [row[1] for row in table_rows(nights, "#heats")] == ["ada", "bob", "cy", "dee"]
        await pilot.press("d")
        await settle(pilot)
        for _ in range(4):
            await race_a_heat_to_its_finish(pilot, nights)
        assert "4 heats raced" in await projector_shows(pilot, nights)

        await pilot.press("k")
        dialog = app.screen
        assert isinstance(dialog, DrawBracketDialog)
        dialog.query_one("#bracket-laps", Input).value = "1"
        await pilot.press("ctrl+s")
        await wait_for(pilot, lambda: "Drew the bracket of 4 racers" in notes.text())
        with open_league() as league:
            (night,) = list_nights(league)
            drawn = read_bracket(league, night.id)
        assert drawn is not None and len(drawn.bracket.seeds) == 4
        for match in ("W1-1", "W1-2", "W2-1"):
            shown = await projector_shows(pilot, nights)
            assert "bracket" in shown.lower() and match in shown  # the next match, named
            await race_a_match_to_its_finish(pilot, nights)
            await wait_for(pilot, lambda match=match: f"Recorded {match}:" in notes.text())
        shown = await projector_shows(pilot, nights)
        assert "Champion" in shown

        await pilot.press("c")
        assert isinstance(app.screen, ConfirmDialog)
        await pilot.press("y")
        # Closed: the season's standings come under the bracket (scrolled out of sight
        # at 80x24, so read from the screen's tables, not its painted lines).
        await wait_for(pilot, lambda: bool(table_rows(nights, "#season")))
        season = {row[1]: int(row[2]) for row in table_rows(nights, "#season")}
    with open_league() as league:
        decided = read_bracket(league, night.id)
    assert decided is not None
    order = decided.final_order()
    assert order is not None
    champion, runner_up = (decided.racers[entrant] for entrant in order[:2])
    assert season[champion] == 10 and season[runner_up] == 6  # the bracket's order
    assert sorted(season.values()) == [2, 4, 6, 10]
