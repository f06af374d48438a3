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
