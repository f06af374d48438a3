"""A mouse-down on a widget being removed is dropped, not a crash (found by the monkey)."""

from __future__ import annotations

import asyncio

from textual import events
from textual.widgets import Static

from racer_tui.app.application import create_app
from racer_tui.app.widgets.footer import RacerFooter


def _mouse_down_at(x: int, y: int) -> events.MouseDown:
    return events.MouseDown(None, x, y, 0, 0, 1, False, False, False, screen_x=x, screen_y=y)


async def test_a_click_on_a_widget_as_it_is_removed_leaves_the_app_running() -> None:
    app = create_app()
    async with app.run_test(size=(80, 24)) as pilot:
        await pilot.pause()
        footer = app.screen.query_one(RacerFooter)
        x, y = footer.region.x + 2, footer.region.y
        footer.remove()  # not awaited: the compositor still maps it, its parent is gone
        await asyncio.sleep(0)
        assert footer.parent is None
        app.screen._forward_event(_mouse_down_at(x, y))  # as the app forwards a click
        await pilot.pause()
        assert app.is_running and app._exception is None
        # A click on what is still there is still a click.
        static = Static("still here")
        await app.screen.mount(static)
        await pilot.pause()
        assert await pilot.click(static)
