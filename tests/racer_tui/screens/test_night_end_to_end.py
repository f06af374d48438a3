"""The league-night issue's whole evening, as a host who has never seen racer-tui runs it
at 80x24 without leaving the app: open a night in a season, enter a garage model, a
model bundle and a physical car, draw, race the two simulated heats live and time the
physical car's with the keyboard (resets, a lap over the limit), close the night, and see
the season's points; the night's projector is checked at every step, and a heat in
progress reaches it through its live file."""

from __future__ import annotations

from pathlib import Path
from typing import Any

from textual.pilot import Pilot
from textual.widgets import Input, Select

from league.live_heat import live_heat_path, read_live_heat
from league.nights import list_nights, standings
from league.opening import open_league
from league.races import race_result
from league.seasons import new_season
from league.store import default_db_path
from racer_tui.app.application import create_app
from racer_tui.app.screens.dialogs import ConfirmDialog
from racer_tui.app.screens.night_projector import NightProjectorScreen
from racer_tui.app.screens.nights import AddEntrantDialog, NewNightDialog, NightsScreen
from racer_tui.app.screens.race_screen import RaceScreen
from racer_tui.app.screens.timekeeper import TimekeeperScreen
from sim.foundation.home import data_home
from sim.physics.labels import PHYSICAL
from tests.racer_tui.screens.test_nights import table_rows, the_nights_screen
from tests.racer_tui.screens.test_timekeeper_screen import Stopwatch
from tests.racer_tui.screens.tui_helpers import (
    Notifications,
    painted,
    settle,
    trained_model,
    wait_for,
)


async def projector_shows(pilot: Pilot[Any], nights: NightsScreen) -> str:
    """Open the night's projector (p), read what it shows, and come back (q, y: a kiosk
    asks before it lets anyone leave)."""
    await pilot.press("p")
    await settle(pilot)
    projector = pilot.app.screen
    assert isinstance(projector, NightProjectorScreen)
    shown = "\n".join(
        painted(projector.query_one(selector))
        for selector in ("#np-title", "#np-heat", "#np-standings", "#np-hint")
    )
    await pilot.press("q", "y")
    await settle(pilot)
    assert pilot.app.screen is nights
    return shown


async def time_the_physical_car(pilot: Pilot[Any], keeper: TimekeeperScreen) -> None:
    """A counting lap of 10 s with one reset, then a lap with four resets (over the
    limit of three), then the end of the race; the projector sees it running."""
    watch = Stopwatch()
    keeper.clock = watch
    await pilot.press("space")
    watch.now += 4.0
    await pilot.press("r")
    watch.now += 6.0
    await pilot.press("l")
    for _ in range(4):
        watch.now += 1.0
        await pilot.press("r")
    setup = keeper.setup
    assert setup.live is not None
    night_id, path = setup.live.heat.night_id, setup.live.path

    def told() -> tuple[str, int, int] | None:
        live = read_live_heat(path, night_id)
        return None if live is None else (live.state, live.lap, live.offtracks)

    await wait_for(pilot, lambda: told() == ("running", 2, 4))  # the clocks' next tick
    watch.now += 5.0
    await pilot.press("l")
    await pilot.press("e")
    assert isinstance(pilot.app.screen, ConfirmDialog)
    await pilot.press("y")
    await pilot.pause()
    await pilot.press("escape")  # records the heat
    await settle(pilot)


