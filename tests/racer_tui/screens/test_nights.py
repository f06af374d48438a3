"""A whole league night from the app: open it with short-window rules, enter two racers
with the reference driver, draw, run both heats live, close it, see the season points."""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path
from typing import Any

from textual.pilot import Pilot
from textual.screen import Screen
from textual.widgets import DataTable, Input, Select, Static

from league.nights import add_entrant, draw_heats, list_nights, new_night, standings
from league.opening import open_league
from racer_tui.app.application import create_app
from racer_tui.app.screens.dialogs import ConfirmDialog
from racer_tui.app.screens.nights import AddEntrantDialog, NightsScreen
from sim.foundation.home import data_home
from sim.race.rules import RankingMethod, preset_rules
from sim.tracks.catalog import resolve_track
from tests.racer_tui.screens.tui_helpers import Notifications, painted, settle, wait_for


async def the_nights_screen(pilot: Pilot[Any]) -> NightsScreen:
    """From the League section (the app started there), the Nights screen (n)."""
    await settle(pilot)
    await pilot.press("n")
    await settle(pilot)
    nights = pilot.app.screen
    assert isinstance(nights, NightsScreen)
    return nights


def table_rows(screen: Screen[Any], table_id: str) -> list[list[str]]:
    table = screen.query_one(table_id, DataTable)
    return [[str(cell) for cell in table.get_row_at(i)] for i in range(table.row_count)]


def test_a_heat_races_against_the_nights_leader_so_far() -> None:
    """The race view's setup for a heat: the night's rules and the heat's seed, and once a
    heat has a counting lap, its best lap as the ghost and its score as the gap to beat.
    (The whole night from the app is tests/racer_tui/app/screens/test_night_end_to_end.py.)"""
    from league.nights import run_heats
    from racer_tui.app.screens.nights import heat_setup
    from racer_tui.app.screens.race_screen import RaceSetup
    from sim.race.rules import RaceRules
    from sim.training.drivers import resolve_driver

    data_home().mkdir(parents=True, exist_ok=True)
    oval = resolve_track("beginner-oval")
    rules = RaceRules(window_seconds=12.0)
    with open_league() as league:
        night = new_night(league, oval, rules=rules, name="friday")
        for racer in ("ada", "bob"):
            add_entrant(league, night, racer, "reference")
        first, second = draw_heats(league, night, seed=2)
        opening = heat_setup(league, night, first, oval)
        assert isinstance(opening, RaceSetup)
        assert opening.rules == rules and opening.seed == first.seed
        assert opening.ghost is None and opening.leader_seconds is None
        run_heats(league, night, oval, resolve_driver, limit=1)
        (leader,) = standings(league, night)
        later = heat_setup(league, night, second, oval)
    assert isinstance(later, RaceSetup)
    assert later.ghost is not None and later.leader_seconds == leader.entry.score
    # The gap names whose score it is to: the night's leader on this heat's own board.
    assert later.leader_name == leader.entry.display_name
    assert later.title.startswith("Heat 2: ")


def test_a_simulated_heat_never_races_a_hand_timed_lap() -> None:
    """The host walk: a physical car's 6.521 s, timed by hand, became the next simulated
    heat's gap (+4.029 s): each heat's ghost and gap are its own board's leader."""
    from league.races import record_race
    from racer_tui.app.screens.nights import heat_setup
    from racer_tui.app.screens.race_screen import RaceSetup
    from sim.physics.labels import PHYSICAL
    from tests.league.helpers import race_result

    data_home().mkdir(parents=True, exist_ok=True)
    oval = resolve_track("beginner-oval")
    with open_league() as league:
        night = new_night(league, oval, name="friday")
        add_entrant(league, night, "zed", "physical")
        add_entrant(league, night, "ada", "reference")
        heats = draw_heats(league, night, seed=2)
        zed = next(heat for heat in heats if heat.entrant.racer == "zed")
        ada = next(heat for heat in heats if heat.entrant.racer == "ada")
        hand_timed = replace(race_result("zed", [6.5], track=oval), physics=PHYSICAL)
        record_race(
            league, replace(hand_timed, model_name="physical car"), night.id, heat_id=zed.id
        )
        assert standings(league, night)[0].entry.racer == "zed"
        setup = heat_setup(league, night, ada, oval)
    assert isinstance(setup, RaceSetup)
    assert setup.ghost is None and setup.leader_seconds is None


