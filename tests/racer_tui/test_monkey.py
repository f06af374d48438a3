"""The monkey, short (issue 42): random keys, bursts, pastes, clicks and resizes against the
real app with fixed seeds never crash it. The long run is `python -m benchmarks.app.monkey`.
A crash found here fails with the actions that led to it; each one fixed has its own test
(tests/racer_tui/test_key_bursts.py)."""

from __future__ import annotations

import pytest

from racer_tui.app.monkey import run_monkey, scratch_home

SEEDS = (1, 2, 3)
ACTIONS = 60  # per seed: the three take about a minute on one free core (5 min at load 7 on 2)
SCREENSHOT_EVERY = 5  # an SVG export is the costliest check


@pytest.mark.parametrize("seed", SEEDS)
async def test_random_input_never_crashes_the_app(seed: int) -> None:
    with scratch_home():
        run = await run_monkey(ACTIONS, seed, screenshot_every=SCREENSHOT_EVERY)
    assert run.actions == ACTIONS
    found = [
        f"after action {crash.action_number}: {crash.error}\n  last actions: "
        + " | ".join(crash.recent_actions[-8:])
        for crash in run.crashes
    ]
    assert not found, "\n".join(found)
    assert len(run.screens) >= 3  # it went places, not only the screen it started on


async def test_a_footer_showing_other_keys_than_its_screen_is_found() -> None:
    from racer_tui.app.application import create_app
    from racer_tui.app.keys_as_delivered import drain
    from racer_tui.app.monkey import InvariantError, stale_footer
    from racer_tui.app.widgets.footer import RacerFooter

    with scratch_home():
        app = create_app(start="garage")
        async with app.run_test(size=(80, 24)) as pilot:
            await drain(pilot)
            assert stale_footer(app) is None  # as drawn: the garage's own keys
            footer = app.screen.query_one(RacerFooter)
            footer._keys = footer._keys[1:]  # as if a key had changed and it had not heard
            found = stale_footer(app)
    assert isinstance(found, InvariantError)
    assert "GarageScreen" in str(found)


async def test_a_click_pilot_cannot_send_is_an_action_not_a_crash() -> None:
    # Seed 405, action 738: Pilot refused a click outside the screen's region before any
    # event reached the app (a screen a moment old has no size yet). That is the harness's
    # limit, not a crash of the app.
    import random

    from racer_tui.app.application import create_app
    from racer_tui.app.monkey import Monkey

    class Clicks(random.Random):
        def choices(self, population, weights=None, **_):  # type: ignore[no-untyped-def, override]
            return ["click"]

        def randrange(self, stop, *_):  # type: ignore[no-untyped-def, override]
            return stop - 1  # the far corner of the size the monkey believes in

    app = create_app(start="garage")
    async with app.run_test(size=(80, 24)) as pilot:
        monkey = Monkey(app, pilot, Clicks(1))
        monkey.size = (200, 60)  # as if a resize had not reached the screen
        kind, said = await monkey.act()
        assert (kind, said) == ("click", "click (199, 59) not sent: the screen was 80x24")
        assert app.is_running and app._exception is None
