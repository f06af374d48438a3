"""Head-to-head in the app: chosen on the Races screen (race type, then who races), drawn
live with every car in its colour, the running order with gaps, crashes and overtakes as
they happen, and played again once it is over."""

from __future__ import annotations

from dataclasses import replace
from typing import Any

import pytest
from textual.pilot import Pilot
from textual.widgets import Select, SelectionList, Static

from racer_tui.app.application import create_app
from racer_tui.app.screens.head_to_head_dialog import HeadToHeadDialog
from racer_tui.app.screens.head_to_head_screen import (
    CAR_COLOURS,
    HELD_WORDS,
    HeadToHeadScreen,
    HeadToHeadSetup,
    car_labels,
    gap_text,
    standings_text,
)
from racer_tui.app.screens.races import RacesScreen
from racer_tui.app.widgets.race_map import RaceMap
from sim.race.driver import reference_driver
from sim.race.head_to_head import Entry
from sim.race.head_to_head_ticks import head_to_head_ticks
from sim.race.rules import HEAD_TO_HEAD_RULES
from sim.tracks.catalog import resolve_track
from tests.racer_tui.screens.tui_helpers import (
    Notifications,
    painted,
    settle,
    trained_model,
    wait_for,
)


async def _choose_head_to_head(pilot: Pilot[Any]) -> HeadToHeadDialog:
    await settle(pilot)
    races = pilot.app.screen
    assert isinstance(races, RacesScreen)
    races.query_one("#race-type", Select).value = "head-to-head"
    races.query_one("#race-track", Select).value = "reinvent_base"
    await pilot.pause()
    await pilot.press("s")
    dialog = pilot.app.screen
    assert isinstance(dialog, HeadToHeadDialog)
    return dialog


async def test_a_head_to_head_is_chosen_on_the_races_screen_and_raced_live() -> None:
    trained_model("ada", track="reinvent_base")
    app = create_app(start="races")
    async with app.run_test(size=(80, 24)) as pilot:
        dialog = await _choose_head_to_head(pilot)
        # The highlighted driver (the reference driver) is chosen already; one is too few.
        assert dialog.query_one(SelectionList).selected == [0]
        await pilot.press("enter")
        problem = str(dialog.query_one("#problem", Static).render())
        assert "Choose 2 to 6 drivers with space (1 chosen)." in problem
        assert app.screen is dialog
        # Chosen and not chosen are told apart without colour: a tick or an empty box.
        listed = painted(dialog.query_one(SelectionList))
        assert "✓▌ reference driver" in listed and "▐ ▌ ada" in listed
        await pilot.press("down", "space")  # ada, second on the grid
        assert "✓▌ ada" in painted(dialog.query_one(SelectionList))
        dialog.query_one("#h2h-laps", Select).value = 1
        await pilot.press("enter")
        view = app.screen
        assert isinstance(view, HeadToHeadScreen)
        assert view.setup.names == ("reference driver", "ada")
        assert view.setup.rules.lap_count == 1
        assert view.setup.rules.race_type is HEAD_TO_HEAD_RULES.race_type
        await wait_for(pilot, lambda: len(view.ticks) > 30 and view.frames > 3)
        # Both cars on the map, each in its own colour; the order with both names.
        map_widget = view.query_one(RaceMap)
        drawn = painted(map_widget)
        assert sum(drawn.count(arrow) for arrow in "→↗↑↖←↙↓↘") >= 1
        order = painted(view.query_one("#h2h-order"))
        assert "#1 reference driver" in order and "#2 ada" in order
        await pilot.press("e")  # to the end
        await wait_for(pilot, lambda: view.at_end)
        # The panel redraws at its own pace: until it shows the finish.
        await wait_for(pilot, lambda: "won." in painted(view.query_one("#h2h-facts")))
        facts = painted(view.query_one("#h2h-facts"))
        assert "#1 reference driver won." in facts  # an untrained policy does not lap
        assert "r replays, Esc goes back." in facts
        await pilot.press("r")
        await pilot.pause()
        assert not view.at_end and view.incidents == []
        await pilot.press("escape")
        # The app may hold a key until the screen it is for is ready (a loaded machine).
        await wait_for(pilot, lambda: isinstance(app.screen, RacesScreen))
        await wait_for(pilot, lambda: not view.is_attached)
        # Let go as the view is removed, not with its reference cycle in a full collection.
        assert view.ticks == [] and view.result is not None


