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