async def test_running_a_heat_before_the_draw_says_what_to_do() -> None:
    app = create_app(start="league")
    async with app.run_test(size=(100, 30)) as pilot:
        notes = Notifications(app)
        await settle(pilot)
        await pilot.press("n")
        await settle(pilot)
        await pilot.press("r")
        assert "Open a night first" in notes.text("warning")
        await pilot.press("o")
        await settle(pilot)
        await pilot.press("ctrl+s")  # the defaults: league rules, first track
        await settle(pilot)
        await pilot.press("r")
        await settle(pilot)
        assert "no drawn heats waiting" in notes.text("error")
        await pilot.press("a", *"ada", "enter", *"no-such-model", "enter")
        await settle(pilot)
        # Said in the dialog, which stays open with what was typed.
        dialog = app.screen
        assert isinstance(dialog, AddEntrantDialog)
        said = " ".join(painted(dialog.query_one("#problem")).split())
        assert "There is no model named 'no-such-model'" in said
        assert "the Garage (1) lists your models, and n there creates one" in said
        assert "racer-tui" not in said  # the command line's words stay there
        assert dialog.query_one("#entrant-racer", Input).value == "ada"
        model = dialog.query_one("#entrant-model", Input)
        model.value = ""
        await pilot.press(*"refer")
        await pilot.pause()
        await pilot.press("right")  # → completes a name...
        assert model.value == "reference"
        model.value = ""
        await pilot.press(*str(data_home())[:-1])
        await pilot.pause()
        await pilot.press("right")  # ...and a path, for a bundle file
        assert model.value == str(data_home()) + "/"
        model.value = "reference"
        await pilot.press("enter")
        await settle(pilot)
        assert isinstance(app.screen, NightsScreen) and "Entered ada with reference." in (
            notes.text()
        )


async def test_drawing_with_nobody_waiting_names_the_key_not_a_command() -> None:
    app = create_app(start="league")
    async with app.run_test(size=(120, 40)) as pilot:
        notes = Notifications(app)
        await settle(pilot)
        await pilot.press("n")
        await settle(pilot)
        screen = app.screen
        assert isinstance(screen, NightsScreen)
        with open_league() as league:
            new_night(league, resolve_track("beginner-oval"), name="friday")
        screen.reload()
        await settle(pilot)
        await pilot.press("d")  # nobody has been added yet
        await settle(pilot)
        errors = notes.text("error")
        assert "no entrants waiting to race; add one (a), then draw (d)" in errors
        assert "racer-tui" not in errors


async def test_the_open_night_dialog_takes_a_preset_and_sets_the_ranking_over_it() -> None:
    app = create_app(start="league")
    async with app.run_test(size=(80, 24)) as pilot:
        nights = await the_nights_screen(pilot)
        await pilot.press("o")
        await settle(pilot)
        app.screen.query_one("#night-preset", Select).value = "physical"
        app.screen.query_one("#night-ranking", Select).value = RankingMethod.BEST_AVERAGE
        await pilot.press(*"sunday", "ctrl+s")
        await settle(pilot)
        assert app.screen is nights
        shown = " ".join(painted(nights.query_one("#night-rules")).split())  # wrapped at 80
        assert "ranked by best average of 3 consecutive laps" in shown
        assert "no time added per off-track" in shown  # the physical cars' preset
    with open_league() as league:
        (night,) = list_nights(league)
    assert (night.name, night.rules.ranking) == ("sunday", RankingMethod.BEST_AVERAGE)
    assert night.rules == replace(preset_rules("physical"), ranking=RankingMethod.BEST_AVERAGE)


