"""The race screen runs a time trial in a worker and plays it back with its laps table."""

from __future__ import annotations

import dataclasses
from collections.abc import Iterator
from functools import partial

import pytest
from textual.app import App
from textual.pilot import Pilot
from textual.widgets import DataTable, Static

from racer_tui.app.jobs import JobState
from racer_tui.app.screens.race_screen import (
    LEAVE,
    RaceScreen,
    RaceSetup,
    countdown_text,
    race_job,
)
from racer_tui.text.clocks import clock_text
from sim.garage.options import new_model
from sim.race.engine import RaceTick, run_race
from sim.race.replay import ghost_lap
from sim.race.rules import RaceRules
from sim.tracks.catalog import resolve_track
from sim.training.policy_driver import driver_for_model
from tests.racer_tui.screens.tui_helpers import wait_for

SHORT = RaceRules(window_seconds=20.0)


async def worked_out(pilot: Pilot[None], screen: RaceScreen) -> None:
    """Until the race (or the replay's ticks), started once the screen is drawn, is ready."""
    for _ in range(1000):
        if screen.result is not None or screen.failure is not None:
            return
        await pilot.pause(0.02)
    raise AssertionError("the race was not worked out within 20 s")


def test_clock_formats() -> None:
    assert clock_text(6.6392) == "0:06.639"
    assert clock_text(75.5) == "1:15.500"
    assert countdown_text(240.0) == "4:00"
    assert countdown_text(0.2) == "0:01"
    assert countdown_text(0.0) == "0:00"


async def test_a_live_race_fills_the_laps_table_and_returns_its_result() -> None:
    track = resolve_track("beginner-oval")
    screen = RaceScreen(RaceSetup(track=track, rules=SHORT, racer="[bold]Ada"))
    app: App[None] = App()
    async with app.run_test(size=(100, 30)) as pilot:
        await app.push_screen(screen)
        await worked_out(pilot, screen)
        # Worked out, but played back at 1x: the race is still running as the view shows it.
        assert screen.job.state is JobState.RUNNING and screen.job.total == 20.0
        assert screen.job.what == "Racing [bold]Ada on beginner-oval"
        await pilot.press("e")
        await pilot.pause()
        result = screen.result
        assert result is not None and result.racer == "[bold]Ada"
        best = result.best_lap
        assert best is not None
        assert screen.job.state is JobState.DONE
        assert screen.job.outcome == f"best lap {clock_text(best.time_seconds)}"
        table = screen.query_one("#laps", DataTable)
        assert table.row_count == len(result.laps) >= 2
        assert table.get_row_at(0)[1] == clock_text(result.laps[0].time_seconds)
        facts = str(screen.query_one("#race-facts", Static).render())
        assert "Finished" in facts
        title = str(screen.query_one("#race-title", Static).render())
        assert "[bold]Ada" in title  # a racer's name is plain text, not markup
        await pilot.press("escape")
        assert app.screen is not screen
        await wait_for(pilot, lambda: not screen.is_attached)
        # Its ticks are let go as it is removed, not with its reference cycle in a full
        # collection (a pause a key could meet); the result stays.
        assert screen.ticks == [] and screen.result is result


async def test_a_recorded_race_replays_with_a_ghost() -> None:
    track = resolve_track("beginner-oval")
    recorded = run_race(track, SHORT, racer="Ada")
    ghost = ghost_lap(recorded)
    assert ghost is not None
    screen = RaceScreen(
        RaceSetup(track=track, rules=SHORT, racer="Ada", replay=recorded, ghost=ghost)
    )
    app: App[None] = App()
    async with app.run_test(size=(80, 24)) as pilot:
        await app.push_screen(screen)
        await worked_out(pilot, screen)
        await pilot.press("e")
        await pilot.pause()
        table = screen.query_one("#laps", DataTable)
        assert table.row_count == len(recorded.laps)
        await pilot.press("r", "space")  # replay from the start, then pause
        await pilot.pause()
        assert screen.paused
        assert screen.race_clock < recorded.laps[0].time_seconds
        assert table.row_count == 0


async def test_a_race_that_cannot_start_says_why_in_the_apps_words() -> None:
    # A night's heat for an entrant whose model lost its weights (retrained from scratch
    # and stopped before the first save, copied without them).
    folder = new_model("ada")
    screen = RaceScreen(
        RaceSetup(
            track=resolve_track("beginner-oval"),
            rules=SHORT,
            racer="Ada",
            driver=partial(driver_for_model, folder),
        )
    )
    app: App[None] = App()
    async with app.run_test(size=(100, 30)) as pilot:
        await app.push_screen(screen)
        await worked_out(pilot, screen)
        assert screen.failure is not None
        assert "Model 'ada' has no trained policy yet" in screen.failure
        assert "press t in the Garage to train it" in screen.failure
        assert "racer-tui" not in screen.failure
        # The race's status says it failed, why, and which key leaves the view.
        assert screen.job.state is JobState.FAILED and screen.job.fix == LEAVE
        await pilot.pause(0.2)  # the panel redraws at 10 Hz
        facts = str(screen.query_one("#race-facts", Static).render())
        assert "Model 'ada' has no trained policy yet" in facts and facts.endswith(LEAVE)