def test_the_standings_give_each_car_its_colour_lap_and_gap() -> None:
    track = resolve_track("reinvent_base")
    driver = reference_driver(track)
    rules = replace(HEAD_TO_HEAD_RULES, lap_count=1)
    ticks = list(head_to_head_ticks(track, rules, [Entry("a", driver), Entry("b", driver)]))
    labels = car_labels(["reference", "reference"])
    assert labels == ["#1 reference", "#2 reference"]
    mid = ticks[len(ticks) // 2]
    text = standings_text(mid, labels, 34)
    lines = text.plain.split("\n")
    assert len(lines) == 2 and all(len(line) <= 34 for line in lines)
    leader, second = mid.order
    assert lines[0].startswith(f"1 ■ {labels[leader]}")
    leading = mid.cars[leader]
    assert lines[0].endswith(HELD_WORDS[leading.held_for] if leading.held > 0 else "lead")
    gap = mid.gaps[second]
    if mid.cars[second].held > 0:
        assert lines[1].endswith(HELD_WORDS[mid.cars[second].held_for])
    else:
        assert lines[1].endswith(gap_text(gap))
    # Each car's square is in its grid colour.
    squares = [span.style for span in text.spans if "bold" in str(span.style)]
    assert f"bold {CAR_COLOURS[leader]}" in squares and f"bold {CAR_COLOURS[second]}" in squares
    # At the end every car has its gap, held or not, and the winner its tick.
    last = ticks[-1]
    assert last.result is not None
    end = standings_text(last, labels, 34).plain.split("\n")
    runner_up = last.result.cars[1]
    assert end[0].endswith("✓") and end[1].endswith(gap_text(runner_up.gap_seconds))
    # A gap of 100 s or more keeps a space before it (it ran into the lap).
    assert gap_text(198.46) == "+198" and gap_text(12.34) == "+12.3" and gap_text(None) == "-"
    # A long name is cut so the lap and the gap keep their place.
    long = standings_text(mid, ["#1 " + "x" * 60, "#2 " + "y" * 60], 30).plain.split("\n")
    assert all(len(line) <= 30 and "…" in line for line in long)


def _broken() -> list[Entry]:
    raise ValueError("this model's policy file is damaged; train it again")


@pytest.mark.parametrize("size", [(80, 24), (60, 20)])
async def test_the_view_fits_80x24_and_60x20_and_says_a_failed_race(size: tuple[int, int]) -> None:
    setup = HeadToHeadSetup(
        track=resolve_track("reinvent_base"),
        rules=HEAD_TO_HEAD_RULES,
        names=("a racer with a rather long name", "b"),
        entries=_broken,
    )
    app = create_app(start="races")
    async with app.run_test(size=size) as pilot:
        await settle(pilot)
        notes = Notifications(app)
        view = HeadToHeadScreen(setup)
        await app.push_screen(view)
        await wait_for(pilot, lambda: view.failure is not None)
        await wait_for(pilot, lambda: "stopped" in painted(view.query_one("#h2h-facts")))
        facts = "".join(painted(view.query_one("#h2h-facts")).split())
        assert "Theracestopped.Thismodel'spolicyfileisdamaged" in facts
        assert "Escgoesback." in facts
        assert notes.text() == ""
        # The side panel and the map share the width.
        side = view.query_one("#h2h-side")
        assert side.region.right <= size[0] and view.query_one(RaceMap).size.width >= 24
        await pilot.press("escape")
        # The app may hold a key until the screen it is for is ready (a loaded machine).
        await wait_for(pilot, lambda: isinstance(app.screen, RacesScreen))