async def test_the_open_night_dialog_sets_a_date_and_a_lap_count_race() -> None:
    app = create_app(start="league")
    async with app.run_test(size=(80, 24)) as pilot:
        nights = await the_nights_screen(pilot)
        await pilot.press("o")
        await settle(pilot)
        dialog = app.screen
        dialog.query_one("#night-ranking", Select).value = RankingMethod.TOTAL_TIME
        await pilot.press(*"sprint", "enter", *"2027-01-08", "enter")
        assert dialog.focused is dialog.query_one("#night-preset", Select)
        await pilot.press("tab", "tab", *"2x", "ctrl+s")  # past the rules file, to the laps
        await settle(pilot)
        assert app.screen is dialog  # total time of 3 laps cannot be had from 2
        problem = " ".join(painted(dialog.query_one("#problem")).split())
        assert "A race of 2 laps cannot be ranked over 3 laps: give at least 3 laps" in problem
        assert dialog.query_one("#night-name", Input).value == "sprint"  # nothing lost
        await pilot.press("backspace", "3", "ctrl+s")
        await settle(pilot)
        assert app.screen is nights
        shown = " ".join(painted(nights.query_one("#night-rules")).split())
        assert "race of 3 laps within 4:00" in shown and "reinvent_base, 2027-01-08" in shown
    with open_league() as league:
        (night,) = list_nights(league)
    assert (night.rules.lap_count, night.rules.ranking) == (3, RankingMethod.TOTAL_TIME)
    assert night.held_on == "2027-01-08"


async def test_closing_a_night_drawn_elsewhere_names_the_keys_and_shows_the_heats() -> None:
    data_home().mkdir(parents=True, exist_ok=True)
    with open_league() as league:
        night = new_night(league, resolve_track("beginner-oval"), name="friday")
        for racer in ("ada", "bob"):
            add_entrant(league, night, racer, "reference")
    app = create_app(start="league")
    async with app.run_test(size=(120, 40)) as pilot:
        notes = Notifications(app)
        screen = await the_nights_screen(pilot)
        with open_league() as league:  # the command line draws while the app shows the night
            draw_heats(league, night, seed=1)
        await pilot.press("c")
        assert isinstance(app.screen, ConfirmDialog)
        # A night of no season: closing adds no points anywhere, and says none.
        asked = " ".join(painted(app.screen).split())
        assert "makes the standings final" in asked and "season" not in asked
        await pilot.press("y")
        await settle(pilot)
        errors = notes.text("error")
        assert "still has 2 heats to run; run them (r), or press c again to close" in errors
        assert "racer-tui" not in errors and "--force" not in errors
        assert [row[3] for row in table_rows(screen, "#heats")] == ["next (r)", "waiting"]
        await pilot.press("c")  # as the error says: the dialog now knows of the heats
        dialog = app.screen
        assert isinstance(dialog, ConfirmDialog)
        assert "2 heats have not raced" in painted(dialog)
        await pilot.press("y")
        await settle(pilot)
    with open_league() as league:
        assert list_nights(league)[0].closed


async def test_what_the_command_line_changes_shows_without_a_key() -> None:
    """A host who draws or opens a night with `racer-tui night ...` in another terminal sees
    it land here within the screen's poll, the cursors where they were."""
    data_home().mkdir(parents=True, exist_ok=True)
    with open_league() as league:
        night = new_night(league, resolve_track("beginner-oval"), name="friday")
        for racer in ("ada", "bob", "cy"):
            add_entrant(league, night, racer, "reference")
    app = create_app(start="league")
    async with app.run_test(size=(120, 40)) as pilot:
        screen = await the_nights_screen(pilot)
        await pilot.press("tab", "down")  # the heats table, on bob
        await settle(pilot)
        assert table_rows(screen, "#heats")[1][1] == "bob"
        with open_league() as league:
            draw_heats(league, night, seed=1)
            new_night(league, resolve_track("beginner-oval"), name="saturday")
        await wait_for(pilot, lambda: len(table_rows(screen, "#nights")) == 2)
        await wait_for(pilot, lambda: table_rows(screen, "#heats")[0][0] == "1")
        assert [row[0] for row in table_rows(screen, "#nights")] == ["saturday", "friday"]
        assert screen.state is not None and screen.state.night.name == "friday"
        heats = table_rows(screen, "#heats")
        assert [row[0] for row in heats] == ["1", "2", "3"]
        assert heats[screen.query_one("#heats", DataTable).cursor_row][1] == "bob"