def test_a_replay_is_a_job_of_its_own_from_its_first_tick_to_its_result() -> None:
    track = resolve_track("beginner-oval")
    recorded = run_race(track, SHORT, racer="Ada")
    setup = RaceSetup(track=track, rules=SHORT, racer="Ada", replay=recorded)
    starting = race_job(setup, None, None)
    assert (starting.what, starting.state, starting.done) == (
        "Replaying Ada on beginner-oval",
        JobState.RUNNING,
        0.0,
    )
    assert race_job(setup, None, "This race cannot be replayed.").state is JobState.FAILED


def test_off_tracks_past_the_limit_say_the_lap_is_lost() -> None:
    from sim.race.engine import RaceTick

    screen = RaceScreen(RaceSetup(track=resolve_track("beginner-oval"), rules=SHORT, racer="A"))
    tick = RaceTick(
        step=40, clock=2.7, window_seconds=20.0, x=0.0, y=0.0, heading=0.0, speed=1.0, lap=1,
        lap_time=2.7, progress=30.0, laps=(), lap_offtracks=4, offtrack=False,
        status="in_progress", penalty_remaining=0.0,
    )  # fmt: skip

    facts = str(screen._facts(tick))

    assert "4/3" not in facts
    assert "over 3" in facts and "won't count" in facts
    within = str(screen._facts(dataclasses.replace(tick, lap_offtracks=3)))
    assert "Off-tracks this lap 3/3" in within


async def test_space_says_resume_in_the_footer_while_the_race_is_paused() -> None:
    """Issue 42, point 6: the footer says what space does now."""
    from racer_tui.app.widgets.footer import screen_keys

    track = resolve_track("beginner-oval")
    screen = RaceScreen(RaceSetup(track=track, rules=SHORT, racer="Ada"))
    app: App[None] = App()
    async with app.run_test(size=(100, 30)) as pilot:
        await app.push_screen(screen)
        await worked_out(pilot, screen)

        def space_says() -> list[str]:
            keys, _ = screen_keys(screen)
            return [key.description for key in keys if key.key == "space"]

        assert space_says() == ["Pause"]
        await pilot.press("space")
        assert screen.paused and space_says() == ["Resume"]
        await pilot.press("space")
        assert not screen.paused and space_says() == ["Pause"]


async def test_e_keeps_to_the_end_while_a_slow_machine_still_works_the_race_out(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """Issue 42, point 6: `e` on a loaded machine jumped to the newest tick worked out,
    then played on at 1x (and said so). It now follows the simulation to the finish."""
    import threading

    from racer_tui.app.screens import race_screen
    from sim.race import engine as race_engine

    holding, release = threading.Event(), threading.Event()
    real = race_engine.race_ticks

    def slow_ticks(*args: object, **kwargs: object) -> Iterator[RaceTick]:
        for tick in real(*args, **kwargs):  # type: ignore[arg-type]
            if tick.clock > 3.0:
                holding.set()
                release.wait(30)  # the machine is busy: the rest comes later
            yield tick

    monkeypatch.setattr(race_screen, "race_ticks", slow_ticks)
    screen = RaceScreen(RaceSetup(track=resolve_track("beginner-oval"), rules=SHORT, racer="Ada"))
    app: App[None] = App()
    async with app.run_test(size=(100, 30)) as pilot:
        await app.push_screen(screen)
        for _ in range(500):  # until the first 3 s are worked out and the rest held back
            if holding.is_set():
                break
            await pilot.pause(0.02)
        assert holding.is_set() and screen.ticks[-1].clock <= 3.0
        await pilot.press("e")
        assert screen.playback == "to the end"
        facts = str(screen.query_one("#race-facts", Static).render())
        assert "to the end" in facts and "1x" not in facts
        release.set()
        await worked_out(pilot, screen)
        # Worked out: the 20-second race's finish is on screen at the next frames, not
        # after the rest of it played at 1x.
        for _ in range(50):
            if screen.finish_shown:
                break
            await pilot.pause(0.02)
        assert screen.finish_shown and screen.race_clock >= screen.ticks[-1].clock


async def test_a_race_shown_to_its_end_neither_pauses_nor_says_it_plays() -> None:
    # After e, the finished race said "2x" and its footer "space Pause"; space then paused
    # a race with nothing left to play (a new host's walk).
    from racer_tui.app.widgets.footer import screen_keys

    track = resolve_track("beginner-oval")
    screen = RaceScreen(RaceSetup(track=track, rules=SHORT, racer="Ada"))
    app: App[None] = App()
    async with app.run_test(size=(80, 24)) as pilot:
        await app.push_screen(screen)
        await worked_out(pilot, screen)
        await pilot.press("2", "space")  # paused at 2x, then to the end
        assert screen.paused
        await pilot.press("e")
        await pilot.pause()
        assert screen.at_end and screen.playback == "finished"
        shown = {key.description for key in screen_keys(screen)[0]}
        assert "Pause" not in shown and "Resume" not in shown and "Replay" in shown
        await pilot.press("space")
        assert not screen.paused and screen.playback == "finished"
        await pilot.press("r")  # plays it again: space pauses again
        await pilot.pause()
        assert not screen.at_end
        assert "Pause" in {key.description for key in screen_keys(screen)[0]}
