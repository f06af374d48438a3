"""SVG snapshot of the Sync screen at 80x24: a saved store, one conflict and one
quarantined record (fixed ids and text; no sync runs, so no times are shown).
Update after a deliberate change with
`pytest tests/racer_tui/snapshots/test_sync_snapshots.py --snapshot-update`."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from textual.pilot import Pilot

from league.opening import open_league
from league.races import record_race
from league.sync import local
from league.sync.record import Quarantined
from league.sync.session import save_store
from racer_tui.app.application import create_app
from sim.foundation.home import data_home
from tests.league.helpers import race_result
from tests.racer_tui.screens.tui_helpers import settle
from tests.racer_tui.snapshots.sizes import SIZES

Compare = Callable[..., bool]
STORE = "dir:/media/league-share"


def league_with_problems() -> None:
    data_home().mkdir(parents=True, exist_ok=True)
    with open_league() as league:
        record_race(league, race_result("ada", [12.0, 11.5], model="ada-car"))
        save_store(league, STORE)
        with league.transaction():
            local.add_conflict(
                league,
                STORE,
                "racer",
                "01J0000000000000000000RACR",
                "racer differs",
                local=("1f" * 32, 0, '{"name":"bob"}'),
                remote=("e7" * 32, 0, '{"name":"[bold red]bob"}'),
            )
            local.add_quarantined(
                league,
                STORE,
                Quarantined(
                    reason="it is not valid JSON",
                    where="records/racer/Z/01M7YFZPX152TMAJ036HERQMZZ.json",
                    excerpt='{"name": "[i]x", "oops"',
                ),
                "racer",
                "01M7YFZPX152TMAJ036HERQMZZ",
            )


@SIZES
def test_sync_screen(snap_compare: Compare, size: tuple[int, int]) -> None:
    league_with_problems()

    async def open_sync(pilot: Pilot[Any]) -> None:
        await settle(pilot)
        await pilot.press("y")
        await settle(pilot)

    app = create_app(start="league")
    assert snap_compare(app, terminal_size=size, run_before=open_sync)