async def test_an_entrant_folder_that_is_not_a_model_names_the_garages_key(
    tmp_path: Path,
) -> None:
    stranger = tmp_path / "download"
    stranger.mkdir()
    with open_league() as league:
        new_night(league, resolve_track("beginner-oval"), name="friday")
    app = create_app(start="league")
    async with app.run_test(size=(120, 40)) as pilot:
        notes = Notifications(app)
        await settle(pilot)
        await pilot.press("n")
        await settle(pilot)
        await pilot.press("a", *"ada", "enter", *str(stranger), "enter")
        await settle(pilot)
        assert not notes.text("error")  # said in the dialog, where it was typed
        errors = str(app.screen.query_one("#problem", Static).content)
        assert f"so {stranger} is not a model folder" in errors
        assert "give a garage model's name, or import the folder in the Garage (i there)" in errors
        assert "racer-tui" not in errors


async def test_the_night_shown_is_the_one_under_the_cursor_after_it_changes() -> None:
    data_home().mkdir(parents=True, exist_ok=True)
    with open_league() as league:
        for name in ("thursday", "friday", "saturday"):  # the list shows the newest first
            new_night(league, resolve_track("beginner-oval"), name=name)
    app = create_app(start="league")
    async with app.run_test(size=(80, 24)) as pilot:
        nights = await the_nights_screen(pilot)
        await pilot.press("down", "down")  # thursday, the oldest
        await settle(pilot)
        await pilot.press("c", "y")  # close it: the list is read again
        await settle(pilot)
        rows = table_rows(nights, "#nights")
        assert [(row[0], row[2]) for row in rows] == [
            ("saturday", "open"),
            ("friday", "open"),
            ("thursday", "closed"),
        ]
        assert nights.query_one("#nights", DataTable).cursor_row == 2
        assert nights.state is not None and nights.state.night.name == "thursday"
        assert painted(nights.query_one("#night-rules")).startswith("thursday")


async def test_every_raced_heat_shows_its_own_best_lap() -> None:
    from league.nights import run_heats
    from sim.race.rules import RaceRules
    from sim.training.drivers import resolve_driver
    from tests.racer_tui.screens.tui_helpers import trained_model

    trained_model("wobbly")  # untrained weights: it may count no lap at all
    oval = resolve_track("beginner-oval")
    with open_league() as league:
        night = new_night(league, oval, rules=RaceRules(window_seconds=12.0), name="friday")
        add_entrant(league, night, "ada", "reference")
        add_entrant(league, night, "ada", "wobbly")  # the same racer's second car
        draw_heats(league, night, seed=3)
        run_heats(league, night, oval, resolve_driver)
    app = create_app(start="league")
    async with app.run_test(size=(80, 24)) as pilot:
        nights = await the_nights_screen(pilot)
        results = {row[2]: row[3] for row in table_rows(nights, "#heats")}
    assert results["reference"].startswith("best ")
    assert results["wobbly"] == "no lap counted" or results["wobbly"].startswith("best ")
    assert results["wobbly"] != results["reference"]  # not the racer's best race twice


async def test_a_host_withdraws_an_entrant_moves_a_heat_and_deletes_an_unheld_night() -> None:
    data_home().mkdir(parents=True, exist_ok=True)
    with open_league() as league:
        night = new_night(league, resolve_track("beginner-oval"), name="friday")
        for racer in ("ada", "bob", "cy"):
            add_entrant(league, night, racer, "reference")
    app = create_app(start="league")
    async with app.run_test(size=(80, 24)) as pilot:
        notes = Notifications(app)
        nights = await the_nights_screen(pilot)
        await pilot.press("w")  # the first press goes to the heats list
        assert nights.focused is nights.query_one("#heats", DataTable)
        await pilot.press("down", "w")
        assert isinstance(app.screen, ConfirmDialog)
        await pilot.press("y")
        await settle(pilot)
        assert "Withdrew bob." in notes.text()
        assert [row[1] for row in table_rows(nights, "#heats")] == ["ada", "cy"]

        await pilot.press("d")
        await settle(pilot)
        drawn = [row[1] for row in table_rows(nights, "#heats")]
        nights.query_one("#heats", DataTable).move_cursor(row=1)
        await pilot.press("left_square_bracket")  # the second heat goes first
        await settle(pilot)
        assert [row[1] for row in table_rows(nights, "#heats")] == drawn[::-1]
        assert nights.query_one("#heats", DataTable).cursor_row == 0  # it follows the heat

        await pilot.press("delete")
        assert isinstance(app.screen, ConfirmDialog)
        await pilot.press("y")
        await settle(pilot)
        assert "Deleted friday." in notes.text()
        assert "No league nights yet" in painted(nights.query_one("#night-rules"))
        # Only that: not the deleted night's headings over empty tables (the host walk).
        for part in ("#heats", "#standings", "#standings-title"):
            assert not nights.query_one(part).display, part
    with open_league() as league:
        assert list_nights(league) == []