async def test_a_new_host_runs_a_mixed_night_from_opening_to_season_points(
    tmp_path: Path,
) -> None:
    data_home().mkdir(parents=True, exist_ok=True)
    from sim.garage.bundle import export_bundle

    trained_model("quick")
    bundle = export_bundle(trained_model("boxed"), tmp_path / "boxed.racer-bundle")
    rules = tmp_path / "night.yaml"
    rules.write_text("window_seconds: 30\npenalty_seconds: 2\nmax_offtracks_per_lap: 3\n")
    with open_league() as league:
        new_season(league, "spring")

    app = create_app(start="league")
    async with app.run_test(size=(80, 24)) as pilot:
        notes = Notifications(app)
        nights = await the_nights_screen(pilot)
        await pilot.press("o")
        await settle(pilot)
        dialog = app.screen
        assert isinstance(dialog, NewNightDialog)
        dialog.query_one("#night-track", Select).value = "beginner-oval"
        season = dialog.query_one("#night-season", Select)
        labels = {value: label for label, value in season._options}
        assert labels[season.value] == "spring"  # the league's current season, by default
        await pilot.press(*"friday", "enter")  # Enter moves on: it does not open the night
        assert app.screen is dialog and dialog.focused is dialog.query_one("#night-date")
        await pilot.press("enter", "tab")  # today; past the rules preset to a rules file
        assert dialog.focused is dialog.query_one("#night-rules")
        bad = tmp_path / "bad.yaml"
        bad.write_text("window_seconds: [\n")
        await pilot.press(*str(bad), "ctrl+s")  # a broken file is said here, nothing lost
        assert app.screen is dialog
        assert "is not valid YAML" in painted(dialog.query_one("#problem"))
        assert dialog.query_one("#night-name", Input).value == "friday"
        dialog.query_one("#night-rules", Input).value = str(rules)
        await pilot.press("ctrl+s")
        await settle(pilot)
        assert app.screen is nights
        shown = " ".join(painted(nights.query_one("#night-rules")).split())
        assert "friday" in shown and "0:30 window" in shown and "season spring" in shown

        # A name that looks like markup stays literal everywhere.
        entries = (("ada", "quick"), ("[b]bob[/b]", str(bundle)), ("carol", "physical:blue"))
        for racer, car in entries:
            await pilot.press("a")
            assert isinstance(app.screen, AddEntrantDialog)
            await pilot.press(*racer, "enter", *car, "enter")
            await settle(pilot)
        assert [row[1] for row in table_rows(nights, "#heats")] == ["ada", "[b]bob[/b]", "carol"]
        assert "3 entered" in await projector_shows(pilot, nights)

        await pilot.press("d")
        await settle(pilot)
        assert "Next up: heat 1 of 3" in await projector_shows(pilot, nights)

        with open_league() as league:
            (night,) = list_nights(league)
        live_file = live_heat_path(default_db_path(), night.id)
        for number in range(1, 4):
            await pilot.press("r")
            await settle(pilot)
            heat = app.screen
            if isinstance(heat, TimekeeperScreen):
                await time_the_physical_car(pilot, heat)
            else:
                assert isinstance(heat, RaceScreen)
                await wait_for(pilot, lambda: read_live_heat(live_file, night.id) is not None)
                await pilot.press("e", "y", "escape")  # the finish at once, asked
                await settle(pilot)
            assert app.screen is nights
            assert not live_file.exists()  # the heat is over: the projector shows none
            shown = await projector_shows(pilot, nights)
            assert (f"Next up: heat {number + 1} of 3" in shown) == (number < 3)
        assert "Recorded carol's heat: best lap 12.000 s." in notes.text()
        assert "blue" in shown and "3 heats raced" in shown

        await pilot.press("c")
        assert isinstance(app.screen, ConfirmDialog)
        await pilot.press("y")
        await settle(pilot)
        assert "Season standings: spring" in painted(nights.query_one("#season-title"))
        season = {row[1]: row[2] for row in table_rows(nights, "#season")}
        assert set(season) == {"ada", "[b]bob[/b]", "carol"}
        assert "[b]bob[/b]" in painted(nights.query_one("#season"))
        # The night's own final standings stay on screen above the season's.
        assert "Standings (final, with points)" in painted(nights.query_one("#standings-title"))
        tonight = {row[1]: row[-1] for row in table_rows(nights, "#standings")}
        assert tonight == season  # a season's first night: its points are the season's
        await pilot.press("r")  # a closed night takes no more heats
        await settle(pilot)
        assert "is closed" in notes.text("warning")
        shown = await projector_shows(pilot, nights)
        assert "final standings" in shown and "The night is over" in shown
        assert "updates itself" not in shown and "the standings are final" in shown

        await pilot.press("x")  # the final standings with points, for the league's site
        app.screen.query_one("#answer", Input).value = str(tmp_path / "friday.md")
        await pilot.press("enter")
        await settle(pilot)
        assert app.screen is nights
    exported = (tmp_path / "friday.md").read_text()
    assert exported.startswith("# friday: final standings")
    assert all(f"| {racer} |" in exported for racer in ("ada", "\\[b\\]bob\\[/b\\]", "carol"))

    with open_league() as league:
        (night,) = list_nights(league)
        table = {s.entry.racer: s for s in standings(league, night)}
        carol = race_result(league, table["carol"].entry.record_id)
    assert carol.physics == PHYSICAL and carol.model_name == "blue"
    assert [(lap.raw_seconds, lap.offtracks, lap.valid) for lap in carol.laps] == [
        (10.0, 1, True),
        (9.0, 4, False),
    ]
    # Ranked once, all three together; points as the season counts them.
    placed = sorted((s.position, s.points) for s in table.values() if s.position is not None)
    assert [position for position, _ in placed] == list(range(1, len(placed) + 1))
    assert int(season["carol"]) == table["carol"].points > 0
