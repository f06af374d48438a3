"""The tracks browser and the races section."""

from __future__ import annotations

import shutil
from pathlib import Path
from typing import Any

from textual.pilot import Pilot
from textual.widgets import DataTable, Input, Select

from racer_tui.app.application import create_app
from racer_tui.app.screens.garage import GarageScreen
from racer_tui.app.screens.model_editor import ModelEditorScreen
from racer_tui.app.screens.race_screen import RaceScreen
from racer_tui.app.screens.races import RacesScreen
from racer_tui.app.screens.tracks import TrackImportDialog, TracksScreen
from sim.garage.folder import open_model
from sim.race.rules import DEFAULT_RULES
from sim.tracks.catalog import list_tracks
from tests.racer_tui.screens.tui_helpers import Notifications, painted, settle, trained_model


async def test_tracks_show_facts_the_limit_laps_and_the_reference_lap() -> None:
    app = create_app(start="tracks")
    async with app.run_test(size=(120, 36)) as pilot:
        await settle(pilot)
        screen = app.screen
        assert isinstance(screen, TracksScreen)
        facts = painted(screen.query_one("#track-facts"))
        assert "beginner-oval" in facts and "reference lap:" in facts and "working" not in facts
        assert "limit lap:" in facts and "s flying" in facts  # the fastest the car can go
        await pilot.press("down")
        await settle(pilot)
        assert "hairpin-circuit" in painted(screen.query_one("#track-facts"))
        await pilot.press("r")
        assert isinstance(app.screen, RaceScreen)
        assert app.screen.setup.track.name == "hairpin-circuit"
        assert app.screen.setup.rules == DEFAULT_RULES


async def test_official_tracks_are_grouped_and_found_by_searching() -> None:
    app = create_app(start="tracks")
    async with app.run_test(size=(80, 24)) as pilot:
        await settle(pilot)
        screen = app.screen
        assert isinstance(screen, TracksScreen)
        table = screen.query_one("#tracks", DataTable)
        headings = [str(table.get_row_at(row)[0]) for row in range(table.row_count)]
        assert "Built-in (5)" in headings and "Official 2019 (12)" in headings
        assert "re:Invent 2018" in headings
        await pilot.press("slash", *"expedition")
        await settle(pilot)
        assert [str(table.get_row_at(row)[0]) for row in range(table.row_count)] == [
            "Official 2021 (4)",
            "Expedition Loop",
            "Expedition Super Loop",
            "Expedition Super Loop ↺",
            "Expedition Super Loop ↻",
        ]
        facts = painted(screen.query_one("#track-facts"))
        assert "Expedition Loop" in facts and "red_star_open" in facts
        await pilot.press("enter", "r")
        assert isinstance(app.screen, RaceScreen)
        assert app.screen.setup.track.name == "red_star_open"
        await pilot.press("escape")
        await settle(pilot)
        await pilot.press("slash", *"no such road")
        await settle(pilot)
        assert "No track matches" in painted(screen.query_one("#track-facts"))
        await pilot.press("enter", "r")
        assert app.screen is screen  # nothing chosen, nothing raced
        await pilot.press("escape")
        await settle(pilot)
        assert screen.query_one("#track-search", Input).value == ""
        lappable = [info for info in list_tracks() if info.lappable]
        assert table.row_count > len(lappable)  # every track is back, under its heading


async def test_a_new_model_from_the_tracks_screen_uses_that_track() -> None:
    app = create_app(start="tracks")
    async with app.run_test(size=(120, 36)) as pilot:
        await settle(pilot)
        await pilot.press("down", "down", "n")
        editor = app.screen
        assert isinstance(editor, ModelEditorScreen)
        assert editor.query_one("#track", Select).value == "bowtie-chicane"
        await pilot.press(*"bowtie-one", "ctrl+s")
        await settle(pilot)
        assert isinstance(app.screen, GarageScreen)
        assert app.screen.highlighted_name == "bowtie-one"
    assert open_model("bowtie-one").training_params().world_name == "bowtie-chicane"


async def test_races_list_trained_models_and_rank_the_session() -> None:
    trained_model("ada", track="beginner-oval")
    app = create_app(start="races")
    async with app.run_test(size=(120, 36)) as pilot:
        await settle(pilot)
        races = app.screen
        assert isinstance(races, RacesScreen)
        assert [d.label for d in races.drivers] == ["reference driver", "ada"]
        races.query_one("#race-window", Select).value = 60.0
        races.query_one("#race-track", Select).value = "beginner-oval"
        await pilot.pause()
        await pilot.press("s")  # the reference driver, on ada's track
        race = app.screen
        assert isinstance(race, RaceScreen)
        assert race.setup.rules.window_seconds == 60.0
        await settle(pilot)
        await pilot.press("escape")
        assert race.result is not None
        await pilot.press("down")  # ada, on her own track
        await pilot.pause()
        assert races.query_one("#race-track", Select).value == "beginner-oval"
        await pilot.press("s")
        second = app.screen
        assert isinstance(second, RaceScreen)
        # The reference driver's best lap on this track comes along as the ghost to beat.
        assert second.setup.ghost is not None
        assert second.setup.leader_seconds == race.result.score
        await settle(pilot)
        await pilot.press("escape")
        table = races.query_one("#race-results", DataTable)
        assert table.row_count == 2
        # Best first, in the league's order: the reference driver laps; an untrained policy
        # does not.
        assert table.get_row_at(0)[1].plain == "reference driver"
        await pilot.press("p")
        replay = app.screen
        assert isinstance(replay, RaceScreen)
        assert replay.setup.replay is not None