async def test_a_heat_is_recorded_as_its_finish_shows_and_never_left_silently() -> None:
    """A host who leaves a simulated heat before its finish is asked, and the heat stays
    to run again; r mid-heat does not restart it; the finish on screen records the heat at
    once (the projector and `night show` see it before anyone presses Esc), and leaving
    after it records nothing twice."""
    from league.night_state import read_night
    from racer_tui.app.screens.race_screen import RECORDED, RaceScreen

    data_home().mkdir(parents=True, exist_ok=True)
    with open_league() as league:
        night = new_night(
            league, resolve_track("beginner-oval"), rules=replace(preset_rules("league"),
            window_seconds=20.0), name="friday",
        )  # fmt: skip
        add_entrant(league, night, "ada", "reference")
        draw_heats(league, night, seed=1)

    def heats_raced() -> int:
        with open_league() as league:
            return sum(1 for heat in read_night(league, night.id).heats if heat.race_id)

    app = create_app(start="league")
    async with app.run_test(size=(100, 30)) as pilot:
        notes = Notifications(app)
        nights = await the_nights_screen(pilot)
        await pilot.press("r")
        await settle(pilot)
        heat = app.screen
        assert isinstance(heat, RaceScreen)
        await pilot.press("r")  # replay before the finish: refused, the heat runs on
        assert "has not finished yet" in notes.text("warning")
        await pilot.press("escape")
        assert isinstance(app.screen, ConfirmDialog)  # asked, never silent
        await pilot.press("n")
        assert app.screen is heat
        await pilot.press("escape", "y")  # left unrecorded: still waiting
        await settle(pilot)
        assert app.screen is nights and heats_raced() == 0
        assert "press r to run it again" in notes.text("warning")

        await pilot.press("r")
        await settle(pilot)
        heat = app.screen
        assert isinstance(heat, RaceScreen)
        await pilot.press("e")  # the room is watching: asked before its show is cut
        assert isinstance(app.screen, ConfirmDialog)
        await pilot.press("n")  # kept watching: nothing jumped
        assert app.screen is heat and not heat.clock.to_end
        await pilot.press("e", "y")  # its finish at once: recorded while the view stays
        await settle(pilot)
        assert app.screen is heat and heats_raced() == 1
        assert RECORDED in painted(heat.query_one("#race-facts"))
        await pilot.press("escape")
        await settle(pilot)
        assert app.screen is nights and heats_raced() == 1
        assert notes.text().count("Recorded ada's heat") == 1


async def test_a_nights_date_is_kept_as_typed_and_said_back_when_wrong() -> None:
    """Nothing typed into the date is dropped: a date with slashes opens the night on that
    day, and a date that is not one is said back as the host wrote it."""
    from racer_tui.app.screens.nights import NewNightDialog

    app = create_app(start="league")
    async with app.run_test(size=(80, 24)) as pilot:
        await the_nights_screen(pilot)
        await pilot.press("o")
        await settle(pilot)
        dialog = app.screen
        assert isinstance(dialog, NewNightDialog)
        await pilot.press(*"friday", "enter", *"27 Nov")
        assert dialog.query_one("#night-date", Input).value == "27 Nov"
        await pilot.press("ctrl+s")
        assert app.screen is dialog
        assert "'27 Nov' is not a night's date" in painted(dialog.query_one("#problem"))
        date_field = dialog.query_one("#night-date", Input)
        date_field.value = ""
        await pilot.press(*"2026/11/27", "ctrl+s")
        await settle(pilot)
        assert isinstance(app.screen, NightsScreen)
    with open_league() as league:
        (night,) = list_nights(league)
    assert (night.name, night.held_on) == ("friday", "2026-11-27")


