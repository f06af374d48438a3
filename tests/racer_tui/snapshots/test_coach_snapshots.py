"""SVG snapshot of the Coach view at each size: the reference driver's evaluated lap of
hairpin-circuit against the limit lap, its worst sector chosen. Update after a deliberate
change with `pytest tests/racer_tui/snapshots/test_coach_snapshots.py --snapshot-update`."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from textual.pilot import Pilot

from racer_tui.app.application import create_app
from tests.racer_tui.screens.test_coach import evaluated_model
from tests.racer_tui.screens.tui_helpers import settle
from tests.racer_tui.snapshots.sizes import SIZES

Compare = Callable[..., bool]


async def _coached(pilot: Pilot[Any]) -> None:
    await settle(pilot)
    await pilot.press("o")
    await settle(pilot)


@SIZES
def test_coach_view(snap_compare: Compare, size: tuple[int, int]) -> None:
    evaluated_model("ada")
    app = create_app(start="garage")
    assert snap_compare(app, terminal_size=size, run_before=_coached)