def unwrapped(text: str) -> str:
    """Painted text without its white space: a long path wraps anywhere."""
    return "".join(text.split())


async def test_a_track_file_is_imported_from_the_tracks_screen(
    tmp_path: Path, deepracer_dir: Path
) -> None:
    """A replay or a night on a track this machine lacks says to import it: the Tracks
    screen does that itself (i), so nobody needs the command line for it. A file that
    cannot be used or a name that is taken is said in the dialog, with the path kept."""
    file = tmp_path / "club_oval.npy"
    shutil.copy(deepracer_dir / "tracks" / "Oval_track.npy", file)
    broken = tmp_path / "broken.npy"
    broken.write_bytes(b"not a track at all")
    app = create_app(start="tracks")
    notes = Notifications(app)
    async with app.run_test(size=(80, 24)) as pilot:
        await settle(pilot)
        screen = app.screen
        assert isinstance(screen, TracksScreen)
        await pilot.press("i")
        dialog = app.screen
        assert isinstance(dialog, TrackImportDialog)
        dialog.query_one("#path", Input).value = str(broken)
        await pilot.press("enter")
        await settle(pilot)
        assert app.screen is dialog  # still open, the path still there to correct
        problem = unwrapped(painted(dialog.query_one("#problem")))
        assert "broken.npy:isnotaNumPy.npyfile" in problem
        assert "Traceback" not in notes.text()
        await pilot.press("escape")
        await pilot.press("slash", *"bowtie", "enter")  # a search is on when it lands
        await settle(pilot)
        await pilot.press("i")
        app.screen.query_one("#path", Input).value = str(file)
        await pilot.press("enter")
        await settle(pilot)
        assert "club_oval" in [info.name for info in list_tracks()]
        assert screen.track is not None and screen.track.name == "club_oval"
        assert "club_oval" in painted(screen.query_one("#track-facts"))
        assert screen.query_one("#track-search", Input).value == ""
        # The same file again: the name is taken. The dialog says so in the app's words
        # (no --name: that is the command line's) and takes another name.
        await pilot.press("i")
        dialog = app.screen
        assert isinstance(dialog, TrackImportDialog)
        dialog.query_one("#path", Input).value = str(file)
        await pilot.press("enter")
        await settle(pilot)
        assert app.screen is dialog
        problem = unwrapped(painted(dialog.query_one("#problem")))
        assert "isalreadyimported;chooseanothername." in problem
        assert "--name" not in problem
        dialog.query_one("#name", Input).value = "club_oval_2"
        await pilot.press("enter")
        await settle(pilot)
        assert app.screen is screen
        assert {"club_oval", "club_oval_2"} <= {info.name for info in list_tracks()}
        assert screen.track is not None and screen.track.name == "club_oval_2"


async def _start_a_minute_race(pilot: Pilot[Any], race_type: str) -> RaceScreen:
    """From the Races screen, start a one-minute race of `race_type` (its Select value)."""
    await settle(pilot)
    races = pilot.app.screen
    assert isinstance(races, RacesScreen)
    races.query_one("#race-type", Select).value = race_type
    races.query_one("#race-window", Select).value = 60.0
    await pilot.pause()
    await pilot.press("s")
    race = pilot.app.screen
    assert isinstance(race, RaceScreen)
    return race


async def test_a_race_among_boxes_is_chosen_in_the_races_screen_and_drawn() -> None:
    from racer_tui.app.widgets.race_map import RaceMap
    from sim.physics.objects.settings import RaceType

    app = create_app(start="races")
    async with app.run_test(size=(80, 24)) as pilot:
        race = await _start_a_minute_race(pilot, "object-avoidance")
        assert race.setup.rules.race_type is RaceType.OBJECT_AVOIDANCE
        assert race.setup.rules.window_seconds == 60.0
        await settle(pilot)
        # The three boxes stand on the map beside the car.
        assert painted(race.query_one(RaceMap)).count("■") >= 2
        await pilot.press("escape")
        assert race.result is not None and race.result.valid_laps > 0


async def test_a_head_to_bot_race_draws_its_bot_cars_pointing_where_they_drive() -> None:
    from racer_tui.app.widgets.race_map import RaceMap
    from sim.physics.objects.settings import RaceType

    app = create_app(start="races")
    async with app.run_test(size=(80, 24)) as pilot:
        race = await _start_a_minute_race(pilot, "head-to-bot")
        assert race.setup.rules.race_type is RaceType.HEAD_TO_BOT
        await settle(pilot)
        drawn = painted(race.query_one(RaceMap))
        # Bot cars are not boxes: each a triangle pointing its way round the track.
        assert sum(drawn.count(glyph) for glyph in "▸◥▴◤◂◣▾◢") >= 2
        assert "■" not in drawn
        await pilot.press("escape")