async def test_closing_a_night_that_counts_only_replayed_results_races_its_heats_again() -> None:
    from league.nights import run_heats
    from sim.race.rules import RaceRules, Verification
    from sim.training.drivers import resolve_driver

    oval = resolve_track("beginner-oval")
    rules = RaceRules(window_seconds=12.0, verification=Verification.REPLAYED)
    with open_league() as league:
        night = new_night(league, oval, rules=rules, name="friday")
        add_entrant(league, night, "ada", "reference")
        draw_heats(league, night, seed=3)
        run_heats(league, night, oval, resolve_driver)
        (heat_race,) = [row[0] for row in league.query("SELECT id FROM races")]
    app = create_app(start="league")
    async with app.run_test(size=(120, 40)) as pilot:
        notes = Notifications(app)
        await the_nights_screen(pilot)
        await pilot.press("c")
        await settle(pilot)
        dialog = app.screen
        assert isinstance(dialog, ConfirmDialog)
        assert "only results verified by replay" in " ".join(painted(dialog).split())
        await pilot.press("y")
        await settle(pilot)
        assert "Closed friday; the standings are final." in notes.text()
    with open_league() as league:
        assert list_nights(league)[0].closed
        verdict = league.query_one(
            "SELECT outcome FROM sync_replays WHERE race_id = ?", (heat_race,)
        )
        assert verdict is not None and verdict[0] == "same"  # raced again before closing
        (standing,) = standings(league, list_nights(league)[0])
        assert standing.entry.racer == "ada"  # replayed here: it counts


async def test_a_heat_whose_car_cannot_be_driven_says_what_helps() -> None:
    """The host walk: after a car that could not be driven, the toast said "press r to run
    it again", which failed the same way."""
    import pytest

    from league.errors import LeagueError
    from racer_tui.app.screens.race_screen import RaceScreen
    from sim.garage.options import new_model
    from tests.racer_tui.screens.tui_helpers import trained_model

    data_home().mkdir(parents=True, exist_ok=True)
    broken = trained_model("red-owl")
    with open_league() as league:
        night = new_night(league, resolve_track("beginner-oval"), name="friday")
        add_entrant(league, night, "dan", "red-owl")
        draw_heats(league, night, seed=1)
    broken.policy_file.write_bytes(b"not a policy")  # damaged after it was entered
    app = create_app(start="league")
    async with app.run_test(size=(80, 24)) as pilot:
        notes = Notifications(app)
        nights = await the_nights_screen(pilot)
        await pilot.press("r")
        await wait_for(pilot, lambda: isinstance(app.screen, RaceScreen))
        view = app.screen
        assert isinstance(view, RaceScreen)
        await wait_for(pilot, lambda: view.failure is not None)
        await pilot.press("escape")
        await wait_for(pilot, lambda: app.screen is nights)
        said = notes.text("warning")
        assert "Heat 1 did not race: a car could not be driven" in said
        assert "withdraw its entrant (w)" in said and "press r to run it again" not in said
    # Entering an untrained model is refused at once, in the dialog's words.
    with open_league() as league, pytest.raises(LeagueError, match="no trained policy yet"):
        add_entrant(league, night, "eve", new_model("green-owl").name)


async def test_a_bad_night_or_season_name_is_said_in_its_dialog_with_what_was_typed() -> None:
    """The host walk: a 300-character night name closed the dialog with a toast; a right-to-
    left override was silently dropped from a night's name; after a bad points table the
    cursor went back to the season's (good) name."""
    app = create_app(start="league")
    async with app.run_test(size=(80, 24)) as pilot:
        nights = await the_nights_screen(pilot)
        for typed in ("N" * 300, "Friday\u202eevil"):
            await pilot.press("o")
            await settle(pilot)
            dialog = app.screen
            name = dialog.query_one("#night-name", Input)
            name.value = typed  # as a paste gives it (NameInput keeps typed ones too)
            await pilot.press("ctrl+s")
            await settle(pilot)
            assert app.screen is dialog, typed[:10]
            problem = " ".join(painted(dialog.query_one("#problem")).split())
            assert "cannot be a night name" in problem and "invisible characters" in problem
            assert name.value == typed and dialog.focused is name
            await pilot.press("escape")
            await settle(pilot)
        assert app.screen is nights
        await pilot.press("s")
        await settle(pilot)
        season = app.screen
        season.query_one("#season-name", Input).value = "Spring"
        season.query_one("#season-points", Input).value = "25,abc"
        await pilot.press("ctrl+s")
        await settle(pilot)
        assert season.focused is season.query_one("#season-points", Input)
    with open_league() as league:
        assert list_nights(league) == []
